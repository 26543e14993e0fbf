"""Scalar variants: the suite runs in the variant's JIT twin, and the scalar variant is
compared with it value by value.

The suite draws hundreds of thousands of samples per incidence; in a ``scalar_*`` variant
each is a Python call (a Python plugin: about 80 times slower than vectorised). So a BSDF
is checked in the JIT variant of the same colour mode (``scalar_rgb`` -> ``llvm_ad_rgb``,
``scalar_spectral_polarized`` -> ``llvm_ad_spectral_polarized``; the same plugin code,
traced) and ``compare`` then evaluates it in the scalar variant, one call at a time, on a
few hundred direction pairs (hard and random) and samples, and reports whether eval, pdf
and the samples agree with the JIT variant's."""
import drjit as dr
import mitsuba as mi
import numpy as np

from .directions import hard_directions, hard_pairs, random_pairs
from .probe import (WAVELENGTHS, call_eval, call_pdf, call_sample, floats, interaction, point2,
                    rows, unpolarized, vec)

__all__ = ["jit_twin", "probe_inputs", "ScalarError", "evaluate", "compare"]


def jit_twin(variant, available):
    """The JIT variant that checks a scalar one (None if this Mitsuba has none)."""
    for backend in ("llvm_ad_", "cuda_ad_"):
        twin = backend + variant.removeprefix("scalar_")
        if twin in available:
            return twin
    return None


def probe_inputs(n=200, seed=3):
    """Direction pairs (the hard ones without the nearly opposite grazing pairs, and n
    random ones, a quarter of them across the surface) and n samples (wi, sample1,
    sample2), as NumPy arrays."""
    d = hard_directions()
    wi, wo = hard_pairs(d, opposite=0)
    a, b = random_pairs(seed, n)
    b[: n // 4] *= [1, 1, -1]
    rng = np.random.default_rng(seed)
    s_wi, _ = random_pairs(seed + 1, n)
    return {"wi": np.concatenate([wi, a]), "wo": np.concatenate([wo, b]),
            "s_wi": np.concatenate([d, s_wi])[:n], "u1": rng.random(n), "u2": rng.random((n, 2))}


class ScalarError(RuntimeError):
    """A BSDF raised in a scalar variant: the first error of the chain and the call."""

    def __init__(self, e, where):
        while e.__cause__ is not None or e.__context__ is not None:
            e = e.__cause__ or e.__context__
        from ..messages import last_line
        super().__init__(f"{type(e).__name__}: {last_line(e)} ({where})")


def _r(v):
    return [round(float(c), 6) for c in np.ravel(v)]


def evaluate(bsdf, inputs):
    """eval, pdf and samples of bsdf at the inputs, in the active variant (vectorised in a
    JIT variant, one call at a time in a scalar one): NumPy arrays (unpolarized parts)."""
    ctx = mi.BSDFContext()
    if dr.is_jit_v(mi.Float):
        wi, wo, n = inputs["wi"], inputs["wo"], len(inputs["wi"])
        si, v = interaction(wi), vec(wo)
        out = {"eval": rows(call_eval(bsdf, ctx, si, v), n, True),
               "pdf": rows(call_pdf(bsdf, ctx, si, v), n)}
        m = len(inputs["u1"])
        u2 = inputs["u2"]
        bs, w = call_sample(bsdf, ctx, interaction(inputs["s_wi"]), floats(inputs["u1"]),
                            point2(u2[:, 0], u2[:, 1]))
        out.update(weight=rows(w, m, True), s_pdf=rows(bs.pdf, m), s_wo=rows(bs.wo, m))
        return out

    def si_at(wi):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(*map(float, wi))
        si.uv = mi.Point2f(0.5, 0.5)
        if mi.is_spectral:
            si.wavelengths = mi.UnpolarizedSpectrum(*WAVELENGTHS)
        return si

    def spectrum(x):
        return np.atleast_1d(np.array(unpolarized(x), float).ravel())

    f, p = [], []
    for a, b in zip(inputs["wi"], inputs["wo"]):
        si, v = si_at(a), mi.Vector3f(*map(float, b))
        try:
            f.append(spectrum(call_eval(bsdf, ctx, si, v)))
            p.append(float(call_pdf(bsdf, ctx, si, v)))
        except Exception as e:
            raise ScalarError(e, f"eval or pdf at wi = {_r(a)}, wo = {_r(b)}") from e
    w, s_pdf, s_wo = [], [], []
    for a, u1, u2 in zip(inputs["s_wi"], inputs["u1"], inputs["u2"]):
        try:
            bs, weight = call_sample(bsdf, ctx, si_at(a), float(u1), mi.Point2f(*map(float, u2)))
        except Exception as e:
            raise ScalarError(e, f"sample at wi = {_r(a)}, sample1 = {u1:.6g}, sample2 = "
                              f"{_r(u2)}") from e
        w.append(spectrum(weight))
        s_pdf.append(float(bs.pdf))
        s_wo.append(np.array(bs.wo, float).ravel())
    return {"eval": np.array(f), "pdf": np.array(p), "weight": np.array(w),
            "s_pdf": np.array(s_pdf), "s_wo": np.array(s_wo)}


def compare(jit, scalar, rtol=1e-4):
    """Where the scalar values differ from the JIT ones by more than rtol (relative, or to 1%
    of the largest value), or are NaN where the other is not: {quantity: (count, largest
    relative difference)}. What integrators read only: pdf where eval is not 0, a sample's
    pdf and direction where its weight is not 0 (see ``suite``'s docstring)."""
    out = {}
    used = (jit["weight"] != 0).any(axis=1) | (scalar["weight"] != 0).any(axis=1)
    lit = (jit["eval"] != 0).any(axis=1) | (scalar["eval"] != 0).any(axis=1)
    for key in ("eval", "pdf", "weight", "s_pdf", "s_wo"):
        a = np.asarray(jit[key], float).reshape(len(jit[key]), -1)
        b = np.asarray(scalar[key], float).reshape(len(a), -1)
        if key != "eval":
            keep = lit if key == "pdf" else used if key != "weight" else slice(None)
            a, b = a[keep], b[keep]
        scale = float(np.nanmax(np.abs(np.where(np.isinf(a), np.nan, a)), initial=0)) or 1.0
        with np.errstate(invalid="ignore"):
            diff = np.abs(a - b)
            same_nan = np.isnan(a) & np.isnan(b)
            same_inf = np.isinf(a) & (a == b)
            off = ~(same_nan | same_inf | (diff <= rtol * np.maximum(np.abs(a), scale * 1e-2)))
            rel = np.where(same_nan | same_inf, 0, diff / np.maximum(np.abs(a), scale * 1e-2))
        out[key] = (int(off.any(axis=1).sum()),
                    float(np.nan_to_num(rel, nan=np.inf).max(initial=0)))
    return out
