"""The renderer: passes, EXR/PNG writing, the ``render`` command."""
import os
import subprocess
import sys

import mitsuba as mi
import numpy as np
import OpenEXR
import pytest

from mitsuba_brdfs import render as R
from mitsuba_brdfs.scenes import SCENES

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(SCENES, "as_sphere.xml")


@pytest.mark.parametrize("spp, pixels, budget", [(64, 256 * 256, 1 << 22), (100, 10_000, 35_000),
                                                 (7, 1_000_000, 10), (1, 16, 1 << 22)])
def test_pass_sizes_cover_spp_within_budget(spp, pixels, budget):
    sizes = R.pass_sizes(spp, pixels, budget)
    assert sum(sizes) == spp
    assert min(sizes) >= 1 and max(sizes) - min(sizes) <= 1
    assert max(sizes) * pixels <= max(budget, pixels)  # one spp per pass at least


def test_passes_average_to_one_render(monkeypatch):
    scene = R.load_scene(SCENE, {"res": 24})
    calls = []
    real = mi.render

    def counting(*a, **kw):
        calls.append(kw["spp"])
        return real(*a, **kw)

    monkeypatch.setattr(mi, "render", counting)
    img_passes, _ = R.render_passes(scene, 64, pass_samples=24 * 24 * 8, progress=False)
    assert calls == [8] * 8
    calls.clear()
    img_one, _ = R.render_passes(scene, 64, pass_samples=1 << 22, progress=False)
    assert calls == [64]
    assert img_passes.shape == img_one.shape == (24, 24, 3)
    assert np.isfinite(img_passes).all() and img_passes.mean() > 0.01
    # different noise, same expectation
    assert abs(img_passes.mean() - img_one.mean()) < 0.03 * img_one.mean()
    assert not np.allclose(img_passes, img_one)


def test_exr_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    img = (rng.random((7, 11, 3)) * 50).astype(np.float32)
    img[0, 0] = [1e-8, 65504.0 * 4, 0.0]
    path = tmp_path / "x.exr"
    R.write_exr(path, img)
    back = R.read_exr(path)
    assert back.dtype == np.float32 and back.shape == img.shape
    assert np.array_equal(back, img)
    assert os.listdir(tmp_path) == ["x.exr"]  # no temporary left behind


def test_tonemap_is_srgb():
    x = np.array([[[0.0, 1.0, 0.5], [2.0, -1.0, 0.0031308]]])
    t = R.tonemap(x)
    assert t.dtype == np.uint8
    assert t[0, 0].tolist() == [0, 255, 188] and t[0, 1].tolist() == [255, 0, 10]


def test_failed_write_leaves_nothing(tmp_path, monkeypatch):
    path = tmp_path / "y.exr"
    R.write_exr(path, np.ones((2, 2, 3), np.float32))
    before = path.read_bytes()

    def boom(*a, **kw):
        raise KeyboardInterrupt

    monkeypatch.setattr(OpenEXR, "File", boom)
    with pytest.raises(KeyboardInterrupt):
        R.write_exr(path, np.zeros((2, 2, 3), np.float32))
    assert path.read_bytes() == before and os.listdir(tmp_path) == ["y.exr"]


def run_cli(*args, **kw):
    return subprocess.run([sys.executable, "-m", "mitsuba_brdfs", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=300, **kw)


def test_cli_renders_exr_and_png(tmp_path):
    out = tmp_path / "sub" / "sphere.exr"
    r = run_cli("render", SCENE, "-o", str(out), "--spp", "4", "-D", "res=20", "-D", "nu=5",
                "--pass-samples", "800")
    assert r.returncode == 0, r.stderr
    assert "100%" in r.stderr and "pass 2/2" in r.stderr  # progress bar, two passes
    img = R.read_exr(out)
    assert img.shape == (20, 20, 3) and np.isfinite(img).all() and img.mean() > 0.01
    png = mi.Bitmap(str(out.with_suffix(".png")))
    assert (png.width(), png.height()) == (20, 20)
    assert sorted(os.listdir(out.parent)) == ["sphere.exr", "sphere.png"]


def test_exr_reads_back_through_openexr(tmp_path):
    rng = np.random.default_rng(1)
    img = (rng.random((5, 9, 3)) * 10).astype(np.float32)
    img[2, 3] = [0.0, 1e-6, 3e4]
    R.write_exr(tmp_path / "a.exr", img)
    with OpenEXR.File(str(tmp_path / "a.exr"), separate_channels=True) as f:
        ch = f.channels()
        back = np.stack([ch[c].pixels for c in "RGB"], axis=-1)
    assert back.dtype == np.float32 and np.array_equal(back, img)
