"""A model fitted to a measured entry in the page: the samples, the fit, the fitted entry.

``data(info)`` reads the samples of the measured file of an entry (``measurement.
rgl_file``'s ``info``): the measurement itself (a MERL entry's MERL file, not the RGL file
drawn), the samples ``measured.read`` gives (an RGL file's through it; a MERL file's bins
picked in its table directly, the same samples without placing every bin), and keeps what
a fit needs, once per entry:

- the shape term: ``SAMPLES`` samples drawn at random (seed 0) among those with both
  directions within 80 deg of the normal (the fitting core's ``MIN_COS``), and as many
  others, held out, on which the fit's error is measured; an isotropic file's pairs each
  turned about the normal by a random angle (the data do not change; an anisotropic model
  sees every azimuth). A reduced set: a full MERL file has about 910,000 such bins, an RGL
  file of the database 6,000-25,000 samples; on 20,000 (``fit-measured``'s default) this
  package's models find parameters within 3 % of these (docs/explore.md). Each sample
  is weighted by the measure of the direction pairs it stands for (``measure``: a MERL
  bin's cell, ``merl.measure``; an RGL node's share of its incidence's band of wi times
  the solid angle of its cell of the adapted grid), so that the loss is an integral over
  the pairs of directions, as ``fit-measured``'s default;
- the energy term: the directional albedo at the fitting core's incidences
  (``albedo_quadrature``), of the data where they are given: an RGL file through
  Mitsuba's ``measured``, a MERL file looked up as MERL's reader does.

``fit(model, fit_data, label, progress)`` fits this package's plugin ``model`` (from its
defaults, colours as RGB) with the fitting core (``measured.fitting.fit``: L-BFGS-B on Dr.Jit's
gradients, from several starts) within ``EVALUATIONS`` evaluations, and returns the
``load_dict`` dictionary of the fitted model and its summary: the loss, the relative RMS
error of f cos on the held-out samples and on the fitted ones, the albedo of the data and
of the fit at 0, 45 and 75 deg, the seconds. ``fit_core`` is the one place that reaches the
fitting core.
"""
import math
import os
import time

import numpy as np

__all__ = ["SAMPLES", "EVALUATIONS", "REPORT_THETAS", "fit_core", "measure", "data", "fit"]

#: shape samples of a fit (and as many held out)
SAMPLES = 4000
#: evaluations of the loss and its gradient a fit may take
EVALUATIONS = 250
#: incidences (deg) at which the summary compares the albedo of the fit and of the data
REPORT_THETAS = (0, 45, 75)


def fit_core():
    """The fitting core: {name: object} of what the explorer uses of it."""
    from ..measured import fitting, quality, variables
    return {"fit": fitting.fit, "quality": quality.quality,
            "bound_warnings": quality.bound_warnings,
            "albedo_quadrature": fitting.albedo_quadrature,
            "ALBEDO_THETAS": fitting.ALBEDO_THETAS, "MIN_COS": fitting.MIN_COS,
            "colour_spec": variables.colour_spec}


# -- the measure of a sample ---------------------------------------------------------------

def _bands(x, lo=None, hi=None):
    """The interval each of the increasing nodes ``x`` stands for: from the midpoint with
    its neighbour below to the one above (the ends: the first and last nodes)."""
    x = np.asarray(x, float)
    mid = (x[1:] + x[:-1]) / 2
    return (np.concatenate([[x[0] if lo is None else lo], mid]),
            np.concatenate([mid, [x[-1] if hi is None else hi]]))


