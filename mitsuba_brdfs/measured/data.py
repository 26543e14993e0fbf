"""What a fit reads: ``prepare(path)`` gives the ``Measured`` data of a MERL or an RGL file,
``prepare_bsdf(bsdf)`` that of any BSDF (a model converted into another): the shape term's
samples (wi, wo, f, weights), held-out samples, the energy term's rows (``fitting.fit``'s
``albedo``) and an evaluator of the data for plots.

The shape term and the held-out pairs: disjoint random subsets (``samples``, ``holdout``,
fixed by ``seed``) of the measured pairs with both directions within 80 deg of the normal,
each weighted by the measure of the direction pairs it stands for (``weights="bins"``:
every sample alike, as Ngan et al. count MERL's bins):

- MERL: the bins, each at the centre of its cell (what its value stands for,
  ``merl.directions``), turned by a random phi_h (an isotropic BRDF does not see it; an
  anisotropic model sees both tangent directions), weighted by its cell's measure
  (``merl.measure``);
- RGL: the nodes of the adapted grid of every incidence (``rgl.samples``, read from the
  tables: exactly what Mitsuba's ``measured`` returns there), weighted by the solid angle
  each node stands for times that of its incidence's band, an isotropic file's turned by a
  random azimuth (as MERL's); a spectral file's values are
  turned into linear sRGB (``srgb_matrix``: CIE 1931 under D65, as Mitsuba's
  ``spectrum_list_to_srgb``), as its RGB twin holds them. Negative values (out-of-gamut
  colours) are kept: docs/measured.md shows why;
- a BSDF: MERL's bins at its resolution (the pairs crowd around the highlight, however
  sharp), the BSDF evaluated there.

The energy term's rows (``fitting.ALBEDO_THETAS``, the data's albedo integrated over the
outgoing directions, the model at directions where the data's values stand, so that a
file's own model has the file's albedo exactly): MERL: a quadrature of the outgoing
directions each looked up in its bin as MERL's reader does, the model at the bins'
centres; RGL: the nodes of the file's incidences within 80 deg; a BSDF: the quadrature
itself. The albedo the constraint and the report compare (``reference``) is the data's by
a finer quadrature: MERL's bins looked up (the model at their centres, like with like),
Mitsuba's ``measured`` on the RGL file (a spectral one turned into RGB first), the BSDF;
the model's by the same quadrature.

``refuse_values`` refuses (one line) a black file or values beyond any BRDF's.
"""
import math
import os

import numpy as np

__all__ = ["SAMPLES", "HOLDOUT", "WEIGHTS", "MAX_ALBEDO", "Measured", "prepare", "rgb_file",
           "prepare_bsdf", "srgb_matrix", "refuse_values"]

#: default number of measured pairs of the shape term
SAMPLES = 20_000
#: held-out pairs (at most; a fifth of the usable ones where they are few)
HOLDOUT = 5000
WEIGHTS = ("solid-angle", "bins")
#: a file whose directional albedo exceeds this somewhere is refused: not a BRDF's values
MAX_ALBEDO = 3.0
#: resolution of the quadrature of the data's own albedo (``fitting.albedo_quadrature``)
_REFERENCE_N = 32
#: azimuth (radians) of the albedo's incidences
_PHI = 0.7


class Measured:
    """What a fit needs of measured data: the shape term's samples (wi, wo, f, weights),
    the held-out samples (``holdout``: the same four), the energy term's rows (``albedo``:
    ``fitting.fit``'s), how many samples within 80 deg there are (``bins``), the file's
    ``dims`` (MERL) or None, ``kind`` ("merl", "rgl", "bsdf"), a ``description``, the
    count of negative values (``negative``), ``evaluate(wi, wo)``: the data's f at any
    direction pairs (for plots; MERL: looked up as its reader does) and whether the data
    are isotropic (``isotropic``: a MERL file, an RGL file of one azimuth of incidence, a
    BSDF unchanged when both directions turn about the normal)."""

    def __init__(self, wi, wo, f, weights, albedo, bins, dims=None, holdout=None,
                 kind="merl", description="", negative=0, evaluate=None, isotropic=True):
        self.wi, self.wo, self.f, self.weights = wi, wo, f, weights
        self.albedo, self.bins, self.dims = albedo, bins, dims
        self.holdout, self.kind, self.description = holdout, kind, description
        self.negative, self.evaluate, self.isotropic = negative, evaluate, isotropic


