"""Stability: finite, non-negative values where the formulas are fragile (grazing and
horizon directions, the normal, mirror pairs, corner sample values), zero below the
horizon, finite gradients."""
import drjit as dr
import mitsuba as mi
import numpy as np

from .directions import hard_directions, hard_pairs, nearly_opposite_grazing
from .probe import bad_values, eval_np, expect, interaction, pdf_np, rows, to_np, vec

__all__ = ["CORNERS", "CORNERS_FINE", "corner_samples", "hard_cases", "check_zero_below_horizon",
           "check_eval_pdf_finite", "check_samples_finite", "check_finite_gradients"]

#: corner values of a sample dimension: 0, just above 0, the middle, the largest float32 below 1
CORNERS = np.array([0, 1e-7, 0.5, 1 - 2**-24])
CORNERS_FINE = np.array([0, 1e-7, 0.25, 0.5, 0.75, 1 - 2**-24])


def corner_samples(d, u1, u2):
    """Arguments (si, sample1, sample2) of BSDF.sample for every direction of d as wi with
    every combination of corner values: sample1 and sample2.x from u1, sample2.y from u2."""
    g1, g2, g3, gi = np.meshgrid(u1, u1, u2, np.arange(len(d)), indexing="ij")
    return interaction(d[gi.ravel()]), mi.Float(g1.ravel()), mi.Point2f(g2.ravel(), g3.ravel())


def hard_cases(bsdf, ctx=None):
    """The values of bsdf where formulas break: eval, pdf and eval_pdf at every pair of
    ``hard_pairs(hard_directions())`` (the normal, grazing and horizon directions, mirror
    pairs where h = n, directions below the horizon, nearly opposite grazing pairs), and
    samples at every corner value (``corner_samples``) with wi from the hard directions and
    from nearly opposite grazing ones. Returns, per quantity (``eval``, ``pdf``,
    ``eval_pdf``, ``weight``, ``sample_pdf``, ``wo``), how many values are NaN or infinite
    and how many negative; ``not_unit``: how many sampled directions of successful samples
    (pdf > 0) are not unit vectors; ``pairs`` and ``samples``: how many were tried;
    ``first``: the first bad value and where it is (or None); and ``bad_wi``: the incident
    directions with a bad value, most frequent first."""
    ctx = ctx or mi.BSDFContext()
    wi, wo = hard_pairs(hard_directions())
    si, v = interaction(wi), vec(wo)
    ep_f, ep_p = bsdf.eval_pdf(ctx, si, v)
    n = len(wi)
    at_pairs = {"eval": rows(bsdf.eval(ctx, si, v), n), "pdf": rows(bsdf.pdf(ctx, si, v), n),
                "eval_pdf": np.column_stack([rows(ep_f, n), rows(ep_p, n)])}
    d = np.concatenate([hard_directions(), nearly_opposite_grazing(12, seed=2)[0]])
    s_si, s1, s2 = corner_samples(d, CORNERS, CORNERS)
    bs, w = bsdf.sample(ctx, s_si, s1, s2)
    m = dr.width(s_si.wi)
    s_pdf, s_wo = rows(bs.pdf, m), rows(bs.wo, m)
    at_samples = {"weight": rows(w, m), "sample_pdf": s_pdf,
                  "wo": np.where(np.isfinite(s_wo), 0.0, np.nan)}
    out = {k: bad_values(x) for k, x in {**at_pairs, **at_samples}.items()}
    out["not_unit"] = int((np.abs(np.linalg.norm(s_wo, axis=1) - 1) > 1e-5)[s_pdf > 0].sum())
    out.update(pairs=n, samples=m, first=None)
    s_wi, s_w = to_np(s_si.wi), at_samples["weight"]
    places = [(at_pairs, wi, lambda i: f"wi = {wi[i]}, wo = {wo[i]}"),
              (at_samples, s_wi, lambda i: f"wi = {s_wi[i]}, sample1 = {to_np(s1)[i]:.8g}, "
                                           f"sample2 = {to_np(s2)[i]} (weight {s_w[i]}, "
                                           f"pdf {s_pdf[i]:.4g})")]
    bad_wi = []
    for values, where, place in places:
        for k, x in values.items():
            bad = (~np.isfinite(x) | (x < 0)).reshape(len(x), -1).any(axis=1)
            bad_wi.extend(map(tuple, np.round(where[bad], 7)))
            if bad.any() and out["first"] is None:
                i = int(np.argmax(bad))
                out["first"] = f"{k} = {np.ravel(x[i])} at {place(i)}"
    #: the incident directions with a bad value, most frequent first
    out["bad_wi"] = [list(w) for w in sorted(set(bad_wi), key=bad_wi.count, reverse=True)]
    return out


def check_zero_below_horizon(bsdf):
    """eval and pdf vanish with either direction below or on the horizon."""
    wi = np.array([[0, 0, 1], [0.6, 0, -0.8], [0.6, 0, 0.8], [0, 0, 1], [1, 0, 0]])
    wo = np.array([[0.6, 0, -0.8], [0, 0, 1], [-0.6, 0, -0.8], [0, 0, -1], [-1, 0, 0]])
    expect((eval_np(bsdf, wi, wo) == 0).all())
    expect((pdf_np(bsdf, wi, wo) == 0).all())


def check_eval_pdf_finite(bsdf, ctx, wi, wo, tag=""):
    """eval and pdf at every pair are finite and >= 0; returns them."""
    f, pdf = (to_np(x) for x in bsdf.eval_pdf(ctx, interaction(wi), vec(wo)))
    expect(np.isfinite(f).all() and (f >= 0).all(), tag)
    expect(np.isfinite(pdf).all() and (pdf >= 0).all(), tag)
    return f, pdf


def check_samples_finite(bsdf, ctx, samples, tag="", unit_wo=True):
    """Samples (arguments from corner_samples) have finite weights and pdfs >= 0 and finite
    directions; with unit_wo, unit vectors. Returns the weights and pdfs."""
    bs, w = bsdf.sample(ctx, *samples)
    w, wo_s, bpdf = to_np(w), to_np(bs.wo), to_np(bs.pdf)
    expect(np.isfinite(w).all() and (w >= 0).all(), tag)
    expect(np.isfinite(bpdf).all() and (bpdf >= 0).all(), tag)
    expect(np.isfinite(wo_s).all(), tag)
    if unit_wo:
        np.testing.assert_allclose(np.linalg.norm(wo_s, axis=1), 1, atol=1e-5, err_msg=tag)
    return w, bpdf


def check_finite_gradients(bsdf, wi, wo, keys=None):
    """The derivatives of the summed eval w.r.t. the parameters `keys` (by default every
    differentiable one) and both directions are finite. Returns the keys checked."""
    params = mi.traverse(bsdf)
    if keys is None:
        keys = [k for k in params.keys() if dr.is_diff_v(params[k])]
    for k in keys:
        dr.enable_grad(params[k])
    params.update()
    si, wo_v = interaction(wi), vec(wo)
    dr.enable_grad(si.wi, wo_v)
    dr.backward(dr.sum(bsdf.eval(mi.BSDFContext(), si, wo_v), axis=None))
    for g in [dr.grad(params[k]) for k in keys] + [dr.grad(si.wi), dr.grad(wo_v)]:
        expect(np.isfinite(np.array(g)).all())
    return keys
