"""Each figure scene's integrator: cheap, and read from the scene as Mitsuba reads it."""
import glob
import os

from mitsuba_brdfs.scene_xml import scene_integrator
from mitsuba_brdfs.paths import SCENES

SCENE_FILES = sorted(glob.glob(os.path.join(SCENES, "*.xml")))


def test_scene_integrators_are_cheap():
    """direct where nothing interreflects; a path tracer only where a scene says so."""
    for path in SCENE_FILES:
        props = scene_integrator(path)
        assert props["type"] in ("direct", "path"), path
        if props["type"] == "path":
            assert 2 < props["max_depth"] <= 8, path
    assert scene_integrator(os.path.join(SCENES, "fig6_sampling.xml"),
                              {"max_depth": 4})["max_depth"] == 4
