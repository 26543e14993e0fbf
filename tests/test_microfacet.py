"""Shared microfacet math: distributions, samplers and pdfs, shadowing-masking, Jacobian."""
import itertools

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mitsuba_brdfs.core import microfacet as mf
from checks import floats, sph, to_np, vec, warp_chi2


def f32(x):
    return floats(x)


def unit_f32(d):
    """Directions rounded to float32 and renormalised in float64 (what the kernels see)."""
    d = np.asarray(d, float).astype(np.float32).astype(float)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


# -- float64 transcriptions of the lecture's D and G ------------------------------------------

def ref_d(kind, cos_h, rho=None, p=None):
    c = np.asarray(cos_h, float)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        if kind == "beckmann":
            alpha = np.arccos(np.clip(c, -1, 1))
            d = np.exp(-(np.tan(alpha) / rho) ** 2) / (np.pi * rho ** 2 * c ** 4)
        elif kind == "blinn":
            if p is None:
                d = c ** (2 / rho ** 2 - 2) / (np.pi * rho ** 2)
            else:
                d = (p + 2) / (2 * np.pi) * c ** p
        else:
            d = rho ** 2 / (np.pi * (c ** 2 * (rho ** 2 - 1) + 1) ** 2)
    return np.where(c > 0, np.nan_to_num(d, nan=0.0, posinf=0.0), 0.0)


