"""The renderer: passes, EXR/PNG writing, progress, and the ``render`` command's outputs."""
import itertools
import math
import os
import re

import mitsuba as mi
import numpy as np
import OpenEXR
import pytest

from cmdline import run_cli, run_many, scene_xml
from mitsuba_brdfs import render as R
from mitsuba_brdfs.paths import SCENES

SCENE = os.path.join(SCENES, "as_sphere.xml")


# -- passes -------------------------------------------------------------------------------

@pytest.mark.parametrize("spp, pixels, budget", [(64, 256 * 256, 1 << 22), (100, 10_000, 35_000),
                                                 (7, 1_000_000, 10), (1, 16, 1 << 22)])
def test_pass_sizes_cover_spp_within_budget(spp, pixels, budget):
    sizes = R.pass_sizes(spp, pixels, budget)
    assert sum(sizes) == spp
    assert min(sizes) >= 1 and max(sizes) - min(sizes) <= 1
    assert max(sizes) * pixels <= max(budget, pixels)  # one spp per pass at least


def test_passes_are_made_one_at_a_time():
    """1e11 spp in passes of 1 spp: the first passes come at once, no list is built."""
    for count in (None, lambda n: n):
        gen = R.passes(10 ** 11, 256 * 256, 256 * 256, count)
        assert list(itertools.islice(gen, 3)) == [1, 1, 1]
    # a pass never exceeds Mitsuba's 32-bit sample count
    sizes = list(R.passes(10 ** 11, 1, 10 ** 12))
    assert max(sizes) <= 2 ** 32 - 1 and sum(sizes) == 10 ** 11 and len(sizes) == 24


def _square(n):  # what stratified does with a sample count
    return math.ceil(math.sqrt(n)) ** 2


@pytest.mark.parametrize("spp, per, count, want", [
    (16, 5, _square, [4, 4, 4, 4]),      # the largest square that fits each pass
    (100, 7, _square, None),
    (25, 5, lambda n: max(4, _square(n)), [4] * 7),  # no count fits the last 1: rounded up
])
def test_passes_of_a_rounding_sampler(spp, per, count, want):
    sizes = list(R.passes(spp, 64, 64 * per, count))
    assert all(count(n) == n for n in sizes)  # each pass a count the sampler takes as it is
    assert all(n <= per for n in sizes) or want is not None
    if want is None:
        assert sum(sizes) == spp
    else:
        assert sizes == want


def test_stratified_counts_the_samples_it_takes(tmp_path, monkeypatch):
    """stratified rounds 10 spp up to 16 (as mi.render would); in passes of at most 5 spp,
    it takes 4 passes of 4, and the image is weighted by those."""
    scene = mi.load_file(scene_xml(tmp_path / "s.xml", sampler="stratified", spp=4))
    calls, real = [], mi.render

    def counting(*a, **kw):
        calls.append(kw["spp"])
        return real(*a, **kw)

    monkeypatch.setattr(mi, "render", counting)
    r = R.render_image(scene, 10, pass_samples=64 * 5, progress=False)
    assert calls == [4, 4, 4, 4] and r.spp == 16 and r.passes == 4
    calls.clear()
    r = R.render_image(scene, 10, progress=False)
    assert calls == [16] and r.spp == 16 and r.passes == 1
    assert scene.sensors()[0].sampler().sample_count() == 16  # as Mitsuba leaves it


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


def test_pass_seeds():
    assert R.pass_seed(7, 0) == 7  # one pass: mi.render(scene, seed=7)
    seeds = [R.pass_seed(7, i) for i in range(1, 2000)]
    assert len(set(seeds)) == len(seeds) and all(0 <= s < 2 ** 32 for s in seeds)
    # renders with neighbouring seeds share no pass
    assert not set(seeds) & {R.pass_seed(8, i) for i in range(2000)}
    assert R.pass_seed(2 ** 32 - 1, 5) < 2 ** 32


# -- progress -----------------------------------------------------------------------------

def test_progress_shows_time_as_hms(capsys):
    bar = R.progress_bar(10 ** 11, "x", "spp")
    bar.update(10 ** 6)
    bar.start_t -= 3600  # an hour spent on 1e6 of 1e11 samples
    text = str(bar)
    bar.close()
    assert "1:00:00 spent" in text
    eta = re.search(r"ETA (\d+):(\d\d):(\d\d)", text)
    hours = int(eta.group(1)) + int(eta.group(2)) / 60
    assert abs(hours - (10 ** 11 - 10 ** 6) / 10 ** 6) < 0.02 * hours
    assert R._hms(59.6) == "0:01:00" and R._hms(3 * 3600 + 62) == "3:01:02"


# -- files --------------------------------------------------------------------------------

def test_exr_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    img = (rng.random((7, 11, 3)) * 50).astype(np.float32)
    img[0, 0] = [1e-8, 65504.0 * 4, 0.0]
    path = tmp_path / "x.exr"
    R.write_exr(path, img)
    back, names = R.read_exr(path, names=True)
    assert back.dtype == np.float32 and back.shape == img.shape and names == ["R", "G", "B"]
    assert np.array_equal(back, img)
    assert os.listdir(tmp_path) == ["x.exr"]  # no temporary left behind


