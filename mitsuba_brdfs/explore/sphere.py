"""A sphere rendered by Mitsuba with the BSDF under a movable light, refined in passes.

The scene is loaded once per BSDF object (``mi.load_dict``); the light is a directional
emitter whose ``to_world`` is changed through ``mi.traverse``, and the BSDF's parameters
are changed on the BSDF itself, so neither recompiles the rendering kernel. Each pass
renders a few samples per pixel with its own seed, and the passes are averaged: the page
asks for pass 0, 1, 2, ... and shows each mean as it arrives; the mean is kept, so that a
request that needs no new pass (the exposure changed, a sphere added beside it) renders
nothing.

The light is the only one (no environment), so a pass has no noise but the pixels'
anti-aliasing, and the unlit side is black: the film keeps the coverage (alpha), and
``displayed`` lays the tone-mapped sphere over a dark grey (``BACKGROUND``), so that its
outline shows where it is unlit.

The light's direction is given in the camera's frame by two angles: ``theta`` from the
viewing direction and ``phi`` around it (0 = from the right, 90 = from above).
"""
import math

import drjit as dr
import mitsuba as mi
import numpy as np

__all__ = ["Sphere", "light_transform", "displayed", "BACKGROUND"]

RES = 192           #: image side in pixels
PASS_SPP = 4        #: samples per pixel of one pass
PASSES = 8          #: passes the page asks for (32 spp in all)
BACKGROUND = 48     #: 8-bit sRGB grey behind the sphere (#303030)


def light_transform(theta, phi):
    """``to_world`` of a directional emitter lighting from the angles (degrees)."""
    t, p = math.radians(theta), math.radians(phi)
    to_light = [math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)]
    up = [0, 1, 0] if abs(to_light[1]) < 0.99 else [1, 0, 0]
    return mi.ScalarTransform4f().look_at(origin=[0, 0, 0], target=[-c for c in to_light],
                                          up=up)


def _scene(bsdf, res):
    T = mi.ScalarTransform4f
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "direct"},
        "sensor": {"type": "perspective", "fov": 22,
                   "to_world": T().look_at(origin=[0, 0, 6], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": res, "height": res,
                            "pixel_format": "rgba", "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": PASS_SPP}},
        # rotated as in scenes/as_sphere.xml: the surface's u runs horizontally
        "ball": {"type": "sphere", "bsdf": bsdf, "to_world": T().rotate([1, 0, 0], -90)},
        "sun": {"type": "directional", "irradiance": {"type": "rgb", "value": math.pi},
                "to_world": light_transform(45, 135)},
    })


class Sphere:
    """The sphere scene of one BSDF object and the running mean of its passes."""

    def __init__(self, bsdf, res=RES):
        self.bsdf = bsdf
        self.scene = _scene(bsdf, res)
        self.params = mi.traverse(self.scene)
        self.light = (45.0, 135.0)
        self.state, self.sum, self.passes = None, None, 0

    def render_pass(self, index, state, light):
        """The mean image of at least ``index + 1`` passes for ``state`` (anything that
        changes when the BSDF does) under ``light`` = (theta, phi), where one more pass
        gets it there: a new state or light starts again, and one pass (at most) is
        rendered where fewer are there; where as many are (the exposure changed, another
        sphere added, a second page), the mean is given again. Pass k has seed k.
        Returns (linear RGBA image (H, W, 4): the colour and the sphere's coverage,
        passes in it)."""
        if tuple(light) != self.light:
            self.params["sun.to_world"] = light_transform(*light)
            self.params.update()
            self.light = tuple(light)
        key = (state, self.light)
        if key != self.state:
            self.state, self.sum, self.passes = key, None, 0
        if self.passes <= index:
            # evaluated (not symbolic) calls: a symbolic call would trace every BSDF alive
            # in the process, so one that raises (a user's plugin) would break every sphere
            with dr.scoped_set_flag(dr.JitFlag.SymbolicCalls, False):
                img = np.array(mi.render(self.scene, spp=PASS_SPP, seed=self.passes),
                               dtype=np.float64)
            self.sum = img if self.sum is None else self.sum + img
            self.passes += 1
        return self.sum / self.passes, self.passes


def displayed(image, exposure=0.0):
    """The 8-bit sRGB image the page shows of ``render_pass``'s: the sphere tone-mapped
    (``output.tonemap``) over ``BACKGROUND`` by its coverage."""
    from ..output import tonemap
    alpha = np.clip(np.asarray(image, np.float64)[..., 3:4], 0.0, 1.0)
    out = tonemap(image[..., :3], exposure) + (1.0 - alpha) * BACKGROUND
    return np.round(np.clip(out, 0, 255)).astype(np.uint8)
