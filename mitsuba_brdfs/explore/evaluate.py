"""The data of the explorer's plots, measured with the BSDF's own ``eval`` and ``sample``,
called as Mitsuba's integrators call them (``validate.probe``: with the ``active`` mask).

Every plot of one BSDF comes from one batch: the directions of all plots are concatenated
and evaluated by one ``eval`` call (one kernel), and the sample-weight means of the albedo
by one ``sample`` call. The grids keep their sizes between calls and the BSDF's parameters
are opaque, so after a parameter change both kernels come from Dr.Jit's cache.

Angles are in degrees. Directions are local (n = z); ``si.wi`` is the incident direction
of the plots, in the plane x-z on the side x < 0, so that a mirror lobe points to x > 0.
Plotted values are luminance (Rec. 709 weights of RGB; the mean of the channels in other
variants): ``eval`` (f cos theta_o) in the plane of incidence and in 3D, f = eval /
cos theta_o in the (theta_h, theta_d) slices of Rusinkiewicz's parametrisation (phi_h = 0,
phi_d = 90 degrees, as Disney's BRDF Explorer shows them), the directional albedo by
quadrature of eval and as the mean sample weight with its standard error.
"""
import functools
import math

import drjit as dr
import mitsuba as mi
import numpy as np

from ..output import tonemap
from ..validate.directions import half_vector_sphere, lobe_sphere, sph
from ..validate.probe import call_eval, call_sample, interaction, rows, vec

__all__ = ["Grids", "GRIDS", "PARTS", "rusinkiewicz", "evaluate"]


class Grids:
    """Sizes of the plots' grids (kept fixed: the batch's shape then does not change)."""

    def __init__(self, polar=361, lobe=(19, 37), slice=91, image=64, albedo_step=5,
                 quad=24, samples=2048):
        self.polar, self.lobe, self.slice, self.image = polar, lobe, slice, image
        self.albedo = np.concatenate([np.arange(0, 90, albedo_step), [89.0]]).astype(float)
        self.quad, self.samples = quad, samples


GRIDS = Grids()
#: the plots, in the order of the batch
PARTS = ("polar", "lobe", "theta_h", "theta_d", "image", "albedo")
_PHI_D = math.radians(90)


def rusinkiewicz(theta_h, theta_d, phi_d=_PHI_D):
    """(wi, wo) of half-vector angles theta_h (phi_h = 0) and difference angles theta_d,
    phi_d (radians, broadcast together)."""
    th, td, pd = np.broadcast_arrays(*(np.asarray(x, float).ravel() for x in
                                       (theta_h, theta_d, phi_d)))
    d = sph(td, pd)
    c, s = np.cos(th), np.sin(th)  # rotate d from h's frame: about y by theta_h
    wi = np.stack([d[:, 0] * c + d[:, 2] * s, d[:, 1], -d[:, 0] * s + d[:, 2] * c], axis=-1)
    h = np.stack([s, np.zeros_like(s), c], axis=-1)
    wo = 2 * np.sum(wi * h, axis=-1, keepdims=True) * h - wi
    return wi, wo


@functools.lru_cache(maxsize=8)
def _inputs(theta_i, theta_h, theta_d, grids, transmits, parts, variant):
    """``_batch`` and its directions as evaluated Dr.Jit arrays: the same for every BSDF of
    a request (kept for the last few angles)."""
    wi, wo, cut, quad = _batch(theta_i, theta_h, theta_d, grids, transmits, parts)
    si, v = interaction(vec(wi)), vec(wo)
    dr.eval(si, v)  # the inputs apart: the kernel of eval then holds eval only
    return wi, wo, cut, quad, si, v


@functools.lru_cache(maxsize=2)
def _sample_interaction(grids, variant):
    """The interaction of the albedo's samples: ``grids.samples`` at each incidence."""
    wis = sph(np.radians(grids.albedo), np.pi)
    si = interaction(vec(np.repeat(wis, grids.samples, axis=0)))
    dr.eval(si)
    return si


def _sample(bsdf, grids, seed):
    """The sample weights of the albedo's samples, as (incidences x samples, C)."""
    si = _sample_interaction(grids, mi.variant())
    n = dr.width(si.wi)
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(seed, n)
    _, weight = call_sample(bsdf, mi.BSDFContext(), si, sampler.next_1d(), sampler.next_2d())
    return rows(weight, n, channels=True)


def _luminance(f):
    """(N, C) -> (N,)."""
    if f.shape[1] == 3 and not mi.is_spectral:
        return f @ np.array([0.2126, 0.7152, 0.0722])
    return f.mean(axis=1)


def _transmits(bsdf):
    return bool(bsdf.flags() & mi.BSDFFlags.Transmission)


@functools.lru_cache(maxsize=8)
def _quadrature_cells(grids, transmits):
    """Directions wi (one per albedo incidence) and the cells (wo, solid angle, which wi);
    the same for every call with these grids (kept)."""
    wis = sph(np.radians(grids.albedo), np.pi)
    wo, dw, which = [], [], []
    for k, wi in enumerate(wis):
        d, a = half_vector_sphere(grids.quad, wi)
        keep = d[:, 2] > 0
        d, a = d[keep], a[keep]
        if transmits:
            t, b = lobe_sphere(grids.quad, wi * [1, 1, -1])
            d, a = np.concatenate([d, t[t[:, 2] < 0]]), np.concatenate([a, b[t[:, 2] < 0]])
        wo.append(d)
        dw.append(a)
        which.append(np.full(len(d), k))
    return wis, np.concatenate(wo), np.concatenate(dw), np.concatenate(which)


