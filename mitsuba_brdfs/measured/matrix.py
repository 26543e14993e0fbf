"""Fits across models: MERL files written from the materials of one model, fitted by every
other, each fit judged by the directional albedo of source and fit at ``THETAS``.

``judge`` gives one fit one of two verdicts:

- ``within``: the fit (``fit-measured``'s defaults: the shape first, the albedo
  constrained wherever the model can reach it) reflects within ``TOLERANCE`` (10%) of the
  source's light at each angle and channel, and says so (the constraint's status 'met':
  the shape alone got there, or 'reached': the constraint did);
- ``cannot reach``: the fit says the model cannot reach the source's albedo, and an
  independent fit with the energy first (albedo weight ``ENERGY_FIRST``, no constraint)
  shows it: it stays more than 10% off, or gets there only with a channel further from
  the data than a black model (relative RMS error 1 or more).

Anything else is ``fails``: a fit more than 10% off that claims to be within, or one that
gives up where the energy-first fit reaches the albedo with a usable shape. The albedo is
computed by quadrature of the BSDFs (source and fit), not from the file.
``write_and_judge`` runs every other model on one source material; the tests
(``tests/test_fit_matrix*.py``) and ``scripts/fit_matrix.py`` (the table of
docs/presets.md) use it.
"""
import numpy as np

# ENERGY_FIRST: the albedo weight of a fit that puts the energy first
from .fitting import ALBEDO_GOAL, ENERGY_FIRST  # noqa: F401

__all__ = ["MODELS", "THETAS", "TOLERANCE", "ENERGY_FIRST", "WARD_REPORTED", "random_material",
           "material", "albedo", "judge", "write_and_judge"]

#: the models, as ``fit-measured`` loads them
MODELS = {"ward": {"type": "ward"}, "cook_torrance": {"type": "cook_torrance"},
          "ashikhmin_shirley": {"type": "ashikhmin_shirley"},
          "ashikhmin_shirley_lambert": {"type": "ashikhmin_shirley",
                                        "diffuse_term": "lambert"},
          "blinn_phong": {"type": "blinn_phong"}}
#: incidence angles (deg) of the judgement
THETAS = (0, 45, 75)
TOLERANCE = ALBEDO_GOAL

#: a Ward material that Cook-Torrance used to fit 56-84% too bright
WARD_REPORTED = {"type": "ward",
                 "diffuse_reflectance": {"type": "rgb", "value": [0.22, 0.30, 0.40]},
                 "specular_reflectance": {"type": "rgb", "value": [0.10, 0.08, 0.06]},
                 "alpha_u": 0.14, "alpha_v": 0.14}


def _rgb(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


def random_material(model, seed):
    """A material of ``model`` (a key of ``MODELS``) with random colours and lobe width
    (alpha 0.03 to 0.4; exponents 2 / alpha^2 - 2)."""
    rng = np.random.default_rng(seed)
    d, s = rng.uniform(0.03, 0.6, 3), rng.uniform(0.02, 0.3, 3)
    a = float(np.exp(rng.uniform(np.log(0.03), np.log(0.4))))
    n = 2 / a ** 2 - 2
    spec = dict(MODELS[model])
    if model == "ward":
        spec.update(diffuse_reflectance=_rgb(d), specular_reflectance=_rgb(s), alpha_u=a,
                    alpha_v=a)
    elif model == "cook_torrance":
        spec.update(diffuse_reflectance=_rgb(d), specular_reflectance=_rgb(
            rng.uniform(0.1, 1, 3)), f0=_rgb(rng.uniform(0.02, 0.9, 3)), roughness=a)
    elif model.startswith("ashikhmin_shirley"):
        spec.update(diffuse_reflectance=_rgb(d), nu=n, nv=n,
                    specular_reflectance=_rgb(rng.uniform(0.02, 0.6, 3)))
        if model.endswith("lambert"):
            spec.update(specular_scale=_rgb(rng.uniform(0.2, 1, 3)))
    else:
        spec.update(diffuse_reflectance=_rgb(d), specular_reflectance=_rgb(s), exponent=n)
    return spec


def material(model, name):
    """The load_dict dict of ``model``'s material ``name``: ``random-SEED``, ``reported``
    (``WARD_REPORTED``), or a preset (Ngan et al.'s Ashikhmin-Shirley fits have the
    Lambertian diffuse term)."""
    from .. import presets
    if name == "reported":
        return WARD_REPORTED
    if name.startswith("random-"):
        return random_material(model, int(name.split("-")[1]))
    return presets.ngan2005(model.replace("_lambert", ""), name)


def albedo(bsdf):
    """Directional albedo at ``THETAS`` (3 angles, 3 channels), by quadrature of the BSDF."""
    from ..validate.directions import sph
    from ..validate.energy import quadrature
    return np.array([quadrature(bsdf, sph(np.radians(t), 0.7)[0], 120, same_side=True)[0][0]
                     for t in THETAS])


def _fit(data, model, **kw):
    import mitsuba as mi
    from .report import fit_file
    from .variables import colour_spec
    spec = colour_spec(MODELS[model], mi.load_dict(MODELS[model]))
    bsdf = mi.load_dict(spec)
    return bsdf, fit_file(data, bsdf, **kw)


def judge(data, target, model, evaluations=None):
    """Fit ``model`` to a file's ``data`` (``data.prepare``) as ``fit-measured`` does; its
    verdict against the source's albedo ``target`` (``albedo``), with the numbers:
    {'verdict', 'status' (the constraint's), 'error' (the largest relative albedo error),
    'rms' (the largest channel's relative RMS error), 'rms_before' (before the constraint,
    where it changed the fit), 'seconds'; for a model that cannot reach the albedo,
    'reach' and 'reach_rms': the energy-first fit's error and relative RMS}."""
    bsdf, r = _fit(data, model, evaluations=evaluations)
    c = r["constraint"]
    out = {"error": float(np.max(np.abs(albedo(bsdf) / target - 1))),
           "rms": r["relative_rms_max"], "seconds": r["seconds"], "status": c["status"]}
    if c["status"] == "reached":
        out["rms_before"] = max(c["relative_rms_unconstrained"])
    if c["status"] != "cannot reach":
        out["verdict"] = "within" if out["error"] <= TOLERANCE else "fails"
        return out
    first, rf = _fit(data, model, evaluations=evaluations, albedo_weight=ENERGY_FIRST,
                     albedo_tolerance=None)
    out.update(reach=float(np.max(np.abs(albedo(first) / target - 1))),
               reach_rms=rf["relative_rms_max"])
    shown = out["reach"] > TOLERANCE or out["reach_rms"] >= 1
    out["verdict"] = "cannot reach" if shown and out["error"] > TOLERANCE else "fails"
    return out


def write_and_judge(path, source_model, name, dims, samples=None, evaluations=None,
                    models=None, progress=None):
    """Write a MERL file of ``dims`` bins (at ``path``) of ``source_model``'s material
    ``name`` and ``judge`` every other model of ``models`` (default: ``MODELS``) on it;
    ``progress(model, judgement)`` after each. Returns {model: judgement}."""
    import mitsuba as mi
    from . import merl
    from .data import SAMPLES, prepare
    src = mi.load_dict(material(source_model, name))
    merl.write(path, merl.from_bsdf(src, dims), dims)
    data = prepare(path, SAMPLES if samples is None else samples)
    target = albedo(src)
    out = {}
    for model in models or MODELS:
        if model == source_model:
            continue
        out[model] = judge(data, target, model, evaluations)
        if progress:
            progress(model, out[model])
    return out
