"""The sphere scene with any BSDF: that of ``scenes/as_sphere.xml`` by default (the figures'
catalog, the manual's renders and the benchmarks render every model on it), and the
variants of it that the ngan2005 plate and the measured materials' figure use."""
import mitsuba as mi

__all__ = ["sphere_scene"]


def sphere_scene(bsdf, res=256, spp=64, integrator="direct", max_depth=3, eye=(0, 0, 6),
                 fov=24, rotate=True, lamp=((-4, 4, 6), 40), env=0.08):
    """A unit sphere of ``bsdf`` (a dict or a loaded BSDF) seen from ``eye`` (looking at its
    centre, ``fov`` degrees), lit by a spherical area ``lamp`` (centre, radiance) of radius
    0.5 and an environment ``env`` (a constant radiance, or an emitter's dict). The defaults
    are ``scenes/as_sphere.xml``'s camera and light. ``rotate``: turned as in that file, so
    that the surface's u runs horizontally; ``spp``: the sampler's count, or None for
    Mitsuba's default (a render gives its own); ``max_depth`` of the ``path`` and ``prb``
    integrators."""
    integ = {"type": integrator}
    if integrator in ("path", "prb"):
        integ["max_depth"] = max_depth
    T = mi.ScalarTransform4f()
    sensor = {"type": "perspective", "fov": fov,
              "to_world": T.look_at(origin=list(eye), target=[0, 0, 0], up=[0, 1, 0]),
              "film": {"type": "hdrfilm", "width": res, "height": res,
                       "rfilter": {"type": "gaussian"}}}
    if spp is not None:
        sensor["sampler"] = {"type": "independent", "sample_count": spp}
    ball = {"type": "sphere", "bsdf": bsdf}
    if rotate:
        ball["to_world"] = T.rotate([1, 0, 0], -90)
    centre, radiance = lamp
    return mi.load_dict({
        "type": "scene",
        "integrator": integ,
        "sensor": sensor,
        "ball": ball,
        "lamp": {"type": "sphere", "center": list(centre), "radius": 0.5,
                 "emitter": {"type": "area", "radiance": {"type": "rgb", "value": radiance}}},
        "env": env if isinstance(env, dict) else {"type": "constant",
                                                   "radiance": {"type": "rgb", "value": env}},
    })
