"""Test setup: the llvm_ad_rgb variant on 2 threads, plugins registered, shared helpers.

The helpers that call a BSDF on NumPy directions live in ``mitsuba_brdfs.validate`` and are
imported here under the names the tests use."""
import drjit as dr
import mitsuba as mi
import pytest

mi.set_variant("llvm_ad_rgb")
dr.set_thread_count(2)
import mitsuba_brdfs  # noqa: E402,F401  (registers the plugins)
from mitsuba_brdfs.validate.directions import random_upper, sph  # noqa: E402,F401
from mitsuba_brdfs.validate.probe import interaction, sample_bsdf, to_np, vec  # noqa: E402,F401


@pytest.fixture(autouse=True)
def _llvm_rgb():
    """Every test starts in llvm_ad_rgb, whatever the previous one switched to."""
    if mi.variant() != "llvm_ad_rgb":
        mi.set_variant("llvm_ad_rgb")
    yield
    if mi.variant() != "llvm_ad_rgb":
        mi.set_variant("llvm_ad_rgb")


def small_scene(bsdf, res=24, integrator="path", max_depth=3):
    """A sphere lit by a point light and a dim environment, seen by a perspective camera."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": integrator, **({"max_depth": max_depth} if integrator == "path" else {})},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 4}},
        "ball": {"type": "sphere", "bsdf": bsdf},
        "light": {"type": "point", "position": [2, 2, 4], "intensity": {"type": "rgb", "value": 30}},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.2}},
    })
