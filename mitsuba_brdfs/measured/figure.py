"""The figure of ``docs/measured.md``: spheres rendered with a source BSDF (left) and with
the RGL file ``to-rgl`` writes from it, through Mitsuba's ``measured`` (right), under one
area light and a uniform environment; the last row a MERL file (written from the
Cook-Torrance fit of gold-paint, ``presets.ngan2005``), which Mitsuba cannot render
otherwise, beside the BSDF it was written from.

    python -m mitsuba_brdfs.measured.figure docs/measured.png
"""
import os
import sys
import tempfile

import numpy as np

__all__ = ["SOURCES", "scene", "render"]

#: (label, load_dict dict) of the rows; "merl" marks the row converted through a MERL file
SOURCES = (
    ("roughplastic", {"type": "roughplastic", "alpha": 0.08,
                      "diffuse_reflectance": {"type": "rgb", "value": [0.1, 0.3, 0.7]}}),
    ("roughconductor", {"type": "roughconductor", "alpha": 0.2, "material": "Au"}),
    ("ashikhmin_shirley", {"type": "ashikhmin_shirley", "nu": 200, "nv": 200,
                           "specular_reflectance": 0.1,
                           "diffuse_reflectance": {"type": "rgb", "value": [0.6, 0.08, 0.05]}}),
    ("merl", None),
)


def scene(bsdf, res):
    """A sphere under an area light and a uniform environment."""
    from ..sphere import sphere_scene
    return sphere_scene(bsdf, res, None, "path", fov=26, rotate=False, lamp=((-4, 4, 6), 60),
                        env=0.25)


def _merl_source(path):
    import mitsuba as mi
    from . import merl
    from .. import presets
    spec = presets.ngan2005("cook_torrance", "gold-paint")
    merl.write(path, merl.from_bsdf(mi.load_dict(spec)))
    return spec


def render(path, res=200, spp=256):
    """Render the rows and write the PNG ``path``; returns the mean pixel of each image
    (source, file) per row."""
    import mitsuba as mi
    from ..output import write_png
    from ..variant import set_variant
    from . import acquire, convert, sources
    set_variant("llvm_ad_rgb")
    rows, means = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for label, spec in SOURCES:
            out = os.path.join(tmp, f"{label}.bsdf")
            if spec is None:
                binary = os.path.join(tmp, "gold-paint.binary")
                spec = _merl_source(binary)
                source = sources.open_source(binary)
            else:
                source = sources.Source(sources.bsdf_evaluator(mi.load_dict(spec)), label,
                                        "bsdf", label, [])
            convert.convert(source, out, acquire.Resolution(), compare=False)
            imgs = [np.array(mi.render(scene(b, res), spp=spp, seed=1))
                    for b in (spec, {"type": "measured", "filename": out})]
            means.append([img.mean((0, 1)) for img in imgs])
            rows.append(np.concatenate(imgs, 1))
    write_png(path, np.concatenate(rows, 0))
    return means


if __name__ == "__main__":
    import drjit as dr
    dr.set_thread_count(2)
    for m in render(sys.argv[1] if len(sys.argv) > 1 else "measured.png"):
        print(np.round(m, 4).tolist())
