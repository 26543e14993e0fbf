"""The figure scenes and the figures command: scenes render, labels fit, EXRs round-trip."""
import glob
import json
import os
import xml.etree.ElementTree as ET

import numpy as np
import OpenEXR
import pytest
from PIL import Image, ImageDraw

from mitsuba_brdfs import catalog as C
from mitsuba_brdfs import figures as F
from mitsuba_brdfs import render as R
from mitsuba_brdfs.__main__ import main

SCENE_FILES = sorted(glob.glob(os.path.join(F.SCENES, "*.xml")))


def tiny_size(path, height=8):
    """Size overrides for a scene: ``res`` or width/height with the scene's aspect."""
    defaults = {d.get("name"): d.get("value") for d in ET.parse(path).getroot().iter("default")}
    if "res" in defaults:
        return {"res": height}
    if "width" in defaults and "height" in defaults:
        aspect = float(defaults["width"]) / float(defaults["height"])
        return {"width": max(1, round(height * aspect)), "height": height}
    return {}


@pytest.mark.parametrize("path", SCENE_FILES, ids=os.path.basename)
def test_scene_renders_finite_and_lit(path):
    size = tiny_size(path)
    scene = R.load_scene(path, size)
    image, _ = R.render_passes(scene, 2, progress=False)
    height = size.get("res", size.get("height"))
    assert image.shape[0] == height and image.shape[2] == 3
    assert np.isfinite(image).all()
    assert image.mean() > 1e-3 and (image >= 0).all()


def test_every_figure_scene_exists_and_every_fig_scene_is_used():
    used = {p.scene for f in F.FIGURES.values() for p in f.panels}
    for name in used:
        assert os.path.exists(os.path.join(F.SCENES, name)), name
    figs = {os.path.basename(p) for p in SCENE_FILES if os.path.basename(p).startswith("fig")}
    assert figs <= used
    assert F.NAMES[-1] == "catalog" and set(F.NAMES) == set(F.FIGURES) | {"catalog"}


def test_scene_integrators_are_cheap():
    """direct where nothing interreflects; a path tracer only where a scene says so."""
    for path in SCENE_FILES:
        props = F.scene_integrator(path)
        assert props["type"] in ("direct", "path"), path
        if props["type"] == "path":
            assert 2 < props["max_depth"] <= 8, path
    assert F.scene_integrator(os.path.join(F.SCENES, "fig6_sampling.xml"),
                              {"max_depth": 4})["max_depth"] == 4


def test_wrap_text_fits_and_keeps_words():
    draw = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    font = F._font(12)
    text = "u along the axis (nu = 10), v around (nv = 100)\nsecond line " + "x" * 60
    lines = F.wrap_text(draw, text, font, 90)
    assert all(draw.textlength(ln, font=font) <= 90 for ln in lines)
    assert len(lines) > 3
    assert "(nu = 10)," in " ".join(lines) and "(nv = 100)" in " ".join(lines)
    assert any(ln.startswith("second") for ln in lines)  # the newline starts a line
    assert "".join(lines).replace(" ", "") == text.replace(" ", "").replace("\n", "")


def test_compose_grows_with_wrapped_labels():
    tiles = [np.full((20, 40, 3), v, np.uint8) for v in (50, 100, 150)]
    short = F.compose(tiles, ["a", "b", "c"], columns=2)
    long_ = F.compose(tiles, ["a", "a much longer label that has to wrap", "c"], columns=2,
                      title="a title longer than the canvas is wide, so it wraps too")
    assert short.shape[1] == long_.shape[1] == 2 * 40 + 3 * 6  # two columns
    assert long_.shape[0] > short.shape[0] + 2 * 14  # extra label and title lines
    # the tiles are placed unchanged
    assert (short[6:26, 6:46] == 50).all() and (short[6:26, 52:92] == 100).all()


