"""The ``ngan2005`` figure: measured materials as the five Ngan et al. 2005 fits.

Twelve MERL materials (metals, paints, plastics, fabrics), one row each, rendered with the
``ngan2005`` presets of Ashikhmin-Shirley, Blinn-Phong, Cook-Torrance, Ward and Ward-Duer
side by side, on the same sphere under one area light and one environment (a sky
gradient over a dark ground with a bright horizon band, so that sharp lobes show their
reflection and wide ones their blur).
"""
import numpy as np

from .panels import Figure, Panel

__all__ = ["MATERIALS", "LABELS", "environment", "scene", "ngan2005_figure"]

#: (material, kind), in rows of the plate
MATERIALS = (("nickel", "metal"), ("brass", "metal"), ("alum-bronze", "metal"),
             ("chrome-steel", "metal"), ("gold-metallic-paint", "paint"),
             ("red-metallic-paint", "paint"), ("orange-paint", "paint"),
             ("red-plastic", "plastic"), ("green-plastic", "plastic"),
             ("yellow-plastic", "plastic"), ("red-fabric", "fabric"), ("pink-felt", "fabric"))
LABELS = {"ashikhmin_shirley": "Ashikhmin-Shirley", "blinn_phong": "Blinn-Phong",
          "cook_torrance": "Cook-Torrance", "ward": "Ward", "ward_duer": "Ward-Duer"}


def environment(width=256):
    """A latitude-longitude environment (float32 RGB): sky gradient, a bright band at the
    horizon, a dark ground, and four darker meridians to show the reflection's sharpness."""
    h = width // 2
    theta = (np.arange(h) + 0.5) / h * np.pi              # 0 at the zenith (+y in Mitsuba)
    phi = (np.arange(width) + 0.5) / width * 2 * np.pi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    up = np.cos(t)
    sky = np.stack([0.35 + 0.25 * up, 0.45 + 0.3 * up, 0.7 + 0.3 * up], -1)
    ground = np.stack([0.08, 0.07, 0.06]) * np.ones_like(sky)
    img = np.where(up[..., None] > 0, sky, ground)
    band = np.exp(-((t - np.pi / 2) / 0.06) ** 2)[..., None] * np.array([1.6, 1.4, 1.1])
    img = img + band
    stripes = (np.cos(4 * p) > 0.97)[..., None] & (up[..., None] > 0)
    img = np.where(stripes, img * 0.25, img)
    return np.ascontiguousarray(img, dtype=np.float32)


def scene(bsdf, res, spp=None):
    """A sphere of ``bsdf`` (a dict or a loaded BSDF) under one area light and
    ``environment()``, seen slightly from above (``spp``: the sampler's count, else
    Mitsuba's default; the figure's renders give theirs)."""
    import mitsuba as mi
    from ..sphere import sphere_scene
    env = {"type": "envmap", "bitmap": mi.Bitmap(environment()), "scale": 1.0,
           "to_world": mi.ScalarTransform4f().rotate([0, 1, 0], 30)}
    return sphere_scene(bsdf, res, spp, eye=(0, 1.2, 6), rotate=False, lamp=((-4, 5, 5), 60),
                        env=env)


def ngan2005_figure(materials=MATERIALS):
    """The plate as a ``panels.Figure``: a row per material, a column per model."""
    from .. import presets
    panels = []
    for material, kind in materials:
        for model in presets.MODELS:
            preset = presets.ngan2005(model, material)
            panels.append(Panel(lambda d, p=preset: scene(p, d["res"]),
                                f"{material}\n{LABELS[model]}"))
    return Figure("ngan2005", "MERL materials as fitted by Ngan et al. 2005 (presets "
                  "ngan2005): rows: 4 metals, 3 paints, 3 plastics, 2 fabrics; columns: "
                  "Ashikhmin-Shirley, Blinn-Phong, Cook-Torrance, Ward, Ward-Duer; one light, "
                  "one environment",
                  panels, spp={"preview": 128, "final": 512},
                  res={"preview": 128, "final": 192}, columns=len(presets.MODELS),
                  check=())
