"""Direction sets for the checks: random, mirror pairs, hard cases, hemisphere quadrature.

Directions are local-frame unit vectors (n = z), NumPy arrays of shape (N, 3).
"""
import functools
import itertools

import numpy as np

__all__ = ["sph", "unit", "unit_f32", "random_upper", "random_pairs", "mirror_pairs",
           "eval_pairs", "diffuse_eval_pairs", "hard_directions", "nearly_opposite_grazing",
           "hard_pairs", "midpoint_hemisphere", "lobe_sphere",
           "half_vector_sphere"]


def sph(theta, phi):
    """Unit vectors from spherical angles (numpy, shape (N, 3))."""
    theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                     np.cos(theta)], axis=-1).reshape(-1, 3)


def unit(a):
    a = np.asarray(a, float)
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


def unit_f32(a):
    """The float32 directions the plugin sees, back in float64 (and renormalised)."""
    return unit(np.asarray(a, np.float32).astype(float))


def random_upper(rng, n):
    """Directions spread over the upper hemisphere, grazing ones included."""
    return sph(np.arccos(rng.uniform(0.001, 1, n)), rng.uniform(0, 2 * np.pi, n))


def random_pairs(seed, n):
    """n pairs (wi, wo) of random directions over the upper hemisphere."""
    rng = np.random.default_rng(seed)
    return random_upper(rng, n), random_upper(rng, n)


def mirror_pairs(n, seed, mirrors):
    """n random pairs, then `mirrors` exact mirror pairs (h = n) and the normal with itself."""
    wi, wo = random_pairs(seed, n)
    wi = np.concatenate([wi, wi[:mirrors], [[0, 0, 1]]])
    wo = np.concatenate([wo, wi[:mirrors] * [-1, -1, 1], [[0, 0, 1]]])
    return wi, wo


def eval_pairs(n=3000, seed=7):
    """mirror_pairs with 100 mirror pairs, as the float32 directions the plugin sees."""
    wi, wo = mirror_pairs(n, seed, mirrors=100)
    return unit_f32(wi), unit_f32(wo)


def hard_directions():
    eps = 1e-7
    g = np.sqrt(1 - eps * eps)
    d = np.array([
        [0, 0, 1],                                  # the normal (h = n with itself)
        [g, 0, eps], [0, g, eps], [-g, 0, eps],     # grazing, cos = 1e-7
        [1, 0, 0], [0, -1, 0],                      # exactly at the horizon
        [0.6, 0, 0.8], [-0.6, 0, 0.8],              # a mirror pair
        [0, 0.6, 0.8], [0, -0.6, 0.8],
        [0.3, 0.4, -np.sqrt(0.75)], [0, 0, -1],     # below the horizon
        [0.577, 0.577, 0.578],
    ], float)
    return unit(d)


def diffuse_eval_pairs(n=4000, seed=7):
    """n random pairs, then retro-reflection (wi = wo), forward scattering (mirror pairs),
    normal incidence and below-the-horizon pairs: the cases of a rough diffuse model."""
    rng = np.random.default_rng(seed)
    wi, wo = random_upper(rng, n), random_upper(rng, n)
    wi = np.concatenate([wi, wi[:100], wi[:100], [[0, 0, 1]] * 3, wi[:20]])
    wo = np.concatenate([wo, wi[:100], wi[:100] * [-1, -1, 1],
                         [[0, 0, 1], [0.6, 0, 0.8], [0, 0.6, 0.8]], wi[:20] * [1, 1, -1]])
    return wi, wo


def nearly_opposite_grazing(n, seed=0):
    """n pairs (wi, wo) of float32 directions (returned as float64), both 1e-8 .. 1e-2 rad
    above the horizon, with azimuths within 5e-3 of opposite (a tenth exactly opposite):
    |wi + wo| falls to ~1e-8, where a half vector taken through a dot product loses every
    digit (float32 directions are unit only to ~6e-8)."""
    rng = np.random.default_rng(seed)
    e1, e2 = 10 ** rng.uniform(-8, -2, n), 10 ** rng.uniform(-8, -2, n)
    phi = rng.uniform(0, 2 * np.pi, n)
    dphi = rng.uniform(-5e-3, 5e-3, n)
    dphi[: n // 10] = 0

    def direction(el, az):
        return np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], -1)

    wi = direction(e1, phi).astype(np.float32)
    wo = direction(e2, phi + np.pi + dphi).astype(np.float32)
    return wi.astype(float), wo.astype(float)


def hard_pairs(d, mirrored=None, opposite=200):
    """Every ordered pair (wi, wo) of the directions d, then wi = -wo for the first
    `mirrored` of them (all by default), then `opposite` nearly opposite grazing pairs
    (``nearly_opposite_grazing``) in both orders."""
    pairs = np.array(list(itertools.product(range(len(d)), repeat=2)))
    k = len(d) if mirrored is None else mirrored
    oi, oo = nearly_opposite_grazing(opposite)
    return (np.concatenate([d[pairs[:, 0]], -d[:k], oi, oo]),
            np.concatenate([d[pairs[:, 1]], d[:k], oo, oi]))