def test_exr_reads_back_through_openexr(tmp_path):
    rng = np.random.default_rng(1)
    img = (rng.random((5, 9, 3)) * 10).astype(np.float32)
    img[2, 3] = [0.0, 1e-6, 3e4]
    R.write_exr(tmp_path / "a.exr", img)
    with OpenEXR.File(str(tmp_path / "a.exr"), separate_channels=True) as f:
        ch = f.channels()
        back = np.stack([ch[c].pixels for c in "RGB"], axis=-1)
    assert back.dtype == np.float32 and np.array_equal(back, img)


def test_render_figure_writes_exrs_and_the_composed_png(tmp_path):
    def square_sphere(defines):  # a panel built in Python, as the catalog's
        return R.load_scene(os.path.join(F.SCENES, "as_sphere.xml"),
                            {"res": defines["height"], "nu": 5})

    fig = F.Figure("tiny", "Tiny figure: two panels and a title long enough to wrap",
                   [F.Panel(square_sphere, "nu = 5, a label long enough to wrap"),
                    F.Panel("fig4_lambert_vs_as.xml", "wide panel", spp=1)],
                   spp={"preview": 2}, res={"preview": (24, 12)})
    t = F.render_figure(fig, "preview", str(tmp_path))
    assert t["spp"] == [2, 1] and t["resolution"] == [24, 12] and t["panels"] == 2
    assert sorted(os.listdir(tmp_path)) == ["tiny.png", "tiny_1.exr", "tiny_2.exr"]
    a, b = R.read_exr(tmp_path / "tiny_1.exr"), R.read_exr(tmp_path / "tiny_2.exr")
    assert a.shape == (12, 12, 3) and b.shape == (12, 24, 3)
    assert np.isfinite(a).all() and np.isfinite(b).all() and a.mean() > 0.01 and b.mean() > 0
    # the PNG is the composition of the tone-mapped EXRs
    png = np.array(Image.open(tmp_path / "tiny.png").convert("RGB"))
    expect = F.compose([R.tonemap(a), R.tonemap(b)], [p.label for p in fig.panels],
                       fig.columns, fig.title)
    assert np.array_equal(png, expect)


def test_catalog_skips_unregistered_plugins(tmp_path, capsys):
    entries = [("lambert-like", {"type": "diffuse"}),
               ("missing", {"type": "no_such_model_yet"}),
               ("as", {"type": "ashikhmin_shirley", "nu": 50.0, "nv": 50.0})]
    t = C.render_catalog(out_dir=str(tmp_path), spp=1, res=8, entries=entries)
    out = capsys.readouterr().out
    assert "skipping 'missing'" in out and "no_such_model_yet" in out
    assert t["panels"] == 2 and t["shown"] == ["lambert-like", "as"]
    assert (tmp_path / "catalog.png").exists() and (tmp_path / "catalog_2.exr").exists()
    assert C.render_catalog(out_dir=str(tmp_path), entries=entries[1:2])["panels"] == 0


def test_figures_command_renders_and_writes_timings(tmp_path, monkeypatch, capsys):
    fig = F.Figure("tiny", "tiny", [F.Panel("as_sphere.xml", "a"), F.Panel("as_sphere.xml", "b")],
                   spp={"preview": 1, "final": 2}, res={"preview": 8, "final": 10}, columns=1)
    monkeypatch.setitem(F.FIGURES, "tiny", fig)
    monkeypatch.setattr(F, "NAMES", F.NAMES + ["tiny"])
    assert main(["figures", "--only", "tiny", "--quality", "final", "--out", str(tmp_path)]) == 0
    assert "tiny: " in capsys.readouterr().out
    t = json.loads((tmp_path / "timings.json").read_text())
    assert t["tiny"]["spp"] == 2 and t["tiny"]["resolution"] == 10
    assert t["last_run"]["figures"] == ["tiny"] and t["last_run"]["seconds_total"] > 0
    png = np.array(Image.open(tmp_path / "tiny.png"))
    assert png.shape[1] == 10 + 2 * 6 and png.shape[0] > 2 * 10  # one column, two rows


def test_every_catalog_entry_loads():
    """No catalog entry is skipped: every model, form and option of the catalog loads."""
    notes = []
    assert len(C.available(note=notes.append)) == len(C.CATALOG) and not notes, notes
