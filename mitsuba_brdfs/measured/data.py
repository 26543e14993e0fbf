"""What a fit of a measured file reads: ``prepare(path)`` gives a ``Measured``, the shape
term's samples (wi, wo, f, weights) and the energy term's rows (``fitting.fit``'s
``albedo``), from a MERL file.

The shape: a random subset (``samples``, fixed by ``seed``) of the measured bins with both
directions within 80 deg of the normal, each at the centre of its cell (what its value
stands for, ``merl.directions``), turned by a random phi_h (an isotropic BRDF does not see
it; an anisotropic model sees both tangent directions); each weighted by the measure of the
direction pairs its cell covers (``merl.measure``; ``weights="bins"``: every bin alike, as
Ngan et al. count them).

The energy: the directional albedo at incidence ``fitting.ALBEDO_THETAS``, integrated over
the outgoing directions where the file is measured (looked up as MERL's reader does,
``merl.lookup``), the model evaluated where those bins' values stand (so a file's own model
has the file's albedo exactly).

``refuse_values`` refuses (one line) a black file or values beyond any BRDF's.
"""
import numpy as np

__all__ = ["SAMPLES", "WEIGHTS", "MAX_ALBEDO", "Measured", "prepare", "refuse_values"]

#: default number of measured pairs of the shape term
SAMPLES = 20_000
WEIGHTS = ("solid-angle", "bins")
#: a file whose directional albedo exceeds this somewhere is refused: not a BRDF's values
MAX_ALBEDO = 3.0


class Measured:
    """What a fit needs of a measured file: the shape term's samples (wi, wo, f, weights),
    the energy term's rows (``albedo``: wi, wo, weight, f; ``fitting.fit``), the measured
    bins within 80 deg (``bins``) and the file's ``dims``."""

    def __init__(self, wi, wo, f, weights, albedo, bins, dims):
        self.wi, self.wo, self.f, self.weights = wi, wo, f, weights
        self.albedo, self.bins, self.dims = albedo, bins, dims


def prepare(path, samples=SAMPLES, seed=0, weights="solid-angle", position="centre"):
    """The ``Measured`` samples of a MERL file: ``samples`` of its measured bins within
    80 deg (all of them if fewer), float64, with their weights (``WEIGHTS``), and the
    energy term's rows. ``position``: where a bin's sample is (``merl.POSITIONS``; the
    centre of its cell, what the value stands for)."""
    from . import merl
    from .fitting import ALBEDO_THETAS, MIN_COS, albedo_quadrature
    if weights not in WEIGHTS:
        raise ValueError(f"--weights must be one of {', '.join(WEIGHTS)} (got {weights!r})")
    dims, f = merl.read(path)
    rng = np.random.default_rng(seed)
    # the bins worth fitting: measured, both directions within 80 deg (a rotation about
    # the normal changes neither)
    wi, wo = merl.directions(dims, position=position)
    usable = np.nonzero(np.isfinite(f).all(1) & (wi[:, 2] > MIN_COS) & (wo[:, 2] > MIN_COS))[0]
    del wi, wo
    bins = len(usable)
    chosen = np.sort(rng.permutation(usable)[:samples])
    wi, wo = merl.directions(dims, rng.uniform(0, 2 * np.pi, len(chosen)), chosen, position)
    w = merl.measure(dims, chosen) if weights == "solid-angle" else np.ones(len(chosen))
    # the energy term: a quadrature of the outgoing directions, each looked up in its bin
    # as MERL's reader does, the model evaluated where the file's values stand (the bin's
    # centre, turned to the quadrature's phi_h), so that a file's own model has the file's
    # albedo exactly
    rows = albedo_quadrature(ALBEDO_THETAS)
    qwi, qwo = rows["wi"].reshape(-1, 3), rows["wo"].reshape(-1, 3)
    index = merl.lookup(qwi, qwo, dims)
    h = qwi + qwo
    cwi, cwo = merl.directions(dims, np.arctan2(h[:, 1], h[:, 0]), index, position)
    shape = rows["weight"].shape
    albedo = {"wi": cwi.reshape(shape + (3,)), "wo": cwo.reshape(shape + (3,)),
              "weight": rows["weight"], "f": f[index].reshape(shape + (3,))}
    return Measured(wi, wo, f[chosen], w, albedo, bins, dims)


def refuse_values(path, data):
    """ValueError (one line) where the file's albedo is beyond any BRDF's."""
    from .fitting import ALBEDO_THETAS, albedo_of
    if not np.any(data.f > 0):
        raise ValueError(f"{path}: every measured value within 80 deg is 0: a black "
                         f"material, nothing to fit")
    a = albedo_of(data.albedo)
    if np.nanmax(a) > MAX_ALBEDO:
        i, c = np.unravel_index(np.nanargmax(a), a.shape)
        fmax = np.nanmax(data.f)
        raise ValueError(
            f"{path}: reflects {a[i, c]:.3g} times the light it receives at "
            f"{ALBEDO_THETAS[i]} deg ({'RGB'[c]}; values up to {fmax:.3g}): a BRDF "
            f"reflects at most 1; a MERL file holds f times 1500 (red), 1500/1.15 (green), "
            f"1500/1.66 (blue)")
