"""How the energy of each model's lobes varies with incidence: what a fit can represent.

For each model ``fit-measured``'s cross-model tests use, the directional albedo of its
lobe alone (white, the diffuse term off) at 45 and 75 deg divided by that at normal
incidence, over its lobe's parameters (widths alpha = 0.004 to 1, exponents 2 / alpha^2 - 2;
Fresnel f0 or Rs 0 to 1, where the model has them), and the same ratios of its diffuse
term. A material's albedo is a mix of the two, so a model whose ratios cannot reach a
material's cannot reflect its light within a given tolerance at every incidence
(docs/presets.md, "what each model can represent"). Albedo by quadrature over the half
vector (``validate.energy.quadrature``). Prints a Markdown table.

    python scripts/fit_model_energy.py
"""
import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
dr.set_thread_count(2)

import mitsuba_brdfs  # noqa: E402,F401  (registers the plugins)
from mitsuba_brdfs.validate.directions import sph  # noqa: E402
from mitsuba_brdfs.validate.energy import quadrature  # noqa: E402

ALPHAS = np.geomspace(0.004, 1, 24)
FRESNEL = np.linspace(0, 1, 11)
THETAS = (0, 45, 75)


def albedo(spec):
    b = mi.load_dict(spec)
    return np.array([quadrature(b, sph(np.radians(t), 0.7)[0], 100, same_side=True)[0][0][0]
                     for t in THETAS])


def lobes(model):
    """(lobe specs, diffuse spec) of a model."""
    n = lambda a: max(2 / a ** 2 - 2, 0.0)
    if model == "ward":
        return ([{"type": "ward", "diffuse_reflectance": 0.0, "specular_reflectance": 1.0,
                  "alpha_u": a, "alpha_v": a} for a in ALPHAS],
                {"type": "ward", "diffuse_reflectance": 1.0, "specular_reflectance": 0.0})
    if model == "ward (duer)":
        return ([{"type": "ward", "form": "duer", "diffuse_reflectance": 0.0,
                  "specular_reflectance": 1.0, "alpha_u": a, "alpha_v": a} for a in ALPHAS],
                {"type": "ward", "diffuse_reflectance": 1.0, "specular_reflectance": 0.0})
    if model == "blinn_phong":
        return ([{"type": "blinn_phong", "diffuse_reflectance": 0.0,
                  "specular_reflectance": 1.0, "exponent": n(a)} for a in ALPHAS],
                {"type": "blinn_phong", "diffuse_reflectance": 1.0, "specular_reflectance": 0.0})
    if model == "cook_torrance":
        return ([{"type": "cook_torrance", "k": 0.0, "specular_reflectance": 1.0,
                  "roughness": a, "f0": f} for a in ALPHAS for f in FRESNEL[1:]],
                {"type": "cook_torrance", "k": 1.0, "diffuse_reflectance": 1.0})
    extra = {"diffuse_term": "lambert"} if model.endswith("(lambert)") else {}
    return ([{"type": "ashikhmin_shirley", **extra, "diffuse_reflectance": 0.0,
              "specular_reflectance": f, "nu": n(a), "nv": n(a)}
             for a in ALPHAS for f in FRESNEL[1:]],
            {"type": "ashikhmin_shirley", **extra, "diffuse_reflectance": 1.0,
             "specular_reflectance": 0.0, "specular_scale": 0.0})


def main():
    print("| model | lobe: albedo at 45 deg / at 0 deg | lobe: at 75 deg / at 0 deg "
          "| diffuse term: at 45, 75 deg / at 0 deg |")
    print("|---|---|---|---|")
    for model in ("ward", "ward (duer)", "blinn_phong", "cook_torrance", "ashikhmin_shirley",
                  "ashikhmin_shirley (lambert)"):
        specs, diffuse = lobes(model)
        r = np.array([a / a[0] for a in map(albedo, specs)])
        d = albedo(diffuse)
        d = d / d[0]
        print(f"| {model} | {r[:, 1].min():.2f} to {r[:, 1].max():.2f} | "
              f"{r[:, 2].min():.2f} to {r[:, 2].max():.2f} | {d[1]:.2f}, {d[2]:.2f} |")


if __name__ == "__main__":
    main()
