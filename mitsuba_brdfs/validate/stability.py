"""Stability: finite, non-negative values where the formulas are fragile (grazing and
horizon directions, the normal, mirror pairs, corner sample values), zero below the
horizon, finite gradients."""
import drjit as dr
import mitsuba as mi
import numpy as np

from .directions import hard_directions, hard_pairs, nearly_opposite_grazing
from .probe import (call_eval, call_eval_pdf, call_pdf, call_sample, eval_np, expect, floats,
                    interaction, pdf_np, point2, rows, short, to_np, vec)

__all__ = ["CORNERS", "CORNERS_FINE", "corner_samples", "hard_cases", "check_zero_below_horizon",
           "check_eval_pdf_finite", "check_samples_finite", "check_finite_gradients"]

#: corner values of a sample dimension: 0, just above 0, the middle, the largest float32 below 1
CORNERS = np.array([0, 1e-7, 0.5, 1 - 2**-24])
CORNERS_FINE = np.array([0, 1e-7, 0.25, 0.5, 0.75, 1 - 2**-24])


def corner_samples(d, u1, u2):
    """Arguments (si, sample1, sample2) of BSDF.sample for every direction of d as wi with
    every combination of corner values: sample1 and sample2.x from u1, sample2.y from u2."""
    g1, g2, g3, gi = np.meshgrid(u1, u1, u2, np.arange(len(d)), indexing="ij")
    return interaction(d[gi.ravel()]), floats(g1), point2(g2, g3)


def hard_cases(bsdf, ctx=None):
    """The values of bsdf where formulas break: eval, pdf and eval_pdf at every pair of
    ``hard_pairs(hard_directions())`` (the normal, grazing and horizon directions, mirror
    pairs where h = n, directions below the horizon, nearly opposite grazing pairs), and
    samples at every corner value (``corner_samples``) with wi from the hard directions and
    from nearly opposite grazing ones.

    Returns ``pairs`` and ``samples`` (how many were tried) and ``findings``: one record per
    kind of bad value, with ``what`` (e.g. "non-finite pdf where eval is 0"), ``count``,
    ``masked`` (whether Mitsuba's integrators mask it, see ``validate.suite``: a NaN or
    negative pdf where eval is 0 in every channel, a non-finite or not unit ``wo`` or a
    non-finite or negative pdf in a sample of weight 0), ``example`` (the first such value
    and where it is) and ``wi`` (the incident directions concerned, most frequent first).
    Every other NaN, infinite or negative eval, pdf or weight, and every sampled direction
    of non-zero weight that is not a finite unit vector, is unmasked."""
    ctx = ctx or mi.BSDFContext()
    wi, wo = hard_pairs(hard_directions())
    si, v = interaction(wi), vec(wo)
    n = len(wi)
    ep_f, ep_p = call_eval_pdf(bsdf, ctx, si, v)
    f, ep_f = rows(call_eval(bsdf, ctx, si, v), n, True), rows(ep_f, n, True)
    p, ep_p = rows(call_pdf(bsdf, ctx, si, v), n), rows(ep_p, n)
    d = np.concatenate([hard_directions(), nearly_opposite_grazing(12, seed=2)[0]])
    s_si, s1, s2 = corner_samples(d, CORNERS, CORNERS)
    bs, w = call_sample(bsdf, ctx, s_si, s1, s2)
    m = dr.width(s_si.wi)
    w, s_pdf, s_wo = rows(w, m, True), rows(bs.pdf, m), rows(bs.wo, m)
    s_wi, u1, u2 = to_np(s_si.wi), to_np(s1), to_np(s2)

    def bad(x):  # NaN, infinite or negative, per row
        x = np.asarray(x, float).reshape(len(x), -1)
        return (~np.isfinite(x) | (x < 0)).any(axis=1)

    def at_pair(i, **values):
        return ", ".join(f"{k} = {short(x[i])}" for k, x in values.items()) + \
            f" at wi = {short(wi[i])}, wo = {short(wo[i])}"

    def at_sample(i, **values):
        values = {**values, "pdf": s_pdf, "weight": w}
        return ", ".join(f"{k} = {short(x[i])}" for k, x in values.items()) + \
            f" at wi = {short(s_wi[i])}, sample1 = {u1[i]:.8g}, sample2 = {short(u2[i])}"

    dark = ~(f != 0).any(axis=1) & ~(ep_f != 0).any(axis=1)  # eval 0 in every channel
    scatters = (w != 0).any(axis=1)
    not_unit = np.abs(np.linalg.norm(np.nan_to_num(s_wo, nan=0.0), axis=1) - 1) > 1e-5
    nonfinite_wo = ~np.isfinite(s_wo).all(axis=1)
    kinds = [  # (what, mask, masked, where, example)
        ("non-finite or negative eval", bad(f) | bad(ep_f), False, wi,
         lambda i: at_pair(i, eval=f, eval_pdf=ep_f)),
        ("non-finite or negative pdf where eval is not 0", (bad(p) | bad(ep_p)) & ~dark, False,
         wi, lambda i: at_pair(i, pdf=p, eval_pdf=ep_p, eval=f)),
        ("non-finite or negative pdf where eval is 0", (bad(p) | bad(ep_p)) & dark, True, wi,
         lambda i: at_pair(i, pdf=p, eval_pdf=ep_p)),
        ("non-finite or negative sample weight", bad(w), False, s_wi, lambda i: at_sample(i)),
        ("non-finite or negative pdf in a sample of non-zero weight", bad(s_pdf) & scatters,
         False, s_wi, lambda i: at_sample(i)),
        ("non-finite or negative pdf in a sample of weight 0", bad(s_pdf) & ~scatters, True,
         s_wi, lambda i: at_sample(i)),
        ("sampled direction of non-zero weight not a finite unit vector",
         (nonfinite_wo | not_unit) & scatters, False, s_wi, lambda i: at_sample(i, wo=s_wo)),
        ("non-finite sampled direction in a sample of weight 0", nonfinite_wo & ~scatters, True,
         s_wi, lambda i: at_sample(i, wo=s_wo)),
    ]
    findings = []
    for what, mask, masked, where, example in kinds:
        if mask.any():
            i = int(np.argmax(mask))
            dirs = [tuple(x) for x in np.round(where[mask], 7)]
            findings.append({"what": what, "count": int(mask.sum()), "masked": masked,
                             "example": example(i),
                             "wi": [list(x) for x in sorted(set(dirs), key=dirs.count,
                                                             reverse=True)]})
    return {"pairs": n, "samples": m, "findings": findings}


