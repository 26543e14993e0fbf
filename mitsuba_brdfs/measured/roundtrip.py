"""How close a written RGL file comes to its source: directional albedo and eval.

Both are functions eval(wi, wo) -> (n, C) on NumPy directions (``sources``). The albedo at
theta_i (at three azimuths, the worst reported) is the integral of eval over the
hemisphere, by the half-vector quadrature of ``validate.directions.half_vector_sphere``
(its cells shrink towards the mirror direction, so sharp lobes are resolved at every
incidence); its errors are relative per channel (``FLOOR``). The eval comparison is made
where the source reflects: at each incidence of ``EVAL_THETAS`` and 4 azimuths, outgoing
directions are drawn from the quadrature's cells with probability proportional to the
energy the source sends there (luminance of eval times solid angle), and the relative
error of the luminance |written - source| / source is taken over all of them: ``median``
and the share within 10 %.
"""
import functools

import numpy as np

from ..validate.directions import half_vector_sphere, sph
from .acquire import luminance

__all__ = ["ALBEDO_THETAS", "ALBEDO_PHIS", "GRAZING_BOUNDS", "NEAR_NORMAL", "EVAL_THETAS",
           "FLOOR", "bound", "quadrature_albedo", "compare"]

#: incidences (degrees) of the albedo comparison, each at these azimuths (radians; the
#: worst is reported): an anisotropic source's albedo depends on the azimuth. Up to 88
#: deg: near the horizon a lobe that is not microfacet-shaped is the hardest to hold
ALBEDO_THETAS = (0, 45, 70, 80, 85, 88)
#: the albedo error a written file is held to near the horizon (theta in degrees: bound);
#: up to 70 deg, ``NEAR_NORMAL``
GRAZING_BOUNDS = {80: 0.05, 85: 0.05, 88: 0.10}
NEAR_NORMAL = 0.03
ALBEDO_PHIS = (0.0, 0.9, 2.1)
#: a channel's albedo error is relative to its albedo, or to this fraction of the
#: brightest channel's where that is larger (a channel near 0, as the blue of a saturated
#: yellow, has no meaningful relative error)
FLOOR = 0.1
#: incidences (degrees) of the eval comparison
EVAL_THETAS = (0, 15, 30, 45, 60, 70, 80)


def bound(theta, near_normal=NEAR_NORMAL):
    """The albedo error allowed at incidence ``theta`` (degrees, or its string):
    ``GRAZING_BOUNDS`` near the horizon, ``near_normal`` below 80 deg."""
    return GRAZING_BOUNDS.get(int(float(theta)), near_normal)


@functools.lru_cache(maxsize=256)
def _cells(theta, phi=0.0, n=96):
    """(wi, the quadrature's outgoing directions above the horizon, their solid angles),
    read-only: the same for every comparison, so computed once."""
    wi = sph(np.radians(theta), phi)[0]
    wo, dw = half_vector_sphere(n, wi)
    keep = wo[:, 2] > 0
    out = wi, wo[keep], dw[keep]
    for a in out:
        a.flags.writeable = False
    return out


def quadrature_albedo(evaluate, theta, n=96, phi=0.0):
    """The directional albedo (C,) of ``evaluate`` at theta degrees (azimuth phi)."""
    wi, wo, dw = _cells(theta, phi, n)
    e = np.asarray(evaluate(np.broadcast_to(wi, wo.shape), wo), float)
    return (e * dw[:, None]).sum(0)


def compare(source, written, samples=2000, seed=0, n=96, phis=ALBEDO_PHIS):
    """{albedo: {theta: (source (C,), written (C,), largest relative error over
    channels)} (at the azimuth of ``phis`` where it is largest: one azimuth is enough
    for an isotropic source), eval_median, eval_within_10, pairs}: how ``written``
    reproduces ``source``."""
    rng = np.random.default_rng(seed)
    out = {"albedo": {}}
    for theta in ALBEDO_THETAS:
        worst = None
        for phi in phis:
            wi, wo, dw = _cells(theta, phi, n)      # one quadrature for both
            a, b = ((np.asarray(f(np.broadcast_to(wi, wo.shape), wo), float)
                     * dw[:, None]).sum(0) for f in (source, written))
            scale = np.maximum(np.abs(a), FLOOR * np.abs(a).max())
            rel = float((np.abs(b - a) / np.maximum(scale, 1e-12)).max())
            if worst is None or rel > worst[2]:
                worst = (a, b, rel)
        out["albedo"][theta] = worst
    wis, wos = [], []
    for theta in EVAL_THETAS:
        for phi in (0.0, 0.9, 2.1, 4.0):
            wi, wo, dw = _cells(theta, phi, n)
            energy = np.maximum(luminance(source(np.broadcast_to(wi, wo.shape), wo)), 0) * dw
            if not energy.sum() > 0:
                continue
            pick = rng.choice(len(wo), size=samples // 4, p=energy / energy.sum())
            wis.append(np.broadcast_to(wi, (len(pick), 3)))
            wos.append(wo[pick])
    wi, wo = np.concatenate(wis), np.concatenate(wos)
    a, b = luminance(source(wi, wo)), luminance(written(wi, wo))
    rel = np.abs(b - a) / np.maximum(a, 1e-12)
    out.update(eval_median=float(np.median(rel)), eval_within_10=float((rel <= 0.1).mean()),
               pairs=len(rel))
    return out