def ref_g1_ggx(c, rho):
    c = np.asarray(c, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = 2 / (1 + np.sqrt(1 + rho ** 2 * (1 - c ** 2) / c ** 2))
    return np.where(c > 0, g, 0.0)


DISTS = [("beckmann", dict(rho=r)) for r in (0.01, 0.1, 0.3, 0.7, 1.0)] \
    + [("blinn", dict(rho=r)) for r in (0.05, 0.3, 1.0)] \
    + [("blinn", dict(p=p)) for p in (0.0, 1.0, 30.0, 1e4)] \
    + [("ggx", dict(rho=r)) for r in (0.01, 0.1, 0.3, 0.7, 1.0)]


def make(kind, rho=None, p=None):
    if kind == "blinn" and p is not None:
        return mf.Blinn(p)
    return mf.DISTRIBUTIONS[kind](rho)


def dist_id(c):
    return f"{c[0]}-" + "-".join(f"{k}={v:g}" for k, v in c[1].items())


# -- normalisation and values -------------------------------------------------------------------

@pytest.mark.parametrize("kind,kw", DISTS, ids=[dist_id(c) for c in DISTS])
def test_d_cos_integrates_to_one(kind, kw):
    """2 pi int D(theta) cos sin dtheta = 1, on a theta grid fine enough for the sharpest lobe;
    the azimuth of h is random (an isotropic D must not depend on it)."""
    n = 400_001
    theta = np.linspace(0, np.pi / 2, n)
    h = sph(theta, np.random.default_rng(0).uniform(0, 2 * np.pi, n))
    d = to_np(make(kind, **kw).eval(vec(h))).astype(float)
    integral = 2 * np.pi * np.trapezoid(d * np.cos(theta) * np.sin(theta), theta)
    assert abs(integral - 1) < 2e-3, integral


@pytest.mark.parametrize("kind,kw", DISTS, ids=[dist_id(c) for c in DISTS])
def test_d_matches_lecture_formula_and_pdf_is_d_cos(kind, kw):
    rng = np.random.default_rng(1)
    h = sph(np.arccos(rng.uniform(0, 1, 3000) ** 0.2), rng.uniform(0, 2 * np.pi, 3000))
    h = np.concatenate([h, [[0, 0, 1], [1, 0, 0], [0, 0.6, -0.8]]])
    h = unit_f32(h)
    dist = make(kind, **kw)
    got = to_np(dist.eval(vec(h)))
    want = ref_d(kind, h[:, 2], **kw)
    np.testing.assert_allclose(got, want, rtol=2e-4, atol=1e-6 * want.max())
    np.testing.assert_allclose(to_np(dist.pdf(vec(h))), want * np.maximum(h[:, 2], 0),
                               rtol=2e-4, atol=1e-6 * want.max())


@pytest.mark.parametrize("alpha", [0.02, 0.2, 0.6, 1.0])
def test_beckmann_and_ggx_match_mitsuba(alpha):
    """Mitsuba's alpha is the lecture's rho for Beckmann and GGX (D, and the D cos pdf)."""
    rng = np.random.default_rng(2)
    h = vec(sph(np.arccos(rng.uniform(0, 1, 4000) ** 0.3), rng.uniform(0, 2 * np.pi, 4000)))
    for kind, mtype in (("beckmann", mi.MicrofacetType.Beckmann), ("ggx", mi.MicrofacetType.GGX)):
        ours = mf.DISTRIBUTIONS[kind](alpha)
        theirs = mi.MicrofacetDistribution(mtype, alpha, False)
        want = to_np(theirs.eval(h))
        np.testing.assert_allclose(to_np(ours.eval(h)), want, rtol=1e-4, atol=1e-6 * want.max(),
                                   err_msg=kind)
        np.testing.assert_allclose(to_np(ours.pdf(h)), to_np(theirs.pdf(mi.Vector3f(0, 0, 1), h)),
                                   rtol=1e-4, atol=1e-6 * want.max(), err_msg=kind)


@pytest.mark.parametrize("alpha", [1e-4, 0.05, 0.3, 1.0])
def test_smith_ggx_g1_matches_lecture_and_mitsuba(alpha):
    rng = np.random.default_rng(3)
    v = sph(np.arccos(rng.uniform(0, 1, 3000)), rng.uniform(0, 2 * np.pi, 3000))
    v = np.concatenate([v, [[0, 0, 1], [1, 0, 0], [0.6, 0, -0.8]]])
    v = unit_f32(v)
    got = to_np(mf.smith_ggx_g1(f32(v[:, 2]), alpha))
    np.testing.assert_allclose(got, ref_g1_ggx(v[:, 2], alpha), rtol=1e-5, atol=1e-7)
    up = v[:, 2] > 0  # Mitsuba's G1 needs v.m > 0: m = n
    theirs = to_np(mi.MicrofacetDistribution(mi.MicrofacetType.GGX, alpha)
                   .smith_g1(vec(v[up]), mi.Vector3f(0, 0, 1)))
    np.testing.assert_allclose(got[up], theirs, rtol=1e-5, atol=1e-7)
    # the separable G is the product, and the GGX object agrees with the free function
    g = to_np(mf.smith_ggx_g(f32(v[:, 2]), f32(v[::-1, 2]), alpha))
    np.testing.assert_allclose(g, got * got[::-1], rtol=1e-6)
    np.testing.assert_array_equal(to_np(mf.GGX(alpha).smith_g1(vec(v))), got)


@pytest.mark.parametrize("alpha", [0.05, 0.3, 1.0])
@pytest.mark.parametrize("theta", [0, 45, 80, 89.9])
def test_visible_pdf_matches_mitsuba(alpha, theta):
    wi = sph(np.radians(theta), 0.4)
    rng = np.random.default_rng(4)
    h = sph(np.arccos(rng.uniform(0, 1, 4000) ** 0.3), rng.uniform(0, 2 * np.pi, 4000))
    wi_v = vec(np.repeat(wi, len(h), axis=0))
    ours = to_np(mf.GGX(alpha).pdf_visible(wi_v, vec(h)))
    theirs = to_np(mi.MicrofacetDistribution(mi.MicrofacetType.GGX, alpha, True).pdf(wi_v, vec(h)))
    np.testing.assert_allclose(ours, theirs, rtol=1e-4, atol=1e-6 * theirs.max())


def test_vgroove_matches_lecture_formula():
    rng = np.random.default_rng(5)
    wi = unit_f32(sph(np.arccos(rng.uniform(0, 1, 3000)), rng.uniform(0, 2 * np.pi, 3000)))
    wo = unit_f32(sph(np.arccos(rng.uniform(0, 1, 3000)), rng.uniform(0, 2 * np.pi, 3000)))
    h = wi + wo
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    nh, ni, no, oh = h[:, 2], wi[:, 2], wo[:, 2], np.sum(wo * h, axis=1)
    want = np.minimum(1, np.minimum(2 * nh * no / oh, 2 * nh * ni / oh))
    got = to_np(mf.vgroove_g(f32(ni), f32(no), f32(nh), f32(oh)))
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-7)
    assert (want < 1).mean() > 0.05  # the test reaches the shadowed configurations