def _split(rng, usable, samples, holdout):
    """(fit, held-out) indices: disjoint random subsets of ``usable``."""
    held = min(holdout, len(usable) // 5)
    order = rng.permutation(usable)
    return np.sort(order[held:held + samples]), np.sort(order[:held])


def _check_weights(weights):
    if weights not in WEIGHTS:
        raise ValueError(f"--weights must be one of {', '.join(WEIGHTS)} (got {weights!r})")


def prepare(path, samples=SAMPLES, seed=0, weights="solid-angle", position="centre",
            holdout=HOLDOUT):
    """The ``Measured`` data of a MERL or an RGL file (``reader.kind``; ``FormatError``
    for anything else). ``position``: where a MERL bin's sample is (``merl.POSITIONS``;
    the centre of its cell, what the value stands for)."""
    from .merl import kind
    _check_weights(weights)
    if kind(path) == "rgl":
        return _prepare_rgl(os.fspath(path), samples, seed, weights, holdout)
    from . import merl
    dims, f = merl.read(path)
    return _prepare_bins(dims, lambda index, wi, wo: f[index], seed, samples, holdout,
                         weights, position, table=f, kind="merl",
                         description=f"MERL {os.path.basename(os.fspath(path))}")


def prepare_bsdf(bsdf, name="", samples=SAMPLES, seed=0, weights="solid-angle",
                 holdout=HOLDOUT):
    """The ``Measured`` data of a loaded BSDF (RGB variant): MERL's bins at its resolution,
    the BSDF evaluated at their centres."""
    from . import merl
    from ..validate.probe import eval_np
    _check_weights(weights)

    def brdf(wi, wo):
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.asarray(eval_np(bsdf, wi, wo), float) / wo[:, 2:3]

    from .evaluators import bsdf_evaluator, is_isotropic
    data = _prepare_bins(merl.DIMS, lambda index, wi, wo: brdf(wi, wo), seed, samples,
                         holdout, weights, "centre",
                         evaluate=brdf, kind="bsdf", description=name)
    data.isotropic = is_isotropic(bsdf_evaluator(bsdf))
    return data


def _prepare_bins(dims, values, seed, samples, holdout, weights, position, table=None,
                  evaluate=None, kind="merl", description=""):
    """MERL's bins as ``Measured`` data: ``values(index, wi, wo)`` gives f of the bins at
    their directions; ``table`` (a file's f in bin order) or ``evaluate`` (f anywhere)."""
    from . import merl
    from .fitting import ALBEDO_THETAS, MIN_COS, albedo_of, albedo_quadrature
    rng = np.random.default_rng(seed)
    # the bins worth fitting: measured, both directions within 80 deg (a rotation about
    # the normal changes neither)
    wi, wo = merl.directions(dims, position=position)
    ok = (wi[:, 2] > MIN_COS) & (wo[:, 2] > MIN_COS)
    if table is not None:
        ok &= np.isfinite(table).all(1)
    usable = np.nonzero(ok)[0]
    del wi, wo, ok
    chosen, held = _split(rng, usable, samples, holdout)

    def pairs(index):
        wi, wo = merl.directions(dims, rng.uniform(0, 2 * np.pi, len(index)), index, position)
        f = values(index, wi, wo)
        w = merl.measure(dims, index) if weights == "solid-angle" else np.ones(len(index))
        keep = np.isfinite(f).all(1)
        return wi[keep], wo[keep], f[keep], w[keep]

    rows = albedo_quadrature(ALBEDO_THETAS, phi=_PHI)
    shape = rows["weight"].shape
    qwi, qwo = rows["wi"].reshape(-1, 3), rows["wo"].reshape(-1, 3)
    if table is not None:
        # the energy term: each direction of the quadrature looked up in its bin as MERL's
        # reader does, the model evaluated where the file's values stand (the bin's
        # centre, turned to the quadrature's phi_h): a file's own model has the file's
        # albedo exactly
        index = merl.lookup(qwi, qwo, dims)
        h = qwi + qwo
        cwi, cwo = merl.directions(dims, np.arctan2(h[:, 1], h[:, 0]), index, position)
        albedo = {"wi": cwi.reshape(shape + (3,)), "wo": cwo.reshape(shape + (3,)),
                  "weight": rows["weight"], "f": table[index].reshape(shape + (3,))}
        # the albedo the constraint and the report compare: a finer quadrature, looked up
        # likewise, and the model at the same bins' centres (like with like: a sharp lobe
        # point-sampled at the centres and read back bin by bin has another albedo than
        # its own, 7% more for Ward alpha 0.005 at MERL's resolution, and so has a model
        # of the same lobe)
        fine = albedo_quadrature(ALBEDO_THETAS, n=_REFERENCE_N, phi=_PHI)
        fwi, fwo = fine["wi"].reshape(-1, 3), fine["wo"].reshape(-1, 3)
        index = merl.lookup(fwi, fwo, dims)
        fine["f"] = table[index].reshape(fine["weight"].shape + (3,))
        albedo["reference"] = albedo_of(fine)
        h = fwi + fwo
        mwi, mwo = merl.directions(dims, np.arctan2(h[:, 1], h[:, 0]), index, position)
        albedo["model"] = {"wi": mwi.reshape(fine["wi"].shape),
                           "wo": mwo.reshape(fine["wo"].shape), "weight": fine["weight"]}
        evaluate = _merl_lookup(table, dims)
    else:
        albedo = dict(rows, f=evaluate(qwi, qwo).reshape(shape + (3,)))
    albedo["thetas"] = list(ALBEDO_THETAS)
    return Measured(*pairs(chosen), albedo, len(usable), dims, holdout=pairs(held),
                    kind=kind, description=description, evaluate=evaluate)


def _merl_lookup(table, dims):
    """f of a MERL table at any direction pairs, as MERL's reader finds it (NaN where not
    measured or below the horizon)."""
    from . import merl

    def evaluate(wi, wo):
        wi, wo = np.asarray(wi, float), np.asarray(wo, float)
        out = np.full((len(wi), 3), np.nan)
        up = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        out[up] = table[merl.lookup(wi[up], wo[up], dims)]
        return out
    return evaluate


# -- RGL files ---------------------------------------------------------------------------

def srgb_matrix(wavelengths):
    """The (3, n) matrix from values at ``wavelengths`` (nm) to linear sRGB: CIE 1931 under
    D65, the spectrum linearly interpolated between the wavelengths and integrated as
    Mitsuba's ``spectrum_list_to_srgb`` does it (1000 steps over the CIE range), unbounded
    and linear: that function clamps negative channels at 0, which a single wavelength's
    colour nearly always has, so it is not called per wavelength."""
    import mitsuba as mi
    wl = np.asarray([float(w) for w in wavelengths])
    lo, hi = float(mi.MI_CIE_MIN), float(mi.MI_CIE_MAX)
    steps = 1000
    w = lo + np.arange(steps) / (steps - 1) * (hi - lo)
    w = w[(w >= wl[0]) & (w <= wl[-1])]
    out = np.zeros((3, len(wl)))
    if len(wl) < 2 or not len(w):
        return out
    # the hat function of each wavelength at w (the linear interpolant's weights)
    i = np.clip(np.searchsorted(wl, w, side="right") - 1, 0, len(wl) - 2)
    t = (w - wl[i]) / (wl[i + 1] - wl[i])
    xyz = np.array(mi.cie1931_xyz(mi.Float(w)), dtype=np.float64).reshape(3, -1)
    xyz *= np.array(mi.cie_d65(mi.Float(w)), dtype=np.float64).ravel()
    per_wavelength = np.zeros((3, len(wl)))
    for c in range(3):
        per_wavelength[c] = np.bincount(i, xyz[c] * (1 - t), len(wl)) \
            + np.bincount(i + 1, xyz[c] * t, len(wl))
    # Python's cie1931_xyz leaves out the C++ one's normalisation of Y (a white of luminance 1)
    per_wavelength *= (hi - lo) / steps * float(mi.MI_CIE_Y_NORMALIZATION)
    to_srgb = np.array([np.array(mi.xyz_to_srgb(mi.ScalarColor3f(*e)), dtype=np.float64)
                        .ravel() for e in np.eye(3)]).T
    return to_srgb @ per_wavelength


def rgb_file(material, folder):
    """The path of an RGL file of ``material`` in RGB: the file itself, or for a spectral
    one a copy with its spectra turned into linear sRGB, written into ``folder``."""
    from . import tensor
    if not material.spectral:
        return material.path
    m = srgb_matrix(material.wavelengths)
    fields = {k: v for k, v in material.fields.items() if k not in ("spectra", "wavelengths")}
    fields["rgb"] = np.einsum("cl,abl...->abc...", m, material.fields["spectra"].astype(
        float)).astype(np.float32)
    path = os.path.join(folder, "rgb.bsdf")
    tensor.write(path, fields)
    return path


def _incidence_bands(theta, phi, isotropic):
    """The solid angle of incident directions each incidence (phi_i[k], theta_i[l])
    stands for: the band between the midpoints of its neighbours (of its azimuth's
    sector for an anisotropic file), (n_phi, n_theta)."""
    edges = np.concatenate([[0.0], (theta[1:] + theta[:-1]) / 2, [np.pi / 2]])
    band = 2 * np.pi * (np.cos(np.minimum(edges[:-1], np.pi / 2)) - np.cos(edges[1:]))
    if isotropic or len(phi) < 2:
        return band[None, :] * np.ones((len(phi), 1))
    p = np.concatenate([[phi[0]], (phi[1:] + phi[:-1]) / 2, [phi[-1]]])
    return (np.diff(p) / (2 * np.pi))[:, None] * band[None, :]


def _prepare_rgl(path, samples, seed, weights, holdout):
    import tempfile
    import mitsuba as mi
    from . import rgl
    from .fitting import ALBEDO_THETAS, MIN_COS, albedo_of, albedo_quadrature, select
    from ..validate.probe import eval_np
    material = rgl.load(path)
    s = rgl.samples(material)
    value = s.value
    if material.spectral:
        value = value @ srgb_matrix(material.wavelengths).T
    rng = np.random.default_rng(seed)
    usable = np.nonzero(select(s.wi, s.wo, value, MIN_COS))[0]
    if weights == "solid-angle":
        band = _incidence_bands(material.theta_i, material.phi_i, material.isotropic)
        w = s.solid_angle * band[s.phi_index, s.incidence]
    else:
        w = np.ones(len(value))
    chosen, held = _split(rng, usable, samples, holdout)
    # an isotropic file's pairs turned about the normal by a random azimuth each, as
    # MERL's are (its incidences all lie in the plane y = 0, which an anisotropic model
    # would otherwise see from one side only)
    turn = rng.uniform(0, 2 * np.pi, len(value)) if material.isotropic else np.zeros(
        len(value))
    pick = lambda i: (_turn(s.wi[i], turn[i]), _turn(s.wo[i], turn[i]), value[i], w[i])
    # the energy term's rows: the nodes of each incidence within 80 deg (of the azimuth
    # nearest the quadrature's), weighted by their solid angles
    k = int(np.argmin(np.abs(np.angle(np.exp(1j * (material.phi_i - _PHI))))))
    ls = [l for l in range(len(material.theta_i)) if math.cos(material.theta_i[l]) > MIN_COS]
    groups = [np.nonzero((s.incidence == l) & (s.phi_index == k))[0] for l in ls]
    groups = [g for g in groups if len(g)]
    width = max(len(g) for g in groups)
    rows = {"wi": np.zeros((len(groups), width, 3)), "wo": np.zeros((len(groups), width, 3)),
            "weight": np.zeros((len(groups), width)), "f": np.zeros((len(groups), width, 3))}
    rows["wi"][..., 2] = rows["wo"][..., 2] = 1
    for r, g in enumerate(groups):
        rows["wi"][r, :len(g)], rows["wo"][r, :len(g)] = s.wi[g], s.wo[g]
        rows["weight"][r, :len(g)] = s.solid_angle[g] * s.wo[g, 2]
        rows["f"][r, :len(g)] = value[g]
    # the data's albedo at the quadrature's incidences, and its values anywhere, through
    # Mitsuba's measured (the file in RGB)
    with tempfile.TemporaryDirectory() as tmp:
        measured = mi.load_dict({"type": "measured",
                                 "filename": os.path.abspath(rgb_file(material, tmp))})

    def evaluate(wi, wo):
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.asarray(eval_np(measured, wi, wo), float) / np.asarray(wo)[:, 2:3]

    fine = albedo_quadrature(ALBEDO_THETAS, n=_REFERENCE_N, phi=_PHI)
    model = dict(fine)
    fine["f"] = evaluate(fine["wi"].reshape(-1, 3), fine["wo"].reshape(-1, 3)).reshape(
        fine["weight"].shape + (3,))
    rows.update(model=model, reference=albedo_of(fine), thetas=list(ALBEDO_THETAS))
    return Measured(*pick(chosen), rows, len(usable), None, holdout=pick(held), kind="rgl",
                    description=material.description or os.path.basename(path),
                    negative=int((value < 0).sum()), evaluate=evaluate,
                    isotropic=material.isotropic)


def _turn(v, angle):
    """Directions (n, 3) turned about the normal by ``angle`` (n,)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1], v[:, 2]], -1)


def refuse_values(name, data):
    """ValueError (one line) where the data's albedo is beyond any BRDF's, or 0."""
    from .fitting import ALBEDO_THETAS
    if not np.any(data.f > 0):
        raise ValueError(f"{name}: every measured value within 80 deg is 0 or less: a black "
                         f"material, nothing to fit")
    a = np.asarray(data.albedo["reference"], float) if "reference" in data.albedo else None
    if a is None:
        from .fitting import albedo_of
        a = albedo_of(data.albedo)
    if np.nanmax(a) > MAX_ALBEDO:
        i, c = np.unravel_index(np.nanargmax(a), a.shape)
        fmax = np.nanmax(data.f)
        hint = ("; a MERL file holds f times 1500 (red), 1500/1.15 (green), 1500/1.66 "
                "(blue)" if data.kind == "merl" else "")
        raise ValueError(
            f"{name}: reflects {a[i, c]:.3g} times the light it receives at "
            f"{ALBEDO_THETAS[i]} deg ({'RGB'[c]}; values up to {fmax:.3g}): a BRDF "
            f"reflects at most 1{hint}")
