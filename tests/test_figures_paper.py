"""The paper's figures: every scene renders finite and lit, every figure scene is used."""
import glob
import os
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from mitsuba_brdfs.passes import render_passes
from mitsuba_brdfs.variant import load_scene
from mitsuba_brdfs.figures import command
from mitsuba_brdfs.figures.paper import FIGURES
from mitsuba_brdfs.paths import SCENES

SCENE_FILES = sorted(glob.glob(os.path.join(SCENES, "*.xml")))


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
    scene = load_scene(path, size)
    image, _ = render_passes(scene, 2, progress=False)
    height = size.get("res", size.get("height"))
    assert image.shape[0] == height and image.shape[2] == 3
    assert np.isfinite(image).all()
    assert image.mean() > 1e-3 and (image >= 0).all()


def test_every_figure_scene_exists_and_every_fig_scene_is_used():
    used = {p.scene for f in FIGURES.values() for p in f.panels}
    for name in used:
        assert os.path.exists(os.path.join(SCENES, name)), name
    figs = {os.path.basename(p) for p in SCENE_FILES if os.path.basename(p).startswith("fig")}
    assert figs <= used
    assert command.NAMES[-3:] == ["catalog", "ngan2005", "energy_compensation"]
    assert set(command.NAMES) == set(FIGURES) | {"catalog", "ngan2005", "energy_compensation"}
