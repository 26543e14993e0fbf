"""The ``render`` command: its outputs, formats, options and refusals (passes: test_passes.py, files: test_output.py)."""
import os
import re
import stat
import subprocess

import mitsuba as mi
import numpy as np
import OpenEXR
import pytest

import user_bsdf
from cmdline import run_cli, run_many, scene_xml
from mitsuba_brdfs import output as O
from mitsuba_brdfs import passes as P
from mitsuba_brdfs.variant import load_scene
from mitsuba_brdfs.paths import SCENES

SCENE = os.path.join(SCENES, "as_sphere.xml")


# -- the render command -------------------------------------------------------------------

def _channels(path):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        return sorted(f.channels()), f.header().get("chromaticities")


def _png(path):
    bmp = mi.Bitmap(str(path))
    return bmp.pixel_format(), np.array(bmp).reshape(bmp.height(), bmp.width(), -1)


def _film(path, extra):
    """A tiny scene (``scene_xml``) whose film has ``extra`` parameters."""
    scene_xml(path)
    text = path.read_text().replace('<film type="hdrfilm">', '<film type="hdrfilm">' + extra)
    path.write_text(text)


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
    _film(d / "f32.xml", '<string name="component_format" value="float32"/>')
    _film(d / "pfm.xml", '<string name="file_format" value="pfm"/>')
    # a user's BSDF (as --load runs it), sound and failing inside the render
    user_bsdf.write(d / "grey.py", "usergrey")
    scene_xml(d / "user.xml", bsdf='<bsdf type="usergrey"/>')
    scene_xml(d / "broken.xml", bsdf='<bsdf type="usergrey"><string name="flaw" '
              'value="raise"/></bsdf>')
    cases = {
        "default": ["render", "s.xml"],
        "f32": ["render", "f32.xml", "-o", "f32.exr"],
        "pfm": ["render", "pfm.xml"],
        "to_pfm": ["render", "s.xml", "-o", "to.pfm"],
        "to_hdr": ["render", "s.xml", "-o", "to.hdr"],
        "several": ["render", "s.xml", "two.xml", "-o", "several"],
        "load": ["render", "user.xml", "--load", "grey.py", "-o", "user"],
        "user_broken": ["render", "broken.xml", "--load", "grey.py", "-o", "broken"],
        "wavefront": ["render", "s.xml", "-W", "-O", "1", "-o", "w.exr"],
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
        assert code == (2 if name == "user_broken" else 0), (name, err)
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
    assert np.array_equal(O.read_exr(d / "b.exr"), O.read_exr(d / "s.exr"))


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
    assert np.array_equal(O.read_exr(d / "s1.exr"), O.read_exr(d / "s1b.exr"))
    assert not np.array_equal(O.read_exr(d / "s1.exr"), O.read_exr(d / "s2.exr"))
    assert O.read_exr(d / "two.exr").shape == (4, 6, 3)  # the second sensor's film
    assert O.read_exr(d / "t.exr").mean() > 0.01  # the texture found through -a
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
    img = O.read_exr(str(out) + ".exr")
    assert img.shape == (20, 20, 3) and np.isfinite(img).all() and img.mean() > 0.01
    png = mi.Bitmap(str(out) + ".png")
    assert (png.width(), png.height()) == (20, 20)
    assert sorted(os.listdir(out.parent)) == ["sphere.exr", "sphere.png"]


def test_exr_honours_the_films_component_and_file_format(rendered):
    """float16 by default (Mitsuba's hdrfilm), float32 when the film says so; a film whose
    file_format is pfm writes NAME.pfm; -o .pfm / .hdr pick those formats."""
    d, results = rendered
    for name in ("f32", "pfm", "to_pfm", "to_hdr"):
        assert results[name][0] == 0, results[name][2]
    with OpenEXR.File(str(d / "s.exr"), separate_channels=True) as f:
        assert f.channels()["R"].pixels.dtype == np.float16
    with OpenEXR.File(str(d / "f32.exr"), separate_channels=True) as f:
        assert f.channels()["R"].pixels.dtype == np.float32
    exr = O.read_exr(d / "f32.exr")
    assert np.abs(O.read_exr(d / "s.exr") - exr).max() <= 1e-3 * exr.max()  # half precision
    assert sorted(p.name for p in d.glob("pfm.*")) == ["pfm.pfm", "pfm.png", "pfm.xml"]
    for name, fmt in (("pfm.pfm", mi.Bitmap.FileFormat.PFM), ("to.pfm", mi.Bitmap.FileFormat.PFM),
                      ("to.hdr", mi.Bitmap.FileFormat.RGBE)):
        bmp = mi.Bitmap(str(d / name), fmt)
        img = np.array(bmp).reshape(8, 8, -1)
        assert img.shape[2] == 3 and np.allclose(img, exr, rtol=0.02, atol=1e-3), name
    assert not (d / "to.png").exists() and not (d / "to.exr").exists()


def test_several_scenes_load_and_jit_options(rendered):
    """Several scenes into the folder -o names, each under its own name; --load runs a
    user's plugin file; -W -O 1 (wavefronts, few optimisations) renders the same image."""
    d, results = rendered
    for name in ("several", "load", "wavefront"):
        assert results[name][0] == 0, results[name][2]
    assert sorted(os.listdir(d / "several")) == ["s.exr", "s.png", "two.exr", "two.png"]
    assert O.read_exr(d / "several" / "two.exr").shape == (8, 8, 3)  # its first sensor
    assert np.array_equal(O.read_exr(d / "several" / "s.exr"), O.read_exr(d / "s.exr"))
    user = O.read_exr(d / "user.exr")
    assert user.shape == (8, 8, 3) and user.mean() > 0.01
    assert np.allclose(O.read_exr(d / "w.exr"), O.read_exr(d / "s.exr"), atol=2e-3)


def test_an_error_inside_the_render_shows_its_cause(rendered):
    """A plugin failing inside mi.render: Dr.Jit's message says "(see above)"; the cause is
    shown in its place."""
    code, _, err = rendered[1]["user_broken"]
    assert code == 2 and "ValueError: the user's plugin fails" in err, err
    assert err.strip().splitlines()[-1].startswith("error: ValueError")


def test_S_prints_the_kernels_ir(tmp_path):
    r = run_cli("render", scene_xml(tmp_path / "s.xml"), "-S", "-q", "-o", tmp_path / "s")
    assert r.returncode == 0, r.stderr
    assert "define void @drjit_" in r.stdout


def test_read_only_and_immutable_targets_are_refused_before_rendering(tmp_path):
    """A read-only target (0444; root too, by the mode) and an immutable one (chattr +i,
    where the file system allows it) are refused before rendering: status 2, the file and
    its mode unchanged."""
    s = scene_xml(tmp_path / "s.xml")
    ro = tmp_path / "keep.png"
    ro.write_bytes(b"mine")
    ro.chmod(0o444)
    imm = tmp_path / "imm.exr"
    imm.write_bytes(b"mine")
    immutable = subprocess.run(["chattr", "+i", str(imm)], capture_output=True).returncode == 0
    try:
        cases = [["render", s, "-o", ro], ["render", s, "-o", tmp_path / "keep"]]
        if immutable:
            cases.append(["render", s, "-o", imm])
        for code, out, err in run_many(cases):
            assert code == 2 and "refusing to replace it" in err and "spp" not in err, err
        assert ro.read_bytes() == b"mine" and stat.S_IMODE(ro.stat().st_mode) == 0o444
        if immutable:
            assert "immutable" in err and imm.read_bytes() == b"mine"
        assert sorted(os.listdir(tmp_path)) == ["imm.exr", "keep.png", "s.xml"]
    finally:
        if immutable:
            subprocess.run(["chattr", "-i", str(imm)])



def test_memory_estimate_bounds_what_a_pass_takes(tmp_path):
    """The estimate holds what Dr.Jit allocates at its peak (``malloc_watermark``) in a
    small render, in one megakernel and in wavefronts (-W), and scales with the film."""
    import gc
    import drjit as dr
    scene = load_scene(scene_xml(tmp_path / "s.xml", res=64, spp=4,
                                 integrator='<integrator type="path"/>'))
    for wavefront in (0, 1):
        with dr.scoped_set_flag(dr.JitFlag.SymbolicLoops, not wavefront):
            # the watermark counts every live allocation: free earlier tests' garbage first
            gc.collect()
            dr.sync_thread()
            dr.flush_malloc_cache()
            dr.detail.malloc_clear_statistics()
            P.render_image(scene, 4, progress=False)
            peak = dr.detail.malloc_watermark(dr.JitBackend.LLVM)
        need, per_pass, block = P.memory_estimate(scene, 4, wavefront=wavefront)
        assert per_pass == 64 * 64 * 4 and block == 4
        assert peak <= need - (256 << 20) <= 4 * peak, (wavefront, peak, need)
    big = load_scene(scene_xml(tmp_path / "s.xml", res=20000))
    assert P.memory_estimate(big)[0] > 20000 ** 2 * 100  # > 40 GB: refused by default here
    assert 0 < P.memory_limit() < os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def test_a_bad_scene_after_a_good_one_says_what_was_written(tmp_path):
    """Several scenes render one after the other, as Mitsuba's ``mitsuba`` does: the one
    that is refused is said in one line (exit 2) with the files already written."""
    scene_xml(tmp_path / "good.xml")
    scene_xml(tmp_path / "bad.xml", integrator="")
    (code, out, err), = run_many([["render", "good.xml", "bad.xml", "-q"]], cwd=tmp_path)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert err.startswith("error: bad.xml: the scene has no <integrator>")
    assert err.rstrip().endswith("(after writing good.exr, good.png)"), err
    assert sorted(os.listdir(tmp_path)) == ["bad.xml", "good.exr", "good.png", "good.xml"]