def test_exr_keeps_channel_names(tmp_path):
    img = np.arange(4 * 3 * 5, dtype=np.float32).reshape(4, 3, 5)
    names = ["R", "G", "B", "depth.T", "albedo.R"]
    R.write_exr(tmp_path / "a.exr", img, names)
    with OpenEXR.File(str(tmp_path / "a.exr"), separate_channels=True) as f:
        ch = {k: v.pixels for k, v in f.channels().items()}
    assert sorted(ch) == sorted(names)
    for i, n in enumerate(names):
        assert np.array_equal(ch[n], img[..., i])


def test_tonemap_is_srgb():
    x = np.array([[[0.0, 1.0, 0.5], [2.0, -1.0, 0.0031308]]])
    t = R.tonemap(x)
    assert t.dtype == np.uint8
    assert t[0, 0].tolist() == [0, 255, 188] and t[0, 1].tolist() == [255, 0, 10]


def test_failed_write_leaves_nothing(tmp_path, monkeypatch):
    path = tmp_path / "y.exr"
    R.write_exr(path, np.ones((2, 2, 3), np.float32))
    before = path.read_bytes()

    def boom(header, pixels, tmp):
        with open(tmp, "wb") as f:
            f.write(b"half")
        raise KeyboardInterrupt

    monkeypatch.setattr(R, "_write_openexr", boom)
    with pytest.raises(KeyboardInterrupt):
        R.write_exr(path, np.zeros((2, 2, 3), np.float32))
    assert path.read_bytes() == before and os.listdir(tmp_path) == ["y.exr"]


def test_exr_reads_back_through_openexr(tmp_path):
    rng = np.random.default_rng(1)
    img = (rng.random((5, 9, 3)) * 10).astype(np.float32)
    img[2, 3] = [0.0, 1e-6, 3e4]
    R.write_exr(tmp_path / "a.exr", img)
    with OpenEXR.File(str(tmp_path / "a.exr"), separate_channels=True) as f:
        ch = f.channels()
        back = np.stack([ch[c].pixels for c in "RGB"], axis=-1)
    assert back.dtype == np.float32 and np.array_equal(back, img)


# -- the render command -------------------------------------------------------------------

def _channels(path):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        return sorted(f.channels()), f.header().get("chromaticities")


def _png(path):
    bmp = mi.Bitmap(str(path))
    return bmp.pixel_format(), np.array(bmp).reshape(bmp.height(), bmp.width(), -1)


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """One process runs every render of the tests below (tiny scenes, 8x8, 2 spp)."""
    d = tmp_path_factory.mktemp("cli")
    scene_xml(d / "s.xml")
    scene_xml(d / "two.xml", sensors=((8, 8), (6, 4)))
    scene_xml(d / "strat.xml", sampler="stratified", spp=4)
    for fmt in ("luminance", "xyz", "rgba"):
        scene_xml(d / f"{fmt}.xml", pixel_format=fmt)
    scene_xml(d / "aov.xml", integrator='<integrator type="aov"><string name="aovs" '
              'value="dd.y:depth,nn:sh_normal"/><integrator type="direct"/></integrator>')
    (d / "assets").mkdir()
    mi.Bitmap(np.full((2, 2, 3), 0.5, np.float32)).write(str(d / "assets" / "tex.exr"))
    scene_xml(d / "textured.xml", bsdf='<bsdf type="diffuse"><texture type="bitmap" '
              'name="reflectance"><string name="filename" value="tex.exr"/></texture></bsdf>')
    cases = {
        "default": ["render", "s.xml"],
        "exr": ["render", "s.xml", "-o", "a.exr"],
        "png": ["render", "s.xml", "-o", "b.png", "--exposure", "1"],
        "png0": ["render", "s.xml", "-o", "e.png", "--no-exr"],
        "jpg": ["render", "s.xml", "-o", "c.jpg", "--no-exr"],
        "noext": ["render", "s.xml", "-o", os.path.join("sub", "d"), "-t", "1"],
        "seed1": ["render", "s.xml", "-o", "s1.exr", "--seed", "1", "-q"],
        "seed1b": ["render", "s.xml", "-o", "s1b.exr", "--seed", "1", "-q"],
        "seed2": ["render", "s.xml", "-o", "s2.exr", "--seed", "2", "-q"],
        "sensor": ["render", "two.xml", "-s", "1", "-o", "two.exr"],
        "paths": ["render", "textured.xml", "-a", "assets", "-o", "t.exr"],
        "strat": ["render", "strat.xml", "--spp", "10", "--pass-samples", "320", "-o", "st.exr"],
        "luminance": ["render", "luminance.xml", "-o", "lum"],
        "xyz": ["render", "xyz.xml", "-o", "xyz"],
        "rgb": ["render", "s.xml", "-o", "rgb"],
        "rgba": ["render", "rgba.xml", "-o", "rgba.exr"],
        "aov": ["render", "aov.xml", "-o", "aov"],
        "mono": ["render", "s.xml", "-m", "llvm_ad_mono", "-o", "mono"],
    }
    results = dict(zip(cases, run_many(list(cases.values()), cwd=d)))
    return d, results