def _batch(theta_i, theta_h, theta_d, grids, transmits, parts):
    """The (wi, wo) of the plots named in ``parts``, and the slice of the batch each takes;
    with the albedo, its quadrature cells (solid angle, incidence index)."""
    wi0 = sph(math.radians(theta_i), np.pi)
    dirs, quad = {}, None
    if "polar" in parts:
        t = np.radians(np.linspace(-90, 90, grids.polar))
        polar = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)
        dirs["polar"] = (np.repeat(wi0, len(polar), 0), polar)
    if "lobe" in parts:
        lt = np.radians(np.linspace(0, 90, grids.lobe[0]))
        lp = np.radians(np.linspace(0, 360, grids.lobe[1]))
        lobe = sph(*np.meshgrid(lt, lp, indexing="ij"))
        dirs["lobe"] = (np.repeat(wi0, len(lobe), 0), lobe)
    s = np.radians(_slice_x(grids))
    if "theta_h" in parts:
        dirs["theta_h"] = rusinkiewicz(s, math.radians(theta_d))
    if "theta_d" in parts:
        dirs["theta_d"] = rusinkiewicz(math.radians(theta_h), s)
    if "image" in parts:
        g = np.radians((np.arange(grids.image) + 0.5) * 90 / grids.image)
        tdg, thg = np.meshgrid(g, g, indexing="ij")  # rows: theta_d, columns: theta_h
        dirs["image"] = rusinkiewicz(thg, tdg)
    if "albedo" in parts:
        q_wi, q_wo, q_dw, q_which = _quadrature_cells(grids, transmits)
        dirs["quad"] = (q_wi[q_which], q_wo)
        quad = (q_dw, q_which)
    cut, start = {}, 0
    for name, (a, _) in dirs.items():
        cut[name] = slice(start, start + len(a))
        start += len(a)
    wi = np.concatenate([p[0] for p in dirs.values()])
    wo = np.concatenate([p[1] for p in dirs.values()])
    return wi, wo, cut, quad


def _slice_x(grids):
    """theta_h or theta_d of the slices (degrees), short of 90, where f = eval / cos is a
    ratio of two zeros."""
    return np.linspace(0, 89.5, grids.slice)


def _listed(x, digits=6):
    """NumPy values as a JSON list of ``digits`` significant digits (non-finite: None)."""
    return [float(f"{v:.{digits}g}") if math.isfinite(v) else None
            for v in np.asarray(x, float).ravel().tolist()]


def evaluate(bsdf, theta_i=45.0, theta_h=30.0, theta_d=30.0, exposure=0.0, grids=GRIDS,
             seed=0, parts=PARTS):
    """The data of the plots named in ``parts`` (default: all) for one BSDF, as JSON-ready
    lists (see the module docstring)."""
    parts = tuple(p for p in PARTS if p in parts)
    transmits = _transmits(bsdf)
    wi, wo, cut, quad_cells, si, v = _inputs(float(theta_i), float(theta_h), float(theta_d),
                                             grids, transmits, parts, mi.variant())
    f = np.asarray(rows(call_eval(bsdf, mi.BSDFContext(), si, v), len(wi), channels=True),
                   float)
    y = _luminance(f)
    cos_o = wo[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        brdf = np.where(((cos_o > 0) & (wi[:, 2] > 0))[:, None], f / cos_o[:, None], np.nan)
    out = {}
    if "polar" in parts:
        out["polar"] = {"theta": _listed(np.linspace(-90, 90, grids.polar), 3),
                        "value": _listed(y[cut["polar"]])}
    if "lobe" in parts:
        lobe = y[cut["lobe"]].reshape(grids.lobe)
        out["lobe"] = {"theta": _listed(np.linspace(0, 90, grids.lobe[0]), 3),
                       "phi": _listed(np.linspace(0, 360, grids.lobe[1]), 3),
                       "value": [_listed(r) for r in lobe]}
    for name in ("theta_h", "theta_d"):
        if name in parts:
            out[name] = {"x": _listed(_slice_x(grids), 3),
                         "value": _listed(_luminance(brdf[cut[name]]))}
    if "image" in parts:
        image = brdf[cut["image"]].reshape(grids.image, grids.image, -1)
        if image.shape[2] != 3:
            image = np.repeat(image.mean(axis=2, keepdims=True), 3, axis=2)
        # row 0: theta_d = 0
        out["image"] = tonemap(np.nan_to_num(image) * math.pi, exposure).tolist()
    if "albedo" in parts:
        q_dw, q_which = quad_cells
        n_alb = len(grids.albedo)
        quad = np.zeros((n_alb, f.shape[1]))
        np.add.at(quad, q_which, f[cut["quad"]] * q_dw[:, None])
        w = _luminance(np.asarray(_sample(bsdf, grids, seed), float)).reshape(
            n_alb, grids.samples)
        out["albedo"] = {"theta": _listed(grids.albedo, 3),
                         "quadrature": _listed(_luminance(quad)),
                         "mean": _listed(w.mean(axis=1)),
                         "stderr": _listed(w.std(axis=1) / math.sqrt(grids.samples)),
                         "samples": grids.samples}
    return out