def check_zero_below_horizon(bsdf):
    """eval and pdf vanish with either direction below or on the horizon."""
    wi = np.array([[0, 0, 1], [0.6, 0, -0.8], [0.6, 0, 0.8], [0, 0, 1], [1, 0, 0]])
    wo = np.array([[0.6, 0, -0.8], [0, 0, 1], [-0.6, 0, -0.8], [0, 0, -1], [-1, 0, 0]])
    expect((eval_np(bsdf, wi, wo) == 0).all())
    expect((pdf_np(bsdf, wi, wo) == 0).all())


def check_eval_pdf_finite(bsdf, ctx, wi, wo, tag=""):
    """eval and pdf at every pair are finite and >= 0; returns them."""
    f, pdf = (to_np(x) for x in call_eval_pdf(bsdf, ctx, interaction(wi), vec(wo)))
    expect(np.isfinite(f).all() and (f >= 0).all(), tag)
    expect(np.isfinite(pdf).all() and (pdf >= 0).all(), tag)
    return f, pdf


def check_samples_finite(bsdf, ctx, samples, tag="", unit_wo=True):
    """Samples (arguments from corner_samples) have finite weights and pdfs >= 0 and finite
    directions; with unit_wo, unit vectors. Returns the weights and pdfs."""
    bs, w = call_sample(bsdf, ctx, *samples)
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
    dr.backward(dr.sum(call_eval(bsdf, mi.BSDFContext(), si, wo_v), axis=None))
    for g in [dr.grad(params[k]) for k in keys] + [dr.grad(si.wi), dr.grad(wo_v)]:
        expect(np.isfinite(np.array(g)).all())
    return keys