def test_every_render_succeeds_and_leaves_no_temporary(rendered):
    d, results = rendered
    for name, (code, out, err) in results.items():
        assert code == 0, (name, err)
    for root, _, files in os.walk(d):
        assert not [f for f in files if f.startswith(".partial-")], root


def test_output_extension_picks_the_formats(rendered):
    d, results = rendered
    assert (d / "s.exr").exists() and (d / "s.png").exists()  # the scene's name, here
    assert (d / "a.exr").exists() and not (d / "a.png").exists()
    assert (d / "b.png").exists() and (d / "b.exr").exists()  # the HDR image is kept
    assert (d / "e.png").exists() and not (d / "e.exr").exists()  # unless --no-exr
    assert (d / "c.jpg").exists() and not (d / "c.exr").exists()
    assert sorted(os.listdir(d / "sub")) == ["d.exr", "d.png"]
    assert "wrote b.exr and b.png" in results["png"][1]
    assert _png(d / "c.jpg")[1].shape == (8, 8, 3)
    # --exposure 1 brightens the PNG, not the EXR
    assert _png(d / "b.png")[1].mean() > _png(d / "e.png")[1].mean() + 10
    assert np.array_equal(R.read_exr(d / "b.exr"), R.read_exr(d / "s.exr"))


def test_summary_reports_loading_compiling_rendering_writing(rendered):
    out = rendered[1]["default"][1]
    m = re.search(r"([\d.]+) s in all = ([\d.]+) s loading \+ ([\d.]+) s compiling \+ "
                  r"([\d.]+) s rendering \+ ([\d.]+) s writing", out)
    assert m, out
    total, parts = float(m.group(1)), [float(x) for x in m.groups()[1:]]
    assert parts[0] > 0 and abs(sum(parts) - total) < 0.05 + 0.05 * total
    assert rendered[1]["seed1"][1] == ""  # -q: nothing but errors


def test_seed_sensor_paths_and_rounded_spp(rendered):
    d, results = rendered
    assert np.array_equal(R.read_exr(d / "s1.exr"), R.read_exr(d / "s1b.exr"))
    assert not np.array_equal(R.read_exr(d / "s1.exr"), R.read_exr(d / "s2.exr"))
    assert R.read_exr(d / "two.exr").shape == (4, 6, 3)  # the second sensor's film
    assert R.read_exr(d / "t.exr").mean() > 0.01  # the texture found through -a
    assert "16 spp in 4 pass(es)" in results["strat"][1]  # stratified: 10 -> 16 = 4 x 4
    assert "rounds --spp 10 up: 16 spp rendered" in results["strat"][2]


def test_films_keep_their_format_and_channels(rendered):
    d, _ = rendered
    assert _channels(d / "lum.exr") == (["Y"], None)
    assert _png(d / "lum.png")[0] == mi.Bitmap.PixelFormat.Y
    names, chroma = _channels(d / "xyz.exr")
    assert names == ["X", "Y", "Z"] and chroma[:6] == (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
    # XYZ converted to sRGB for the PNG: the grey sky looks as in the RGB render
    assert np.abs(_png(d / "xyz.png")[1].astype(int) - _png(d / "rgb.png")[1]).max() <= 2
    assert _channels(d / "rgba.exr")[0] == ["A", "B", "G", "R"]
    aov = _channels(d / "aov.exr")[0]
    assert {"R", "G", "B", "dd.y.T", "nn.X", "nn.Y", "nn.Z"} <= set(aov)
    assert not [n for n in aov if re.fullmatch(r"C\d+", n)]
    assert _channels(d / "mono.exr")[0] == ["Y"]
    fmt, png = _png(d / "mono.png")
    assert fmt == mi.Bitmap.PixelFormat.Y and png.shape == (8, 8, 1) and png.mean() > 10


def test_cli_renders_a_plugin_scene(tmp_path):
    """As a user does: the package's sphere, a progress bar with the ETA as h:mm:ss, two
    passes, EXR and PNG."""
    out = tmp_path / "sub" / "sphere"
    r = run_cli("render", SCENE, "-o", out, "--spp", "4", "-D", "res=20", "-D", "nu=5",
                "--pass-samples", "800")
    assert r.returncode == 0, r.stderr
    assert "100%" in r.stderr and "pass 2" in r.stderr  # progress bar, two passes
    assert re.search(r"\d+:\d\d:\d\d spent, ETA \d+:\d\d:\d\d", r.stderr)
    assert "4 spp in 2 pass(es)" in r.stdout
    img = R.read_exr(str(out) + ".exr")
    assert img.shape == (20, 20, 3) and np.isfinite(img).all() and img.mean() > 0.01
    png = mi.Bitmap(str(out) + ".png")
    assert (png.width(), png.height()) == (20, 20)
    assert sorted(os.listdir(out.parent)) == ["sphere.exr", "sphere.png"]
