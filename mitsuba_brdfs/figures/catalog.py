"""The model catalog: every model and form on the same sphere under the same light.

One tile per configuration, labelled, composed into ``catalog.png`` (rendered by
``python -m mitsuba_brdfs figures``, figure ``catalog``). The scene is the sphere of
``scenes/as_sphere.xml`` (``timing.sphere_scene``): a small area light up-left and a dim
environment, ``direct`` integrator (nothing else in the scene to reflect). Every model
gets the same red diffuse colour and a white specular layer where it has one.

Entries whose plugin is not registered (a model not written yet) are left out with a
printed note, so the catalog always renders what exists::

    python -m mitsuba_brdfs figures --only catalog
"""
import os

from ..passes import DEFAULT_PASS_SAMPLES
from ..paths import SCENES
from ..timing import sphere_scene
from .panels import Figure, Panel, render_figure

__all__ = ["RED", "CATALOG", "available", "catalog_figure", "render_catalog"]

RED = {"type": "rgb", "value": [0.5, 0.1, 0.08]}
WHITE = lambda v: {"type": "rgb", "value": [v, v, v]}  # noqa: E731



def _ramp(name, filter_type):
    """One of the PNG colour ramps of ``scenes/toon_ramp.xml``."""
    return {"type": "bitmap", "filename": os.path.join(SCENES, name), "filter_type": filter_type}


#: (label, bsdf dict) in reading order
CATALOG = [
    ("lambert", {"type": "lambert", "reflectance": RED}),
    ("oren_nayar sigma=0.5", {"type": "oren_nayar", "reflectance": RED, "sigma": 0.5}),
    ("oren_nayar a=0.6 b=0.4", {"type": "oren_nayar", "reflectance": RED, "a": 0.6, "b": 0.4}),
    ("oren_nayar energy_preserving r=1", {"type": "oren_nayar", "form": "energy_preserving",
                                          "reflectance": RED, "roughness": 1.0}),
    ("toon", {"type": "toon", "diffuse_reflectance": RED}),
    ("toon ramps (nearest)", {"type": "toon",
                              "diffuse_ramp": _ramp("toon_ramp_diffuse.png", "nearest"),
                              "specular_ramp": _ramp("toon_ramp_specular.png", "nearest")}),
] + [
    (f"{m} {form}", {"type": m, "form": form, "diffuse_reflectance": RED,
                     "specular_reflectance": WHITE(0.3), "exponent": 60.0})
    for m in ("phong", "blinn_phong") for form in ("original", "modified", "normalized")
] + [
    ("blinn_phong normalized approximate", {"type": "blinn_phong", "form": "normalized",
                                            "normalization": "approximate",
                                            "diffuse_reflectance": RED,
                                            "specular_reflectance": WHITE(0.3), "exponent": 60.0}),
] + [
    ("torrance_sparrow p=60", {"type": "torrance_sparrow", "diffuse_reflectance": RED,
                               "specular_reflectance": WHITE(1.0), "exponent": 60.0}),
    ("ward au=0.05 av=0.3", {"type": "ward", "diffuse_reflectance": RED,
                             "specular_reflectance": WHITE(0.2), "alpha_u": 0.05, "alpha_v": 0.3}),
] + [
    (f"ward {form} au=0.05 av=0.3", {"type": "ward", "form": form, "diffuse_reflectance": RED,
                                     "specular_reflectance": WHITE(0.2), "alpha_u": 0.05,
                                     "alpha_v": 0.3})
    for form in ("duer", "balanced")
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
    # roughness instead of exponents: alpha = 0.1 is n = 198 (AS, Blinn-Phong), 49.5 (Phong)
    ("ashikhmin_shirley alpha_u=0.05 alpha_v=0.3",
     {"type": "ashikhmin_shirley", "diffuse_reflectance": RED, "specular_reflectance": WHITE(0.05),
      "alpha_u": 0.05, "alpha_v": 0.3}),
    ("phong alpha=0.1", {"type": "phong", "diffuse_reflectance": RED,
                         "specular_reflectance": WHITE(0.3), "alpha": 0.1}),
    ("blinn_phong alpha=0.1", {"type": "blinn_phong", "diffuse_reflectance": RED,
                               "specular_reflectance": WHITE(0.3), "alpha": 0.1}),
]


def available(entries=None, note=print):
    """The entries whose BSDF loads in the active variant; a note for each one left out.

    A plugin that is not registered (yet) or does not accept the entry's parameters is
    skipped, never an error: the catalog shows what exists.
    """
    import mitsuba as mi
    kept = []
    for label, bsdf in (CATALOG if entries is None else entries):
        try:
            mi.load_dict(bsdf)
        except RuntimeError as e:
            reason = (f"plugin {bsdf['type']!r} is not registered" if "not found" in str(e)
                      else f"{bsdf['type']!r} did not load: {str(e).splitlines()[0]}")
            note(f"catalog: skipping {label!r}: {reason}")
            continue
        kept.append((label, bsdf))
    return kept


def catalog_figure(entries=None, columns=5, note=print):
    """The catalog as a ``panels.Figure``: one panel per available entry."""
    def loader(bsdf):
        return lambda defines: sphere_scene(bsdf, res=defines["res"])

    panels = [Panel(loader(bsdf), label) for label, bsdf in available(entries, note)]
    return Figure("catalog", "Every model on the same sphere, light and diffuse colour",
                  panels, spp={"preview": 64, "final": 256},
                  res={"preview": 160, "final": 320}, columns=columns)


def render_catalog(quality="preview", out_dir=None, pass_samples=DEFAULT_PASS_SAMPLES,
                   spp=None, res=None, entries=None, columns=5):
    """Render every available catalog entry and write the labelled grid ``catalog.png``
    (and one EXR per tile, ``catalog_<k>.exr``); returns the timings dict."""
    fig = catalog_figure(entries, columns)
    if not fig.panels:
        print("catalog: no model available, nothing rendered")
        return {"panels": 0, "quality": quality}
    t = render_figure(fig, quality, out_dir, pass_samples, spp, res)
    return {**t, "shown": [p.label for p in fig.panels]}