def midpoint_hemisphere(n):
    """Midpoint quadrature of the upper hemisphere (n polar, 2 n azimuthal cells): the
    directions and the solid angle of each cell."""
    t, p = (np.arange(n) + 0.5) * (np.pi / 2 / n), (np.arange(2 * n) + 0.5) * (np.pi / n)
    tt, pp = np.meshgrid(t, p, indexing="ij")
    return sph(tt.ravel(), pp.ravel()), np.sin(tt.ravel()) * (np.pi / 2 / n) * (np.pi / n)


def _edges(lo, hi, n, bands, fine):
    """Cell edges on [lo, hi]: n equal cells, cut `fine` times finer inside each band (a, b)."""
    edges = [np.linspace(lo, hi, n + 1)]
    h = (hi - lo) / n / fine
    for a, b in bands:
        a, b = max(a, lo), min(b, hi)
        if b > a:
            edges.append(np.linspace(a, b, int(np.ceil((b - a) / h)) + 1))
    return np.unique(np.concatenate(edges))


def _kept(function):
    """``function(n, wi, *rest)`` remembered for the last few dozen (n, wi, rest): the
    checks integrate every BSDF of a run over the same cells. The arrays it returns are
    read-only (shared by every caller)."""
    @functools.lru_cache(maxsize=64)
    def kept(n, wi, *rest, **kw):
        out = function(n, np.array(wi), *rest, **kw)
        for a in out:
            a.flags.writeable = False
        return out

    @functools.wraps(function)
    def call(n, wi, *rest, **kw):
        return kept(int(n), tuple(np.reshape(np.asarray(wi, float), 3).tolist()), *rest, **kw)
    return call


@_kept
def lobe_sphere(n, wi, fine=8, band=np.radians(10)):
    """Midpoint quadrature of the whole sphere for a BSDF lit from wi: n polar cells per
    hemisphere and 2 n azimuthal ones, made `fine` times finer where lobes are sharp, within
    `band` of the mirror direction (in theta and in phi) and of the horizon. Each cell's
    solid angle is exact. The lower hemisphere mirrors the upper one. Returns the
    directions (cell midpoints) and the solid angles."""
    wi = np.reshape(np.asarray(wi, float), 3)
    theta_m = np.arccos(min(abs(wi[2]), 1.0))
    phi_m = np.arctan2(wi[1], wi[0]) + np.pi
    t = _edges(0, np.pi / 2, n, [(theta_m - band, theta_m + band), (np.pi / 2 - band, np.pi / 2)],
               fine)
    p = _edges(phi_m - np.pi, phi_m + np.pi, 2 * n, [(phi_m - band, phi_m + band)], fine)
    tt, pp = np.meshgrid(0.5 * (t[1:] + t[:-1]), 0.5 * (p[1:] + p[:-1]), indexing="ij")
    dw = np.outer(np.cos(t[:-1]) - np.cos(t[1:]), np.diff(p)).ravel()
    d = sph(tt.ravel(), pp.ravel())
    return np.concatenate([d, d * [1, 1, -1]]), np.concatenate([dw, dw])


@_kept
def half_vector_sphere(n, wi):
    """Midpoint quadrature of the sphere of directions wo reflected from wi, over the half
    vector h (wo = 2 (wi.h) h - wi, d wo = 4 (wi.h) d h). h lies on a grid around the normal
    on wi's side whose polar cells shrink geometrically towards it, down to 1e-4 rad: a
    specular lobe is resolved however sharp it is and however grazing wi is (in wo it is
    squeezed by wi.h). n sets the resolution: about n geometric and 2 n even polar cells,
    2 n azimuthal ones. Returns the directions wo and their solid angles."""
    wi = np.reshape(np.asarray(wi, float), 3)
    t = np.unique(np.concatenate([[0.0], np.geomspace(1e-4, np.pi, n),
                                  np.linspace(0, np.pi, 2 * n + 1)]))
    p = np.linspace(-np.pi, np.pi, 2 * n + 1)
    tt, pp = np.meshgrid(0.5 * (t[1:] + t[:-1]), 0.5 * (p[1:] + p[:-1]), indexing="ij")
    dh = np.outer(np.cos(t[:-1]) - np.cos(t[1:]), np.diff(p)).ravel()
    h = sph(tt.ravel(), pp.ravel()) * (1 if wi[2] >= 0 else -1)  # finest at wi's normal
    c = h @ wi
    keep = c > 0
    h, c, dh = h[keep], c[keep], dh[keep]
    return unit(2 * c[:, None] * h - wi), 4 * c * dh