def _rgl_measure(path, s, index):
    """The measure of the RGL samples ``index`` of ``s`` (``measured.read``): each one's
    incidence's share of the hemisphere of wi (a band of theta_i between the midpoints to
    its neighbours, times a band of phi_i, or 2 pi for an isotropic file) times the solid
    angle of its node's cell of the adapted grid, 1 / (n - 1)^2 of the VNDF warp's input square mapped to wo:
    1 / ((n - 1)^2 p(u_m)) 2 pi^2 u sin(theta_m) 4 |wi . m|, p the warp's density at the
    half vector's coordinates u_m."""
    from ..measured import rgl, warp
    m = rgl.load(path)
    n = m.resolution[2]
    lo, hi = _bands(m.theta_i, 0.0, min(m.theta_i[-1], math.pi / 2))
    band_theta = np.cos(lo) - np.cos(hi)
    if m.isotropic:
        band_phi = np.full(len(m.phi_i), 2 * math.pi / len(m.phi_i))
    else:
        a, b = _bands(m.phi_i)
        band_phi = b - a
    wi, wo, incidence, phi_index = s.wi[index], s.wo[index], s.incidence[index], \
        s.phi_index[index]
    h = wi + wo
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    theta_m = warp.elevation(h)
    phi_m = np.arctan2(h[:, 1], h[:, 0])
    if m.isotropic:   # the half vector's azimuth relative to the incidence's
        phi_m = phi_m - np.where(np.hypot(wi[:, 0], wi[:, 1]) > 0,
                                 np.arctan2(wi[:, 1], wi[:, 0]), 0.0)
    phi_m = np.mod(phi_m + math.pi, 2 * math.pi) - math.pi
    u = np.stack([warp.theta2u(theta_m), warp.phi2u(phi_m)], -1)
    out = np.zeros(len(wi))
    for k in range(len(m.phi_i)):
        for l in range(len(m.theta_i)):
            here = (incidence == l) & (phi_index == k)
            if not here.any():
                continue
            p = warp.Marginal2D(m.vndf[k, l]).eval(u[here])
            cell = (2 * math.pi ** 2 * u[here, 0] * np.sin(theta_m[here])
                    * 4 * np.abs(np.sum(wi[here] * h[here], axis=1)))
            with np.errstate(divide="ignore", invalid="ignore"):
                dw = np.where(p > 0, cell / (p * (n - 1) ** 2), 0.0)
            out[here] = band_theta[l] * band_phi[k] * dw
    return out


def measure(s, index=None):
    """The measure in the space of direction pairs of each sample of ``s`` (a
    ``measured.read`` result; ``index``: of these samples only)."""
    from ..measured import merl
    if s.kind == "merl":
        sub = np.arange(len(s.wi)) if index is None else index
        dims = merl.check_file(s.path)
        return merl.measure(dims, merl.lookup(s.wi[sub], s.wo[sub], dims))
    return _rgl_measure(s.path, s, slice(None) if index is None else index)


# -- the data of a fit ---------------------------------------------------------------------

def _turn(v, angle):
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    return np.concatenate([c * v[:, :1] - s * v[:, 1:2], s * v[:, :1] + c * v[:, 1:2],
                           v[:, 2:]], 1)


def _data_at(info, wi, wo):
    """f (the BRDF, without cosine) of the data at the pairs (wi, wo), NaN where it is not
    measured: Mitsuba's ``measured`` on an RGL file (a plugin of its own: the entry's is
    drawn meanwhile), a MERL file's bins looked up as its reader does (unmeasured bins NaN,
    as ``fit-measured`` leaves them out of the energy term)."""
    if info["kind"] == "merl":
        from ..measured import merl
        dims, f = merl.read(info["file"])
        return f[merl.lookup(wi, wo, dims)]
    import mitsuba as mi
    from ..validate.probe import eval_np
    bsdf = mi.load_dict({"type": "measured", "filename": info["rgl"]})
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.asarray(eval_np(bsdf, wi, wo), float).reshape(len(wi), -1) / wo[:, 2:3]


def _merl_samples(path, count, min_cos, rng):
    """``count`` random measured bins of a MERL file with both directions more than
    ``min_cos`` above the horizon, as (wi, wo, f, measure, usable bins, isotropic): the
    bins of ``measured.read``, found without the directions of every bin (1.5 s for a
    full file): random candidates are placed, those within 80 deg kept, more drawn while
    too few (and all bins for a small file)."""
    from ..measured import merl
    dims, f = merl.read(path)
    measured = np.nonzero(np.isfinite(f).all(1))[0]
    rng.shuffle(measured)
    chosen, start, step = [], 0, max(8 * count, 50_000)
    while sum(len(c) for c in chosen) < count and start < len(measured):
        cand = measured[start:start + step]
        wi, wo = merl.directions(dims, index=cand)
        chosen.append(cand[(wi[:, 2] > min_cos) & (wo[:, 2] > min_cos)])
        start += step
    found = np.concatenate(chosen) if chosen else np.zeros(0, int)
    # the usable bins of the file: counted, or estimated from the candidates placed
    placed = min(start, len(measured))
    usable = len(found) if placed == len(measured) else \
        int(round(len(found) / placed * len(measured)))
    chosen = found[:count]
    wi, wo = merl.directions(dims, index=chosen)
    return wi, wo, f[chosen], merl.measure(dims, chosen), usable, True


def _rgl_samples(path, count, min_cos, rng):
    """The same of an RGL file (``measured.read``; ``measure``)."""
    from ..measured.reader import read
    s = read(path)
    if s.spectral:
        raise ValueError(f"{os.path.basename(path)}: a spectral file; a fit needs RGB "
                         f"values (explore --variant llvm_ad_rgb and an RGB file)")
    usable = np.nonzero(np.isfinite(s.value).all(1) & (s.wi[:, 2] > min_cos)
                        & (s.wo[:, 2] > min_cos))[0]
    chosen = rng.permutation(usable)[:count]
    return (s.wi[chosen], s.wo[chosen], s.value[chosen], measure(s, chosen), len(usable),
            s.isotropic)