# -- sampling -------------------------------------------------------------------------------

CHI2 = [
    ("beckmann", 0.1, 32), ("beckmann", 0.5, 8), ("beckmann", 1.0, 8),
    ("blinn", 0.1, 32), ("blinn", 0.5, 8), ("blinn", 1.0, 8),
    ("ggx", 0.1, 32), ("ggx", 0.5, 8), ("ggx", 1.0, 8),
]


@pytest.mark.parametrize("kind,rho,ires", CHI2)
def test_sample_chi2(kind, rho, ires):
    """h drawn by ``sample`` has the density ``pdf`` = D cos."""
    dist = mf.DISTRIBUTIONS[kind](rho)
    ok, messages = warp_chi2(dist.sample, dist.pdf, ires)
    assert ok, messages


@pytest.mark.parametrize("rho,theta,ires", [
    (0.1, 0, 32), (0.1, 60, 32), (0.1, 89, 128),  # 64 is too coarse at 89 deg (for Mitsuba too)
    (0.5, 0, 8), (0.5, 45, 8), (0.5, 80, 16), (0.5, 89.5, 16),
    (1.0, 30, 8), (1.0, 87, 8),
])
def test_sample_visible_chi2(rho, theta, ires):
    """Visible normals from wi follow G1(wi) max(0, wi.h) D(h) / cos(theta_i)."""
    dist = mf.GGX(rho)
    wi = mi.Vector3f(*map(float, sph(np.radians(theta), 0.9)[0]))
    ok, messages = warp_chi2(lambda u: dist.sample_visible(wi, u),
                             lambda h: dist.pdf_visible(wi, h), ires)
    assert ok, messages


@pytest.mark.parametrize("theta", [0, 50, 85, 89])
def test_reflected_density_integrates_to_one(theta):
    """pdf(h(wo)) / (4 wo.h) over the sphere of wo is 1: the Jacobian of reflection is right.

    wo -> h = normalize(wi + wo) maps the sphere onto the normals with wi.h > 0, all of which
    the visible-normal density covers; the D cos densities also put mass on wi.h < 0 unless
    wi = n, so they are checked at normal incidence.
    """
    wi = sph(np.radians(theta), 0.2)[0]
    n_t, n_p = 3000, 600
    t = np.linspace(0, np.pi, n_t)
    p = np.linspace(0, 2 * np.pi, n_p, endpoint=False)
    tt, pp = np.meshgrid(t, p, indexing="ij")
    wo = sph(tt.ravel(), pp.ravel())
    h = wi + wo
    h /= np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1e-300)
    jac = to_np(mf.reflection_jacobian(f32(np.sum(wo * h, axis=1))))
    ggx = mf.GGX(0.4)
    wi_v = vec(np.repeat(wi[None], len(h), axis=0))
    pdfs = {"visible": lambda hv: ggx.pdf_visible(wi_v, hv)}
    if theta == 0:
        pdfs.update(beckmann=mf.Beckmann(0.4).pdf, ggx=ggx.pdf, blinn=mf.Blinn(10.0).pdf)
    for name, pdf in pdfs.items():
        dens = (to_np(pdf(vec(h))) * jac).reshape(n_t, n_p).astype(float)
        integral = np.trapezoid(dens.mean(axis=1) * 2 * np.pi * np.sin(t), t)
        assert abs(integral - 1) < 5e-3, (name, integral)


# -- limits ---------------------------------------------------------------------------------

