"""Energy compensation priced: render time of each ``energy_compensation`` form against
``none``, beside the white furnace error each form leaves (``core.energy``).

Part 12 of the performance study. Each case is a microfacet material rendered on the sphere
(``speed.compare``: paired, alternating renders after a warm-up, the median of the
per-pair ratios) as ``kulla_conty`` against ``none`` and as ``turquin`` against ``none``;
and the same lobe made white (F = 1, no diffuse part) is integrated over the hemisphere
(``validate.energy.reflected``) at incidences of 0 to 80 degrees: the furnace error is the
largest |1 - albedo|, what each form leaves of the light single scattering loses.
"""
from ..progress import advance

__all__ = ["GOLD", "CASES", "FORMS", "THETAS", "white", "furnace", "run"]

#: Schlick's f0 of gold (linear sRGB)
GOLD = {"type": "rgb", "value": [1.0, 0.71, 0.29]}
_RED = {"type": "rgb", "value": [0.6, 0.08, 0.05]}

#: key -> (what, the rendered BSDF without its ``energy_compensation``)
CASES = {
    "ct_ggx_smith_gold": ("cook_torrance GGX D, Smith G, roughness 0.5, gold metal (k = 0)",
                          {"type": "cook_torrance", "distribution": "ggx", "geometry": "ggx",
                           "roughness": 0.5, "k": 0.0, "f0": GOLD}),
    "ct_beckmann_vgroove_gold": ("cook_torrance Beckmann D, V-groove G, roughness 0.5, gold "
                                 "metal (k = 0)",
                                 {"type": "cook_torrance", "distribution": "beckmann",
                                  "geometry": "cook_torrance", "roughness": 0.5, "k": 0.0,
                                  "f0": GOLD}),
    "ct_ggx_smith_plastic": ("cook_torrance GGX D, Smith G, roughness 0.5, red plastic "
                             "(k = 0.5, f0 = 0.04: the glossy lobe is chosen against the "
                             "diffuse one)",
                             {"type": "cook_torrance", "distribution": "ggx", "geometry": "ggx",
                              "roughness": 0.5, "k": 0.5, "diffuse_reflectance": _RED}),
    "ts_p5": ("torrance_sparrow exponent 5, white metal (k_d = 0, eta = 1e30: F = 1)",
              {"type": "torrance_sparrow", "exponent": 5.0, "diffuse_reflectance": 0.0,
               "eta": 1e30}),
}
#: the forms compared with ``none``
FORMS = ("kulla_conty", "turquin")
#: incidences of the furnace (degrees)
THETAS = (0, 20, 40, 60, 70, 80)


def white(bsdf):
    """The white single lobe of a case's BSDF: no diffuse part, F = 1."""
    if bsdf["type"] == "torrance_sparrow":
        return {**bsdf, "diffuse_reflectance": 0.0, "specular_reflectance": 1.0, "eta": 1e30}
    return {**bsdf, "k": 0.0, "f0": 1.0, "specular_reflectance": 1.0}


def furnace(bsdf, thetas=THETAS):
    """The white lobe's albedo at each incidence of ``thetas`` (degrees), by quadrature."""
    import mitsuba as mi

    from ..validate.energy import reflected
    return [float(a) for a in reflected(mi.load_dict(bsdf), thetas)[:, 0]]


def run(settings, available, progress=None):
    """Part 12: for each case, the furnace of each form and each form's render time
    against ``none``."""
    import mitsuba as mi

    from .speed import compare
    from ..timing import bsdf_instructions
    out = {"settings": {"res": settings.speed_res, "spp": settings.speed_spp,
                        "runs": settings.speed_runs, "integrator": "direct",
                        "thetas": list(THETAS), "variant": mi.variant()},
           "cases": {}, "skipped": []}
    for key in settings.energy_cases:
        what, bsdf = CASES[key]
        if bsdf["type"] not in available:
            out["skipped"].append(f"{key}: plugin `{bsdf['type']}` is not registered")
            advance(progress, len(FORMS), f"skip {key}")
            continue
        case = {"what": what, "bsdf": bsdf, "forms": {}}
        for form in ("none",) + FORMS:
            albedo = furnace({**white(bsdf), "energy_compensation": form})
            case["forms"][form] = {
                "albedo": albedo, "furnace_error": max(abs(1 - a) for a in albedo),
                "instructions": bsdf_instructions(mi.load_dict(
                    {**bsdf, "energy_compensation": form}))}
        for form in FORMS:
            r = compare({**bsdf, "energy_compensation": form}, bsdf, settings, progress,
                        note=f"{key} {form}")
            case["forms"][form]["against_none"] = r
        out["cases"][key] = case
    return out
