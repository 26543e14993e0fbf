"""Stability: finite, non-negative values where the formulas are fragile (grazing and
horizon directions, the normal, mirror pairs, corner sample values), zero below the
horizon, finite gradients."""
import drjit as dr
import mitsuba as mi
import numpy as np

from .probe import eval_np, expect, interaction, pdf_np, to_np, vec

__all__ = ["CORNERS", "CORNERS_FINE", "corner_samples", "check_zero_below_horizon",
           "check_eval_pdf_finite", "check_samples_finite", "check_finite_gradients"]

#: corner values of a sample dimension: 0, just above 0, the middle, the largest float32 below 1
CORNERS = np.array([0, 1e-7, 0.5, 1 - 2**-24])
CORNERS_FINE = np.array([0, 1e-7, 0.25, 0.5, 0.75, 1 - 2**-24])


def corner_samples(d, u1, u2):
    """Arguments (si, sample1, sample2) of BSDF.sample for every direction of d as wi with
    every combination of corner values: sample1 and sample2.x from u1, sample2.y from u2."""
    g1, g2, g3, gi = np.meshgrid(u1, u1, u2, np.arange(len(d)), indexing="ij")
    return interaction(d[gi.ravel()]), mi.Float(g1.ravel()), mi.Point2f(g2.ravel(), g3.ravel())


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