def data(info, samples=SAMPLES, seed=0):
    """What a fit to the measured entry ``info`` needs (see the module docstring): {'wi',
    'wo', 'f', 'weights'} of the fitted samples, the same of the held-out ones under
    'heldout', 'albedo' (the energy term's rows), 'usable' (samples within 80 deg in the
    file), 'samples' (fitted)."""
    core = fit_core()
    rng = np.random.default_rng(seed)
    read = _merl_samples if info["kind"] == "merl" else _rgl_samples
    wi, wo, f, w, usable, isotropic = read(info["file"], 2 * samples, core["MIN_COS"], rng)
    name = os.path.basename(info["file"])
    if len(wi) < 20:
        raise ValueError(f"{name}: {len(wi)} measured samples within 80 deg of the normal: "
                         f"too few to fit a model")
    if isotropic:
        angle = rng.uniform(0, 2 * np.pi, len(wi))
        wi, wo = _turn(wi, angle), _turn(wo, angle)
    half = samples if len(wi) >= 2 * samples else len(wi) // 2
    part = lambda a, b: {"wi": wi[a:b], "wo": wo[a:b], "f": f[a:b], "weights": w[a:b]}
    rows = core["albedo_quadrature"](core["ALBEDO_THETAS"])
    qf = _data_at(info, rows["wi"].reshape(-1, 3), rows["wo"].reshape(-1, 3))
    qf[rows["weight"].ravel() <= 0] = np.nan    # the rows' padding
    rows["f"] = qf.reshape(rows["weight"].shape + (3,))
    return {**part(0, half), "heldout": part(half, len(wi)), "albedo": rows,
            "usable": usable, "samples": half, "file": info["file"]}


# -- the fit ---------------------------------------------------------------------------------

class Cancelled(Exception):
    """Raised by a fit's progress callback to stop it."""


def _props(spec, params):
    """The ``load_dict`` dictionary of the fitted model: ``spec`` with the fitted values
    ({traverse key: list}) under the names the plugin reads."""
    out = dict(spec)
    for key, v in params.items():
        name = key[:-len(".value")] if key.endswith(".value") else key
        out[name] = float(v[0]) if len(v) == 1 else {"type": "rgb",
                                                      "value": [float(x) for x in v[:3]]}
    return out


def _albedo_summary(result, thetas):
    rows = [thetas.index(t) for t in REPORT_THETAS]
    measured = np.array(result["albedo"]["measured"])[rows]
    fitted = np.array(result["albedo"]["fitted"])[rows]
    from ..measured.acquire import LUMINANCE as lum
    return {"thetas": list(REPORT_THETAS), "measured": (measured @ lum).tolist(),
            "fitted": (fitted @ lum).tolist()}


def fit(model, fit_data, label, progress=None, evaluations=EVALUATIONS):
    """Fit this package's plugin ``model`` to ``fit_data`` (``data``); (the fitted model's
    ``load_dict`` dictionary, its summary). ``progress(loss)`` after each evaluation may
    raise ``Cancelled``."""
    import mitsuba as mi
    core = fit_core()
    t0 = time.perf_counter()
    spec = {"type": model}
    spec = core["colour_spec"](spec, mi.load_dict(spec))
    bsdf = mi.load_dict(spec)
    d = fit_data
    r = core["fit"](bsdf, d["wi"], d["wo"], d["f"], weights=d["weights"],
                    albedo=d["albedo"], evaluations=evaluations, progress=progress)
    h = d["heldout"]
    heldout = core["quality"](bsdf, h["wi"], h["wo"], h["f"], h["weights"])
    fitted = core["quality"](bsdf, d["wi"], d["wo"], d["f"], d["weights"])
    props = _props(spec, r["params"])
    summary = {
        "model": model, "to": label, "loss": r["loss"], "start_loss": r["start_loss"],
        "heldout_rms": heldout["relative_rms"], "heldout_rms_max": heldout["relative_rms_max"],
        "fitted_rms_max": fitted["relative_rms_max"],
        "albedo": _albedo_summary(r, list(core["ALBEDO_THETAS"])),
        "samples": d["samples"], "heldout": len(h["wi"]), "usable": d["usable"],
        "evaluations": r["evaluations"], "budget": evaluations,
        "seconds": time.perf_counter() - t0,
        "warning": core["bound_warnings"](r["at_bounds"])}
    return props, summary
