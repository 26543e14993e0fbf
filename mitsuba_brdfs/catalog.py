"""The model catalog: every model and form on the same sphere under the same light.

One tile per configuration, labelled, composed into ``renders/catalog.png`` (rendered by
``python -m mitsuba_brdfs figures``, figure ``catalog``). The scene is the sphere of
``scenes/as_sphere.xml`` (``timing.sphere_scene``): a small area light up-left and a dim
environment, ``direct`` integrator (nothing else in the scene to reflect). Every model
gets the same red diffuse colour and a white specular layer where it has one.
"""
import os
import time

from . import render as R

__all__ = ["RED", "CATALOG", "render_catalog"]

RED = {"type": "rgb", "value": [0.5, 0.1, 0.08]}
WHITE = lambda v: {"type": "rgb", "value": [v, v, v]}  # noqa: E731

#: (label, bsdf dict) in reading order
CATALOG = [
    ("lambert", {"type": "lambert", "reflectance": RED}),
    ("oren_nayar sigma=0.5", {"type": "oren_nayar", "reflectance": RED, "sigma": 0.5}),
    ("toon", {"type": "toon", "diffuse_reflectance": RED}),
] + [
    (f"{m} {form}", {"type": m, "form": form, "diffuse_reflectance": RED,
                     "specular_reflectance": WHITE(0.3), "exponent": 60.0})
    for m in ("phong", "blinn_phong") for form in ("original", "modified", "normalized")
] + [
    ("torrance_sparrow p=60", {"type": "torrance_sparrow", "diffuse_reflectance": RED,
                               "specular_reflectance": WHITE(1.0), "exponent": 60.0}),
    ("ward au=0.05 av=0.3", {"type": "ward", "diffuse_reflectance": RED,
                             "specular_reflectance": WHITE(0.2), "alpha_u": 0.05, "alpha_v": 0.3}),
] + [
    (f"cook_torrance {d}/{g}", {"type": "cook_torrance", "distribution": d, "geometry": g,
                                "diffuse_reflectance": RED, "roughness": 0.2, "k": 0.5})
    for d in ("beckmann", "blinn", "ggx") for g in ("cook_torrance", "ggx")
] + [
    ("ashikhmin_shirley n=100", {"type": "ashikhmin_shirley", "diffuse_reflectance": RED,
                                 "specular_reflectance": WHITE(0.05), "nu": 100.0, "nv": 100.0}),
    ("ashikhmin_shirley nu=10 nv=1000", {"type": "ashikhmin_shirley", "diffuse_reflectance": RED,
                                         "specular_reflectance": WHITE(0.05), "nu": 10.0,
                                         "nv": 1000.0}),
    ("ashikhmin_shirley metal n=300", {"type": "ashikhmin_shirley", "diffuse_reflectance": 0.0,
                                       "specular_reflectance": {"type": "rgb",
                                                                "value": [0.95, 0.7, 0.35]},
                                       "nu": 300.0, "nv": 300.0}),
]


def render_catalog(quality="preview", out_dir=None, pass_samples=R.DEFAULT_PASS_SAMPLES,
                   spp=None, res=None, entries=None, columns=5):
    """Render every catalog entry and write the labelled grid ``catalog.png``; timings dict."""
    from .figures import ROOT, compose
    from .timing import sphere_scene
    out_dir = out_dir or os.path.join(ROOT, "renders")
    spp = spp or {"preview": 64, "final": 256}[quality]
    res = res or {"preview": 160, "final": 320}[quality]
    entries = entries or CATALOG
    tiles, labels = [], []
    t0, seconds = time.perf_counter(), 0.0
    for k, (label, bsdf) in enumerate(entries):
        scene = sphere_scene(bsdf, res=res, spp=spp)
        image, sec = R.render_passes(scene, spp, pass_samples,
                                     label=f"catalog {k + 1}/{len(entries)}")
        seconds += sec
        tiles.append(R.tonemap(image))
        labels.append(label)
    grid = compose(tiles, labels, columns=min(columns, len(tiles)),
                   title="Every model on the same sphere, light and diffuse colour")
    R.write_png(os.path.join(out_dir, "catalog.png"), grid, already_tonemapped=True)
    return {"seconds_render": round(seconds, 3), "seconds_total": round(time.perf_counter() - t0, 3),
            "spp": spp, "resolution": res, "panels": len(entries), "quality": quality}
