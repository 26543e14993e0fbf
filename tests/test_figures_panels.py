"""Figures made of panels: labels fit, tiles are composed, panels are rendered and written."""
import os

import mitsuba as mi
import numpy as np
from PIL import Image, ImageDraw

from mitsuba_brdfs.output import read_exr, tonemap
from mitsuba_brdfs.variant import load_scene
from mitsuba_brdfs.figures import panels as F
from mitsuba_brdfs.paths import SCENES


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


def test_render_figure_writes_exrs_and_the_composed_png(tmp_path):
    def square_sphere(defines):  # a panel built in Python, as the catalog's
        return load_scene(os.path.join(SCENES, "as_sphere.xml"),
                            {"res": defines["height"], "nu": 5})

    fig = F.Figure("tiny", "Tiny figure: two panels and a title long enough to wrap",
                   [F.Panel(square_sphere, "nu = 5, a label long enough to wrap"),
                    F.Panel("fig4_lambert_vs_as.xml", "wide panel", spp=1)],
                   spp={"preview": 2}, res={"preview": (24, 12)})
    t = F.render_figure(fig, "preview", str(tmp_path))
    assert t["spp"] == [2, 1] and t["resolution"] == [24, 12] and t["panels"] == 2
    assert sorted(os.listdir(tmp_path)) == ["tiny.png", "tiny_1.exr", "tiny_2.exr"]
    a, b = read_exr(tmp_path / "tiny_1.exr"), read_exr(tmp_path / "tiny_2.exr")
    assert a.shape == (12, 12, 3) and b.shape == (12, 24, 3)
    assert np.isfinite(a).all() and np.isfinite(b).all() and a.mean() > 0.01 and b.mean() > 0
    # the PNG is the composition of the tone-mapped EXRs
    png = np.array(Image.open(tmp_path / "tiny.png").convert("RGB"))
    expect = F.compose([tonemap(a), tonemap(b)], [p.label for p in fig.panels],
                       fig.columns, fig.title)
    assert np.array_equal(png, expect)


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
    a, b = read_exr(tmp_path / "tiny_1.exr"), read_exr(tmp_path / "tiny_2.exr")
    assert np.isfinite(a).all() and a.mean() > 0.01 and not np.allclose(a, b)
