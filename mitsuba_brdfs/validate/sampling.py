"""Sampling checks: the sampled directions follow the pdf (chi-square), and each sample's
weight is eval / pdf."""
import mitsuba as mi
import numpy as np
from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

from .directions import sph
from .probe import expect, sample_bsdf, to_np

__all__ = ["check_chi2", "check_sample_weight_is_eval_over_pdf"]


def check_chi2(plugin, params, theta, res, ires):
    """Chi^2 test of the sampled directions against the pdf at theta_i = theta degrees
    (phi = 0.3); a "component" entry of params selects that lobe through the context.
    Returns the test's p-value."""
    params, ctx = dict(params), mi.BSDFContext()
    if "component" in params:
        ctx.component = params.pop("component")
    wi = sph(np.radians(theta), 0.3)[0]
    sample_func, pdf_func = BSDFAdapter(plugin, {"type": plugin, **params},
                                        wi=mi.Vector3f(*map(float, wi)), ctx=ctx)
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func,
                         pdf_func=pdf_func, sample_dim=3, res=res, ires=ires)
    expect(test.run(), test.messages)
    return test.p_value


def check_sample_weight_is_eval_over_pdf(bsdf, wi, min_valid, pdf_rtol, weight_rtol,
                                         weight_atol=0.0, unit_wo=False, n=20000, tag=None):
    """n samples at wi: more than a share min_valid of them succeed (pdf > 0); their pdf is
    pdf(wo) and their weight eval(wo) / pdf(wo); a failed sample weighs 0; eval_pdf gives
    exactly eval and pdf; with unit_wo, every sampled direction is a unit vector.
    Returns the sample record and the mask of successful samples."""
    si, (bs, weight) = sample_bsdf(bsdf, wi, n)
    ctx = mi.BSDFContext()
    f, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
    w, f, pdf, bpdf = to_np(weight), to_np(f), to_np(pdf), to_np(bs.pdf)
    ok = bpdf > 0
    expect(ok.mean() > min_valid, tag)
    np.testing.assert_allclose(bpdf[ok], pdf[ok], rtol=pdf_rtol)
    np.testing.assert_allclose(w[ok], f[ok] / pdf[ok, None], rtol=weight_rtol, atol=weight_atol)
    expect((w[~ok] == 0).all())
    if unit_wo:
        np.testing.assert_allclose(np.linalg.norm(to_np(bs.wo), axis=1), 1, atol=1e-5)
    np.testing.assert_array_equal(f, to_np(bsdf.eval(ctx, si, bs.wo)))
    np.testing.assert_array_equal(pdf, to_np(bsdf.pdf(ctx, si, bs.wo)))
    return bs, ok
