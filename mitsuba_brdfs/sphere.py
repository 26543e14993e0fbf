"""The sphere scene of ``scenes/as_sphere.xml`` with any BSDF: the figures' catalog, the
manual's renders and the benchmarks render every model on it."""
import mitsuba as mi

__all__ = ["sphere_scene"]


def sphere_scene(bsdf, res=256, spp=64, integrator="direct", max_depth=3):
    """The sphere of ``scenes/as_sphere.xml`` (same camera and light) with any BSDF."""
    integ = {"type": integrator}
    if integrator in ("path", "prb"):
        integ["max_depth"] = max_depth
    return mi.load_dict({
        "type": "scene",
        "integrator": integ,
        "sensor": {"type": "perspective", "fov": 24,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 6], target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "sampler": {"type": "independent", "sample_count": spp},
                   "film": {"type": "hdrfilm", "width": res, "height": res,
                            "rfilter": {"type": "gaussian"}}},
        "ball": {"type": "sphere", "bsdf": bsdf,
                 "to_world": mi.ScalarTransform4f().rotate([1, 0, 0], -90)},
        "lamp": {"type": "sphere", "center": [-4, 4, 6], "radius": 0.5,
                 "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 40}}},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.08}},
    })
