"""Sampling checks: the sampled directions follow the pdf (chi-square), and each sample's
weight is eval / pdf."""
import drjit as dr
import mitsuba as mi
import numpy as np
from mitsuba.chi2 import ChiSquareTest, SphericalDomain

from .directions import sph
from .probe import (call_eval, call_eval_pdf, call_pdf, call_sample, close, expect, interaction,
                    rows, sample_bsdf, unpolarized)

__all__ = ["DIRAC", "bsdf_functions", "chi2", "check_chi2", "sample_record", "weight_errors",
           "check_sample_weight_is_eval_over_pdf"]


#: lobes without a density: delta reflection and transmission, and the null (pass-through)
#: lobe of ``mask`` and ``null``
DIRAC = int(mi.BSDFFlags.Delta | mi.BSDFFlags.Delta1D | mi.BSDFFlags.Null)


def bsdf_functions(bsdf, wi, ctx=None, same_side=False, by_pdf=False):
    """The sample and pdf functions of ``mitsuba.chi2.BSDFAdapter`` for a loaded BSDF at the
    local direction wi (BSDFAdapter loads the plugin anew from its name at every call, and a
    BSDF read from a scene file has no name to load it by). As there, a sample of zero weight
    is left out of the histogram, and so is a sample of a lobe without a density
    (``DIRAC``): pdf() is the density of the others (Mitsuba's convention), so they are
    compared under the default context, the one integrators use. With same_side, the pdf
    counts only on wi's side of the surface (a BSDF without transmission: its samples of
    non-zero weight must all be there). wi enters the kernel as an opaque value, so every
    incidence reuses the same kernels. With by_pdf, a sample counts when its pdf is > 0,
    whatever its weight (for a BSDF that is black at wi, whose weights are all 0)."""
    ctx = ctx or mi.BSDFContext()
    wi = dr.opaque(mi.Vector3f, [float(c) for c in np.ravel(wi)])

    def make_si(n):
        return interaction(wi, n)

    def sample_func(sample):
        bs, weight = call_sample(bsdf, ctx, make_si(dr.width(sample)), sample[0],
                                  mi.Point2f(sample[1], sample[2]))
        dirac = (bs.sampled_type & DIRAC) != 0
        dropped = ~(bs.pdf > 0) if by_pdf else dr.all(unpolarized(weight) == 0)
        return bs.wo, dr.select(dropped | dirac, 0.0, 1.0)

    def pdf_func(wo):
        pdf = call_pdf(bsdf, ctx, make_si(dr.width(wo)), wo)
        return dr.select(wo.z * wi.z > 0, pdf, 0.0) if same_side else pdf

    return sample_func, pdf_func


def chi2(bsdf, wi, ctx=None, res=101, ires=16, sample_count=1_000_000, significance=0.01,
         test_count=1, seed=0, same_side=False, by_pdf=False):
    """Mitsuba's chi-square test (``ChiSquareTest``, run quietly: it writes no file) of the
    directions ``bsdf`` samples at wi against its pdf, over the sphere (with same_side, the
    pdf counts on wi's side only; with by_pdf, samples of weight 0 count:
    ``bsdf_functions``). ``test_count`` tests run together share the significance level
    (Sidak). Returns ``ok``, the ``p_value``,
    ``pdf_sum`` (the pdf's integral) and ``histogram_sum`` (the share of samples kept), the
    test's ``messages`` and its ``histogram`` and ``expected`` counts (arrays of res x res/2
    cells, rows: -cos(theta) from -1 to 1, columns: phi from -pi to pi)."""
    sample_func, pdf_func = bsdf_functions(bsdf, wi, ctx, same_side, by_pdf)
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func,
                         sample_dim=3, sample_count=int(sample_count), res=res, ires=ires,
                         seed=seed)
    ok = test.run(significance_level=significance, test_count=test_count, quiet=True)
    shape = (int(test.res.y), int(test.res.x))
    p = test.p_value
    return {"ok": bool(ok), "p_value": float(p[0] if hasattr(p, "__len__") else p),
            "pdf_sum": float(test.pdf_sum[0]), "histogram_sum": float(test.histogram_sum[0]),
            "messages": test.messages.strip(),
            "histogram": np.array(test.histogram).reshape(shape),
            "expected": np.array(test.pdf).reshape(shape)}


def check_chi2(plugin, params, theta, res, ires):
    """Chi^2 test of the sampled directions against the pdf at theta_i = theta degrees
    (phi = 0.3); a "component" entry of params selects that lobe through the context.
    Returns the test's p-value."""
    params, ctx = dict(params), mi.BSDFContext()
    if "component" in params:
        ctx.component = params.pop("component")
    bsdf = mi.load_dict({"type": plugin, **params})
    r = chi2(bsdf, sph(np.radians(theta), 0.3)[0], ctx, res=res, ires=ires)
    expect(r["ok"], r["messages"])
    return r["p_value"]


