"""The ``energy_compensation`` figure: rough metals with and without the light they lose.

White and gold ``cook_torrance`` metals (GGX D and Smith G, k = 0, m_S = 1; f0 = 1 and
f0 = ``GOLD``, Schlick's gold) at roughness 0.1 to 1, each form of ``energy_compensation``
(``none``, ``kulla_conty``, ``turquin``), beside Mitsuba's ``roughconductor`` (GGX,
alpha = roughness; ``material = none``, a perfect mirror's Fresnel, and ``Au``), which has
the same single-scattering lobe as ``none``. The scene is a white furnace: a sphere under
uniform light of ``FURNACE`` from every direction, ``direct`` integrator (a convex shape
sees only the light), so every pixel is the directional albedo at its angle times the
light: a sphere that reflects all the light vanishes into the background.
"""
from .panels import Figure, Panel

__all__ = ["ROUGHNESS", "FORMS", "GOLD", "FURNACE", "bsdf", "furnace_scene", "energy_figure"]

#: the columns
ROUGHNESS = (0.1, 0.25, 0.4, 0.55, 0.7, 0.85, 1.0)
#: the rows of each colour: the package's three forms, then Mitsuba's plugin
FORMS = ("none", "kulla_conty", "turquin", "roughconductor")
#: Schlick's f0 of gold (linear sRGB)
GOLD = (1.0, 0.71, 0.29)
#: the furnace's radiance
FURNACE = 0.8


def bsdf(form, roughness, gold):
    """The BSDF dict of one panel."""
    if form == "roughconductor":
        return {"type": "roughconductor", "distribution": "ggx", "alpha": roughness,
                "material": "Au" if gold else "none"}
    return {"type": "cook_torrance", "distribution": "ggx", "geometry": "ggx", "k": 0.0,
            "specular_reflectance": 1.0, "roughness": roughness,
            "f0": {"type": "rgb", "value": list(GOLD)} if gold else 1.0,
            "energy_compensation": form}


def furnace_scene(bsdf, res, spp=None):
    """A unit sphere of ``bsdf`` in the white furnace, seen from the front."""
    import mitsuba as mi
    sensor = {"type": "perspective", "fov": 26,
              "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0],
                                                         up=[0, 1, 0]),
              "film": {"type": "hdrfilm", "width": res, "height": res,
                       "rfilter": {"type": "gaussian"}}}
    if spp is not None:
        sensor["sampler"] = {"type": "independent", "sample_count": spp}
    return mi.load_dict({"type": "scene", "integrator": {"type": "direct"}, "sensor": sensor,
                         "ball": {"type": "sphere", "bsdf": bsdf},
                         "env": {"type": "constant",
                                 "radiance": {"type": "rgb", "value": FURNACE}}})


def energy_figure():
    """The plate as a ``panels.Figure``: rows white none, kulla_conty, turquin,
    roughconductor, then the same in gold; a column per roughness."""
    panels = []
    for gold in (False, True):
        for form in FORMS:
            for r in ROUGHNESS:
                label = f"{'gold' if gold else 'white'} {form}\nroughness {r:g}"
                panels.append(Panel(lambda d, b=bsdf(form, r, gold): furnace_scene(b, d["res"]),
                                    label))
    return Figure("energy_compensation",
                  "Rough metals in a white furnace (uniform light from every direction: a "
                  "sphere that reflects all of it vanishes). cook_torrance, GGX D and Smith G, "
                  "white (f0 = 1) and gold (f0 = 1, 0.71, 0.29); rows: energy_compensation "
                  "none, kulla_conty, turquin, then Mitsuba's roughconductor (GGX, material "
                  "none / Au); columns: roughness 0.1 to 1",
                  panels, spp={"preview": 64, "final": 256},
                  res={"preview": 96, "final": 160}, columns=len(ROUGHNESS), check=())