def test_stable_at_the_limits():
    """rho = 1e-4 (and 0) and 1, h = n, grazing, horizon and below: finite, >= 0, unit samples."""
    eps = 1e-7
    dirs = np.array([[0, 0, 1], [np.sqrt(1 - eps * eps), 0, eps], [1, 0, 0], [0, 0.6, 0.8],
                     [0.3, 0.4, -np.sqrt(0.75)], [0, 0, -1], [0.577, 0.577, 0.578]])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    u = np.array([0, 1e-7, 0.25, 0.5, 0.999999, 1 - 2**-24])
    g1, g2, gi = np.meshgrid(u, u, np.arange(len(dirs)), indexing="ij")
    samples = mi.Point2f(f32(g1), f32(g2))
    wi = vec(dirs[gi.ravel()])
    cos = f32([0, 1e-20, 1e-7, 1e-3, 0.5, 1, -0.5])
    for rho in (0.0, 1e-4, 0.3, 1.0):
        dists = [mf.Beckmann(rho), mf.Blinn.from_roughness(rho), mf.GGX(rho)]
        for dist in dists:
            name = f"{type(dist).__name__} rho={rho}"
            d, pdf = to_np(dist.eval(vec(dirs))), to_np(dist.pdf(vec(dirs)))
            assert np.isfinite(d).all() and (d >= 0).all(), name
            assert np.isfinite(pdf).all() and (pdf >= 0).all(), name
            assert d[0] > 0, name  # h = n
            hs = [dist.sample(samples)]
            if isinstance(dist, mf.GGX):
                hs.append(dist.sample_visible(wi, samples))
                pv = to_np(dist.pdf_visible(wi, hs[-1]))
                assert np.isfinite(pv).all() and (pv >= 0).all(), name
            for h in hs:
                hn = to_np(h)
                assert np.isfinite(hn).all(), name
                np.testing.assert_allclose(np.linalg.norm(hn, axis=1), 1, atol=1e-5, err_msg=name)
                assert (hn[:, 2] >= 0).all(), name
        for g in (to_np(mf.smith_ggx_g1(cos, rho)), to_np(mf.smith_ggx_g1_over_cos(cos, rho))):
            assert np.isfinite(g).all() and (g >= 0).all()
        g1 = to_np(mf.smith_ggx_g1(cos, rho))
        assert (g1 <= 1).all() and g1[5] == 1 and g1[0] == 0 and g1[6] == 0
    # V-groove over every combination of limit cosines (wi.h = 0 included)
    c = np.array([0, 1e-7, 0.5, 1.0])
    combos = np.array(list(itertools.product(c, repeat=4)))
    g = to_np(mf.vgroove_g(*(f32(combos[:, i]) for i in range(4))))
    assert np.isfinite(g).all() and (g >= 0).all() and (g <= 1).all()
    assert np.isfinite(to_np(mf.reflection_jacobian(f32(c)))).all()


@pytest.mark.parametrize("rho", [1e-4, 1.0])
def test_gradients_finite_at_the_limits(rho):
    """Derivatives w.r.t. rho and h through eval, pdf, samplers and G stay finite."""
    dirs = np.array([[0, 0, 1], [1, 0, 1e-7], [1, 0, 0], [0.3, 0.4, -0.866], [0.6, 0, 0.8]])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    u = mi.Point2f(f32([0, 1e-7, 0.5, 1 - 2**-24, 0.3]), f32([0, 0.5, 1 - 2**-24, 0.25, 0.9]))
    for ctor in (mf.Beckmann, mf.Blinn.from_roughness, mf.GGX):
        r = mi.Float(rho)
        h = vec(dirs)
        dr.enable_grad(r, h)
        dist = ctor(r)
        loss = dr.sum(dist.eval(h)) + dr.sum(dist.pdf(h)) + dr.sum(dist.sample(u), axis=None)
        if isinstance(dist, mf.GGX):
            loss += dr.sum(dist.sample_visible(h, u), axis=None) + dr.sum(dist.pdf_visible(h, h))
        loss += dr.sum(mf.smith_ggx_g(h.z, h.z, r))
        loss += dr.sum(mf.vgroove_g(h.z, h.z, h.z, h.z))
        dr.backward(loss)
        for name, g in (("rho", dr.grad(r)), ("h", dr.grad(h))):
            assert np.isfinite(np.array(g)).all(), (ctor, rho, name)


def test_microfacet_specular_is_dfg_over_4_cos():
    d, f, g, ci = f32([2.0, 5.0, 0.0]), f32([0.5, 1.0, 1.0]), f32([0.8, 1.0, 1.0]), f32([0.5, 0.0, 1e-7])
    np.testing.assert_allclose(to_np(mf.microfacet_specular(d, f, g, ci)), [0.4, 0.0, 0.0])