def sample_record(bsdf, wi, n, ctx=None, seed=0):
    """n samples at each direction of wi (shape (3,) or (K, 3)), in one batch, with what the
    BSDF says about each sampled direction, as NumPy arrays: ``wi``, ``wo``, ``pdf`` (the
    sample's), ``weight``, ``sampled_type``, ``sampled_component``, ``eval``, ``pdf_wo``
    (pdf(wo)), ``ep_eval``, ``ep_pdf`` (eval_pdf(wo)), ``delta`` (the sample is of a lobe
    without a density, ``DIRAC``) and ``ok`` (pdf > 0 and not delta: the samples that eval
    and pdf describe); ``bs`` is the sample record itself."""
    ctx = ctx or mi.BSDFContext()
    si, (bs, weight) = sample_bsdf(bsdf, wi, n, seed=seed, ctx=ctx)
    ep_eval, ep_pdf = call_eval_pdf(bsdf, ctx, si, bs.wo)
    f, pdf_wo = call_eval(bsdf, ctx, si, bs.wo), call_pdf(bsdf, ctx, si, bs.wo)
    m = dr.width(si.wi)
    rec = {"wi": rows(si.wi, m), "wo": rows(bs.wo, m), "pdf": rows(bs.pdf, m),
           "weight": rows(weight, m, True),
           "sampled_type": rows(bs.sampled_type, m).astype(np.int32),
           "sampled_component": rows(bs.sampled_component, m).astype(np.int32),
           "eval": rows(f, m, True), "pdf_wo": rows(pdf_wo, m),
           "ep_eval": rows(ep_eval, m, True), "ep_pdf": rows(ep_pdf, m), "bs": bs}
    rec["delta"] = (rec["sampled_type"] & DIRAC) != 0
    rec["ok"] = (rec["pdf"] > 0) & ~rec["delta"]
    return rec


def weight_errors(rec, pdf_rtol, weight_rtol, weight_atol=0.0, eval_pdf_rtol=0.0,
                  zero_weight_fails=False):
    """What a sample record (``sample_record``) says about the sampler's own bookkeeping:
    ``pdf`` (the sample's pdf against pdf(wo) on the samples that succeeded), ``weight``
    (the weight against eval(wo) / pdf(wo)), ``failed`` (the largest |weight| of a sample
    with pdf 0, which must weigh 0) and ``eval_pdf`` (eval_pdf(wo) against eval(wo) and
    pdf(wo), to eval_pdf_rtol: 0 asks for the same bits). Each is a ``close`` record, and
    ``valid`` the share of samples that succeeded: those with pdf > 0 (not a delta lobe's),
    and with zero_weight_fails also a non-zero weight (Mitsuba's convention: its samplers
    may discard a sample by its weight alone, and keep its pdf)."""
    ok, failed = rec["ok"], (rec["pdf"] == 0) & ~rec["delta"]
    if zero_weight_fails:
        ok = ok & (rec["weight"] != 0).any(axis=1)
    f, pdf, w = rec["eval"][ok], rec["pdf_wo"][ok], rec["weight"][ok]
    w_failed = np.abs(rec["weight"][failed])
    ep_f = close(rec["ep_eval"], rec["eval"], eval_pdf_rtol)
    ep_p = close(rec["ep_pdf"], rec["pdf_wo"], eval_pdf_rtol)
    with np.errstate(divide="ignore", invalid="ignore"):
        weight = close(w, f / pdf[:, None], weight_rtol, weight_atol)
    return {
        "valid": float(ok.mean()) if ok.size else 0.0,
        "pdf": close(rec["pdf"][ok], pdf, pdf_rtol),
        "weight": weight,
        "failed": {"ok": bool((w_failed == 0).all()), "off": int((w_failed != 0).sum()),
                   "max_rel": float(np.max(w_failed, initial=0.0))},
        "eval_pdf": {"ok": ep_f["ok"] and ep_p["ok"], "off": ep_f["off"] + ep_p["off"],
                     "max_rel": max(ep_f["max_rel"], ep_p["max_rel"])},
    }


def check_sample_weight_is_eval_over_pdf(bsdf, wi, min_valid, pdf_rtol, weight_rtol,
                                         weight_atol=0.0, unit_wo=False, n=20000, tag=None):
    """n samples at wi: more than a share min_valid of them succeed (pdf > 0); their pdf is
    pdf(wo) and their weight eval(wo) / pdf(wo); a failed sample weighs 0; eval_pdf gives
    exactly eval and pdf; with unit_wo, every sampled direction is a unit vector.
    Returns the sample record and the mask of successful samples."""
    rec = sample_record(bsdf, wi, n)
    e = weight_errors(rec, pdf_rtol, weight_rtol, weight_atol)
    expect(e["valid"] > min_valid, (tag, "share of successful samples", e["valid"]))
    for key in ("pdf", "weight", "failed", "eval_pdf"):
        expect(e[key]["ok"], (tag, key, e[key]))
    if unit_wo:
        np.testing.assert_allclose(np.linalg.norm(rec["wo"], axis=1), 1, atol=1e-5)
    return rec["bs"], rec["ok"]
