"""A BSDF under test and how hard the suite looks at it: ``Settings`` and its presets
(``SETTINGS``), ``Subject`` (the BSDF, what its flags say, and the samples and quadratures
several checks share, computed once), and the helpers the checks read those through.
"""
import math
from dataclasses import dataclass

import mitsuba as mi
import numpy as np

from .directions import random_pairs, sph
from .energy import quadrature
from .results import flag_names
from .sampling import DIRAC, sample_record, weight_errors

__all__ = ["Settings", "SETTINGS", "Subject", "kept", "per_incidence", "quadratures",
           "incidence_quadratures", "mean_weights", "furnace_tolerance", "weights_ok"]


@dataclass(frozen=True)
class Settings:
    """How hard the suite looks; ``SETTINGS`` holds the three presets."""
    chi2_thetas: tuple = (0, 30, 60, 75, 85, 89)  #: incidences of the chi-square tests (deg)
    chi2_res: int = 161                   #: histogram rows, in cos(theta) (phi: half as many)
    chi2_ires: int = 64                   #: pdf integration points per cell and dimension
    chi2_samples: int = 1_000_000         #: samples per chi-square test
    thetas: tuple = (0, 20, 40, 60, 70, 80, 85, 89)  #: incidences of the other checks
    samples: int = 100_000                #: samples per incidence (weights, furnace)
    quad: int = 128                       #: quadrature: polar cells per hemisphere
    pairs: int = 20_000                   #: random direction pairs (reciprocity, components)
    component_thetas: tuple = (30, 75)    #: incidences of the component checks
    significance: float = 0.01            #: of all chi-square tests together
    weight_rtol: float = 1e-3             #: weight against eval / pdf, sample pdf against pdf
    eval_pdf_rtol: float = 1e-5           #: eval_pdf against (eval, pdf)
    reciprocity_rtol: float = 1e-3
    allow_gain: bool = False              #: an albedo above 1 is a NOTE, not a FAIL
    reciprocal: bool = False              #: a non-reciprocal BSDF FAILs (else: NOTE)


SETTINGS = {
    "quick": Settings(chi2_thetas=(30, 85), chi2_res=64, chi2_ires=16, chi2_samples=200_000,
                      thetas=(0, 45, 80, 89), samples=30_000, quad=64, pairs=4000,
                      component_thetas=(45,)),
    "default": Settings(),
    "thorough": Settings(chi2_thetas=(0, 20, 40, 60, 75, 85, 89), chi2_res=201, chi2_ires=64,
                         chi2_samples=4_000_000,
                         thetas=tuple(range(0, 90, 5)) + (87, 89, 89.9), samples=100_000,
                         quad=256, pairs=200_000, component_thetas=(0, 30, 60, 85)),
}


class Subject:
    """A BSDF under test, with what its flags say about it and the samples several checks
    share (drawn once)."""

    def __init__(self, bsdf, name, settings):
        F = mi.BSDFFlags
        self.bsdf, self.name, self.settings = bsdf, name, settings
        self.count = bsdf.component_count()
        self.components = [int(bsdf.flags(i)) for i in range(self.count)]
        self.flags = int(bsdf.flags())
        self.two_sided = bool(self.flags & int(F.BackSide))
        self.transmissive = bool(self.flags & int(F.Transmission))
        delta = DIRAC
        self.delta = [i for i, c in enumerate(self.components) if c & delta]
        self.cache = {}  #: what several checks share, computed once

    def describe(self):
        return ", ".join(f"[{i}] {flag_names(c)}" for i, c in enumerate(self.components))

    def thetas(self, thetas):
        """Incidences (degrees): thetas, and 180 - theta (from below) for a two-sided BSDF."""
        out = [float(t) for t in thetas]
        return out + [180.0 - t for t in out] if self.two_sided else out

    def context(self, **attrs):
        ctx = mi.BSDFContext()
        for k, v in attrs.items():
            setattr(ctx, k, v)
        return ctx

    def record(self, key="all", ctx=None, thetas=None):
        """``sampling.sample_record`` at every incidence (``settings.thetas`` by default),
        drawn once per key."""
        if key not in self.cache:
            th = self.thetas(self.settings.thetas if thetas is None else thetas)
            wis = np.concatenate([sph(np.radians(t), 0.3) for t in th])
            rec = sample_record(self.bsdf, wis, self.settings.samples, ctx=ctx)
            rec["thetas"] = th
            self.cache[key] = rec
        return self.cache[key]

    def pairs(self, n, seed=5):
        """n random pairs above the surface, and as many below for a two-sided BSDF."""
        a, b = random_pairs(seed, n)
        if self.two_sided:
            a, b = np.concatenate([a, -a]), np.concatenate([b, -b])
        return a, b


def kept(rec):
    """The samples a renderer keeps: a pdf > 0 or a delta lobe, and a non-zero weight."""
    return (rec["ok"] | rec["delta"]) & (np.abs(rec["weight"]).max(axis=1) > 0)


def per_incidence(rec, values):
    """values (one per sample of rec) split by incidence: shape (K, n, ...)."""
    k = len(rec["thetas"])
    return values.reshape((k, -1) + values.shape[1:])


def weights_ok(rec, e, rtol, atol):
    """Whether a ``weight_errors`` record e of rec passes, and how many samples it lets
    through: those off by less than 10 x rtol, when they are at most 1 in 100,000 (a
    float32 formula can lose a few digits where it is ill-conditioned, e.g. the half
    vector of a refraction near the critical angle)."""
    if e["weight"]["ok"] and e["pdf"]["ok"] and e["failed"]["ok"]:
        return True, 0
    loose = weight_errors(rec, 10 * rtol, 10 * rtol, atol, zero_weight_fails=True)
    off = e["weight"]["off"] + e["pdf"]["off"]
    if (loose["weight"]["ok"] and loose["pdf"]["ok"] and e["failed"]["ok"]
            and off <= max(1, 1e-5 * len(rec["ok"]))):
        return True, off
    return False, 0


def quadratures(s, thetas, ctx=None):
    """Quadratures of eval and pdf at the incidences thetas (degrees): lists of the eval
    integral, its error, the pdf integral, its error."""
    out = [quadrature(s.bsdf, sph(np.radians(t), 0.3)[0], s.settings.quad, ctx,
                      same_side=not s.transmissive) for t in thetas]
    return ([o[0][0] for o in out], [o[0][1] for o in out],
            [o[1][0] for o in out], [o[1][1] for o in out])


def incidence_quadratures(s):
    """``quadratures`` at the incidences of ``Subject.record()``, computed once."""
    if "quad" not in s.cache:
        s.cache["quad"] = quadratures(s, s.record()["thetas"])
    return s.cache["quad"]


def furnace_tolerance(err, q, qerr):
    """How far the mean weight (standard error err) may be from the quadrature q (error
    qerr): 5 standard errors, twice the quadrature's error, and 0.1% + 0.2% of q (a
    sampler biased by less is not worth a failure; the message still shows the gap)."""
    return 5 * err + 2 * qerr + 1e-3 + 2e-3 * np.abs(q)


def mean_weights(rec, smooth_only=False):
    """The mean sample weight of rec at each incidence (the Monte Carlo albedo; with
    ``smooth_only``, delta lobes left out) and its standard error."""
    w = rec["weight"] * (~rec["delta"])[:, None] if smooth_only else rec["weight"]
    w = per_incidence(rec, w)
    return w.mean(axis=1), w.std(axis=1) / math.sqrt(w.shape[1])
