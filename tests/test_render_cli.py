"""The command-line renderer: passes, EXR/PNG writing, interruption, the figure command."""
import os
import signal
import subprocess
import sys
import time

import mitsuba as mi
import numpy as np
import pytest

from mitsuba_brdfs import figures as F
from mitsuba_brdfs import render as R
from mitsuba_brdfs.__main__ import main

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "scenes", "as_sphere.xml")


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

    import OpenEXR
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
    assert "100.0%" in r.stderr and "pass 2/2" in r.stderr  # progress bar, two passes
    img = R.read_exr(out)
    assert img.shape == (20, 20, 3) and np.isfinite(img).all() and img.mean() > 0.01
    png = mi.Bitmap(str(out.with_suffix(".png")))
    assert (png.width(), png.height()) == (20, 20)
    assert sorted(os.listdir(out.parent)) == ["sphere.exr", "sphere.png"]


@pytest.mark.parametrize("args, msg", [
    (["render", "missing.xml"], "missing.xml"),
    (["render", SCENE, "-D", "res"], "key=value"),
    (["render", SCENE, "-D", "rs=2", "-D", "res=8", "--spp", "1"], "specular_reflectance"),
])
def test_cli_bad_input_is_reported(tmp_path, args, msg):
    r = run_cli(*args, "-o", str(tmp_path / "z.exr"))
    assert r.returncode == 2 and msg in r.stderr and "Traceback" not in r.stderr
    assert os.listdir(tmp_path) == []


def test_interrupt_exits_130_without_output(tmp_path, monkeypatch):
    out = tmp_path / "i.exr"
    real, calls = mi.render, []

    def interrupted(*a, **kw):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*a, **kw)

    monkeypatch.setattr(mi, "render", interrupted)
    code = main(["render", SCENE, "-o", str(out), "--spp", "4", "-D", "res=16",
                 "--pass-samples", "256"])
    assert code == 130 and len(calls) == 2 and os.listdir(tmp_path) == []


def test_sigint_during_render_leaves_no_files(tmp_path):
    out = tmp_path / "s.exr"
    p = subprocess.Popen([sys.executable, "-m", "mitsuba_brdfs", "render", SCENE, "-o", str(out),
                          "--spp", "100000", "-D", "res=64", "--pass-samples", "40000"],
                         cwd=ROOT, stderr=subprocess.PIPE, text=True)
    # wait for the first progress line (the scene is loaded, passes are running)
    line = p.stderr.readline()
    assert "spp" in line
    time.sleep(1.0)
    p.send_signal(signal.SIGINT)
    err = p.communicate(timeout=120)[1]
    assert p.returncode == 130, err
    assert "interrupted" in err
    assert os.listdir(tmp_path) == []


def test_figure_composition_and_timings(tmp_path):
    fig = F.Figure("tiny", "two tiny panels",
                   [F.Panel("as_sphere.xml", "nu = 5", {"nu": 5}),
                    F.Panel("as_sphere.xml", "nu = 500", {"nu": 500})],
                   spp={"preview": 2}, res={"preview": 16})
    t = F.render_figure(fig, "preview", str(tmp_path))
    assert t["spp"] == 2 and t["panels"] == 2 and t["seconds_render"] > 0
    assert sorted(os.listdir(tmp_path)) == ["tiny.png", "tiny_1.exr", "tiny_2.exr"]
    png = np.array(mi.Bitmap(str(tmp_path / "tiny.png")))
    assert png.shape[1] > 2 * 16 and png.shape[0] > 16  # two tiles side by side, labels below
    a, b = R.read_exr(tmp_path / "tiny_1.exr"), R.read_exr(tmp_path / "tiny_2.exr")
    assert np.isfinite(a).all() and a.mean() > 0.01 and not np.allclose(a, b)


def test_figures_command_writes_timings(tmp_path):
    r = run_cli("figures", "--only", "as_sphere", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    import json
    t = json.loads((tmp_path / "timings.json").read_text())
    assert t["as_sphere"]["spp"] == F.FIGURES["as_sphere"].spp["preview"]
    assert (tmp_path / "as_sphere.png").exists() and (tmp_path / "as_sphere.exr").exists()
