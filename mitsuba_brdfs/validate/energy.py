"""Energy checks: the directional albedo (white furnace) by Monte Carlo and by quadrature,
and its bounds."""
import mitsuba as mi
import numpy as np

from .directions import half_vector_sphere, lobe_sphere, sph
from .probe import call_eval_pdf, expect, interaction, rows, sample_bsdf, to_np, vec

__all__ = ["albedo_at", "albedo", "quadrature", "reflected", "albedo_bound",
           "check_albedo_is_one", "check_albedo_at_most_one"]


def albedo_at(bsdf, wi, n=300_000, seed=0, ctx=None):
    """Monte Carlo directional albedo at wi (mean sample weight) and its standard error."""
    _, (_, weight) = sample_bsdf(bsdf, wi, n, seed=seed, ctx=ctx)
    w = to_np(weight)
    return w.mean(axis=0), w.std(axis=0) / np.sqrt(n)


def albedo(bsdf, theta, n=300_000, seed=0, ctx=None):
    """albedo_at theta_i = theta degrees (phi = 0.7)."""
    return albedo_at(bsdf, sph(np.radians(theta), 0.7)[0], n, seed=seed, ctx=ctx)


def _cells(n, wi, transmission):
    """Quadrature cells (directions, solid angles) of the sphere lit from wi: wi's side over
    the half vector (``directions.half_vector_sphere``), and with transmission the other side
    on a grid of directions (``directions.lobe_sphere``)."""
    wi = np.reshape(np.asarray(wi, float), 3)
    wo, dw = half_vector_sphere(n, wi)
    side = wo[:, 2] * wi[2] > 0
    wo, dw = wo[side], dw[side]
    if transmission:
        wt, dt = lobe_sphere(n, wi * [1, 1, -1])
        other = wt[:, 2] * wi[2] < 0
        wo, dw = np.concatenate([wo, wt[other]]), np.concatenate([dw, dt[other]])
    return wo, dw


def quadrature(bsdf, wi, n, ctx=None, same_side=False):
    """The integrals of eval and of pdf over the sphere at wi, each with an estimate of its
    error: the difference from the same rule with half the resolution. wi's side is
    integrated over the half vector, where specular lobes are regular at any incidence
    (``directions.half_vector_sphere``), the other side over directions
    (``directions.lobe_sphere``) unless same_side (a BSDF without transmission). Returns
    (eval integral, its error) (shape (C,)) and (pdf integral, its error) (floats)."""
    ctx = ctx or mi.BSDFContext()
    out = []
    for m in (n, n // 2):
        wo, dw = _cells(m, wi, transmission=not same_side)
        f, pdf = call_eval_pdf(bsdf, ctx, interaction(np.broadcast_to(np.reshape(wi, (1, 3)), wo.shape)),
                               vec(wo))
        f, pdf = rows(f, len(wo), channels=True), rows(pdf, len(wo))
        out.append(((f * dw[:, None]).sum(axis=0), float((pdf * dw).sum())))
    (f, p), (f2, p2) = out
    return (f, np.abs(f - f2)), (p, abs(p - p2))


def reflected(bsdf, thetas, n=48, phi=0.3, ctx=None):
    """The directional albedo int eval d wo of a reflecting BSDF at each theta_i in
    ``thetas`` (degrees), by midpoint quadrature over the half vector
    (``directions.half_vector_sphere``, resolution ``n``), all incidences in one call:
    shape (len(thetas), C)."""
    wis, wos, dws, sizes = [], [], [], []
    for t in thetas:
        wi = sph(np.radians(t), phi)[0]
        wo, dw = half_vector_sphere(n, wi)
        up = wo[:, 2] > 0
        wos.append(wo[up])
        dws.append(dw[up])
        sizes.append(int(up.sum()))
        wis.append(np.repeat(wi[None], sizes[-1], axis=0))
    wi, wo, dw = np.concatenate(wis), np.concatenate(wos), np.concatenate(dws)
    f = rows(call_eval_pdf(bsdf, ctx or mi.BSDFContext(), interaction(wi), vec(wo))[0],
             len(wi), channels=True)
    ends = np.cumsum(sizes)
    return np.array([(f[a:b] * dw[a:b, None]).sum(axis=0) for a, b in zip(ends - sizes, ends)])


def albedo_bound(err):
    """The largest value an albedo estimate with standard error err may show and still count
    as at most 1: 4 standard errors and 1e-3 above 1 (``check_albedo_at_most_one``)."""
    return 1 + 4 * np.asarray(err) + 1e-3


def check_albedo_is_one(bsdf, thetas):
    """The albedo at each theta_i in thetas (degrees) is 1 to 1e-5 (100 000 samples): for a
    white Lambertian lobe, whose sample weights are all exactly 1. Returns the albedos."""
    out = []
    for theta in thetas:
        a, _ = albedo(bsdf, theta, n=100_000)
        np.testing.assert_allclose(a, 1, atol=1e-5, err_msg=f"theta = {theta}")
        out.append(a)
    return out


def check_albedo_at_most_one(a, err, tag=None):
    """An albedo estimate (with its standard error) is finite and at most 1 (up to 4 standard
    errors and 1e-3). Returns its largest value."""
    expect(np.isfinite(a).all(), (tag, a))
    expect((a <= albedo_bound(err)).all(), (tag, a, err))
    return float(np.max(a))
