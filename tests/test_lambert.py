"""The lambert plugin: against Mitsuba's ``diffuse``, the formula, sampling, energy, lobes,
parameters and renders."""
import itertools

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

from conftest import interaction, random_upper, sample_bsdf, small_scene, sph, to_np, vec

PLUGIN = "lambert"
F = mi.BSDFFlags


def load(**kw):
    d = {"type": PLUGIN}
    for k, v in kw.items():
        d[k] = {"type": "rgb", "value": v} if isinstance(v, (list, tuple)) else v
    return mi.load_dict(d)


def eval_np(bsdf, wi, wo, ctx=None):
    return to_np(bsdf.eval(ctx or mi.BSDFContext(), interaction(wi), vec(wo)))


def pdf_np(bsdf, wi, wo, ctx=None):
    return to_np(bsdf.pdf(ctx or mi.BSDFContext(), interaction(wi), vec(wo)))


def ref_lambert(wi, wo, rho):
    """f(wo, wi) cos(theta_o) = rho / pi max(cos(theta_o), 0), one-sided, float64."""
    rho = np.atleast_1d(np.asarray(rho, float))[None, :]
    up = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    return np.where(up[:, None], rho / np.pi * wo[:, 2:3], 0.0)


def directions(seed, n):
    """Random pairs over the whole sphere (a quarter of them below the horizon)."""
    rng = np.random.default_rng(seed)
    wi, wo = random_upper(rng, n), random_upper(rng, n)
    wi[: n // 8, 2] *= -1
    wo[n // 8: n // 4, 2] *= -1
    return wi, wo


# -- the formula and Mitsuba's diffuse ---------------------------------------------------------

@pytest.mark.parametrize("rho", [[0.5, 0.5, 0.5], [0.9, 0.3, 0.05], [1.0, 1.0, 1.0]])
def test_eval_pdf_match_reference_and_diffuse(rho):
    wi, wo = directions(1, 4000)
    b, d = load(reflectance=rho), mi.load_dict({"type": "diffuse", "reflectance": {"type": "rgb", "value": rho}})
    wi32, wo32 = (a.astype(np.float32).astype(float) for a in (wi, wo))
    got = eval_np(b, wi, wo)
    np.testing.assert_allclose(got, ref_lambert(wi32, wo32, rho), rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(got, eval_np(d, wi, wo), rtol=1e-6, atol=0)
    pdf = pdf_np(b, wi, wo)
    up = (wi32[:, 2] > 0) & (wo32[:, 2] > 0)
    np.testing.assert_allclose(pdf, np.where(up, wo32[:, 2] / np.pi, 0), rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(pdf, pdf_np(d, wi, wo), rtol=1e-6, atol=0)


@pytest.mark.parametrize("theta", [0, 45, 89.9])
def test_samples_equal_diffuse(theta):
    """Same random numbers, same directions, pdfs, weights and lobe types as ``diffuse``."""
    rho = [0.8, 0.4, 0.2]
    wi = sph(np.radians(theta), 0.4)[0]
    _, (bs, w) = sample_bsdf(load(reflectance=rho), wi, 20000, seed=3)
    _, (bs_d, w_d) = sample_bsdf(mi.load_dict({"type": "diffuse", "reflectance": {"type": "rgb", "value": rho}}),
                                 wi, 20000, seed=3)
    np.testing.assert_allclose(to_np(bs.wo), to_np(bs_d.wo), rtol=0, atol=1e-7)
    np.testing.assert_allclose(to_np(bs.pdf), to_np(bs_d.pdf), rtol=1e-6)
    np.testing.assert_allclose(to_np(w), to_np(w_d), rtol=1e-6)
    assert (np.broadcast_to(to_np(bs.sampled_type), (20000,)) == +(F.DiffuseReflection | F.FrontSide)).all()
    assert (to_np(bs.sampled_component) == 0).all()
    # the weight of a Lambertian sample is the reflectance itself
    np.testing.assert_allclose(to_np(w), np.broadcast_to(rho, (20000, 3)), rtol=1e-5)


@pytest.mark.parametrize("integrator", ["path", "direct"])
def test_render_equals_diffuse(integrator):
    """Both plugins consume the sampler alike: the same seed gives the same image."""
    rho = {"type": "rgb", "value": [0.7, 0.5, 0.3]}
    img = np.array(mi.render(small_scene({"type": PLUGIN, "reflectance": rho}, integrator=integrator), spp=8, seed=5))
    ref = np.array(mi.render(small_scene({"type": "diffuse", "reflectance": rho}, integrator=integrator), spp=8, seed=5))
    assert img.mean() > 1e-2
    np.testing.assert_allclose(img, ref, rtol=1e-4, atol=1e-5)
    # and within noise of an independent render of the reference
    ref2 = np.array(mi.render(small_scene({"type": "diffuse", "reflectance": rho}, integrator=integrator), spp=64, seed=9))
    assert abs(img.mean() - ref2.mean()) < 0.03 * ref2.mean()


def test_reciprocity():
    rng = np.random.default_rng(3)
    a, b = random_upper(rng, 3000), random_upper(rng, 3000)
    bsdf = load(reflectance=[0.3, 0.6, 0.9])
    f_ab = eval_np(bsdf, a, b) / b[:, 2:3].astype(np.float32)
    f_ba = eval_np(bsdf, b, a) / a[:, 2:3].astype(np.float32)
    np.testing.assert_allclose(f_ab, f_ba, rtol=1e-5)


# -- sampling and energy -----------------------------------------------------------------------

@pytest.mark.parametrize("theta", [0, 45, 80, 89.5])
def test_chi2(theta):
    wi = sph(np.radians(theta), 0.3)[0]
    sample_func, pdf_func = BSDFAdapter(PLUGIN, {"type": PLUGIN}, wi=mi.Vector3f(*map(float, wi)))
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func,
                         sample_dim=3, res=101, ires=8)
    assert test.run(), test.messages


@pytest.mark.parametrize("theta", [0, 60, 89.99])
def test_sample_weight_is_eval_over_pdf(theta):
    bsdf = load(reflectance=[0.2, 0.5, 0.9])
    si, (bs, weight) = sample_bsdf(bsdf, sph(np.radians(theta), 1.0)[0], 20000)
    ctx = mi.BSDFContext()
    f, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
    w, f, pdf, bpdf = to_np(weight), to_np(f), to_np(pdf), to_np(bs.pdf)
    ok = bpdf > 0
    assert ok.mean() > 0.99
    np.testing.assert_allclose(bpdf[ok], pdf[ok], rtol=1e-6)
    np.testing.assert_allclose(w[ok], f[ok] / pdf[ok, None], rtol=1e-5)
    assert (w[~ok] == 0).all()
    np.testing.assert_array_equal(f, to_np(bsdf.eval(ctx, si, bs.wo)))
    np.testing.assert_array_equal(pdf, to_np(bsdf.pdf(ctx, si, bs.wo)))


@pytest.mark.parametrize("theta", [0, 30, 60, 85, 89.9])
def test_white_furnace(theta):
    """A white Lambert surface reflects all light: albedo 1 at every incidence. The
    estimate is checked against numerical quadrature of eval as well (no sampling)."""
    b = load(reflectance=1.0)
    _, (bs, w) = sample_bsdf(b, sph(np.radians(theta), 0.7)[0], 100_000)
    np.testing.assert_allclose(to_np(w).mean(axis=0), 1.0, rtol=1e-5)
    # midpoint quadrature of the integral of eval over the hemisphere
    n = 400
    t, p = (np.arange(n) + 0.5) * (np.pi / 2 / n), (np.arange(2 * n) + 0.5) * (np.pi / n)
    tt, pp = np.meshgrid(t, p, indexing="ij")
    wo = sph(tt.ravel(), pp.ravel())
    wi = np.repeat(sph(np.radians(theta), 0.7), len(wo), axis=0)
    f = eval_np(b, wi, wo)[:, 0]
    integral = np.sum(f * np.sin(tt.ravel())) * (np.pi / 2 / n) * (np.pi / n)
    assert abs(integral - 1.0) < 1e-4, integral


# -- flags, components, contexts -----------------------------------------------------------------

def test_flags_components_and_context():
    b = load()
    assert b.component_count() == 1
    assert b.flags() == b.flags(0) == F.DiffuseReflection | F.FrontSide
    assert b.flags() == mi.load_dict({"type": "diffuse"}).flags()
    black = load(reflectance=0.0)
    assert black.component_count() == 0 and black.flags() == F.Empty
    wi, wo = random_upper(np.random.default_rng(2), 200), random_upper(np.random.default_rng(4), 200)
    want = ref_lambert(wi, wo, [0.5] * 3)
    for attrs, on in [({}, True), (dict(component=0), True), (dict(type_mask=+F.Diffuse), True),
                      (dict(type_mask=+F.DiffuseReflection), True), (dict(type_mask=+F.Glossy), False),
                      (dict(component=1), False), (dict(type_mask=+F.Transmission), False)]:
        ctx = mi.BSDFContext()
        for k, v in attrs.items():
            setattr(ctx, k, v)
        np.testing.assert_allclose(eval_np(b, wi, wo, ctx), want if on else 0 * want, rtol=1e-5,
                                   atol=1e-8, err_msg=str(attrs))
        assert (pdf_np(b, wi, wo, ctx) > 0).all() == on, attrs
        _, (bs, w) = sample_bsdf(b, wi[3], 1000, ctx=ctx)
        assert ((to_np(w) > 0).all() if on else (to_np(w) == 0).all()), attrs
    # a black surface evaluates, samples and renders to zero
    assert (eval_np(black, wi, wo) == 0).all()
    _, (bs, w) = sample_bsdf(black, wi[0], 100)
    assert (to_np(w) == 0).all()
    img = np.array(mi.render(small_scene({"type": PLUGIN, "reflectance": 0.0}, res=8), spp=2))
    assert np.isfinite(img).all()


# -- textures and parameters -------------------------------------------------------------------

def test_bitmap_texture(tmp_path):
    arr = np.zeros((2, 2, 3), np.float32)
    arr[:, 0], arr[:, 1] = [0.9, 0.1, 0.2], [0.1, 0.2, 0.8]  # left / right halves
    mi.Bitmap(arr).write(str(tmp_path / "rho.exr"))
    b = mi.load_dict({"type": PLUGIN, "reflectance": {"type": "bitmap", "filename": str(tmp_path / "rho.exr"),
                                                     "raw": True, "filter_type": "nearest"}})
    assert b.flags() & F.SpatiallyVarying
    si = interaction(np.array([[0, 0, 1], [0, 0, 1]]))
    si.uv = mi.Point2f([0.25, 0.75], [0.5, 0.5])
    wo = vec(sph(np.radians(30), 0.2).repeat(2, axis=0))
    f = to_np(b.eval(mi.BSDFContext(), si, wo))
    np.testing.assert_allclose(f, arr[0] / np.pi * np.cos(np.radians(30)), rtol=1e-5)
    bad = np.full((2, 2, 3), 1.2, np.float32)
    mi.Bitmap(bad).write(str(tmp_path / "bad.exr"))
    with pytest.raises(RuntimeError, match=r"lambert: parameter 'reflectance' must be a reflectance in \[0, 1\]"):
        mi.load_dict({"type": PLUGIN, "reflectance": {"type": "bitmap", "filename": str(tmp_path / "bad.exr"),
                                                     "raw": True}})


@pytest.mark.parametrize("params,msg", [
    ({"reflectance": 1.5}, r"lambert: parameter 'reflectance' must be a reflectance in \[0, 1\].*\(got 1.5\)"),
    ({"reflectance": -0.1}, r"parameter 'reflectance' must be a reflectance in \[0, 1\]"),
    ({"reflectance": float("nan")}, r"parameter 'reflectance'"),
    ({"reflectance": {"type": "rgb", "value": [0.2, 1.2, 0.3]}}, r"parameter 'reflectance'.*\[0, 1\]"),
    ({"reflectance": "red"}, r"parameter 'reflectance'"),
])
def test_bad_parameters(params, msg):
    with pytest.raises(RuntimeError, match=msg):
        mi.load_dict({"type": PLUGIN, **params})


def test_bad_parameters_from_xml():
    xml = '<bsdf version="3.0.0" type="lambert"><rgb name="reflectance" value="0.5, 2, 0.5"/></bsdf>'
    with pytest.raises(RuntimeError, match=r"lambert: parameter 'reflectance'.*\[0, 1\]"):
        mi.load_string(xml)
    ok = mi.load_string('<bsdf version="3.0.0" type="lambert"><rgb name="reflectance" value="0.5, 0.2, 0.5"/></bsdf>')
    assert "reflectance" in str(ok)


# -- hard cases ----------------------------------------------------------------------------------

def hard_directions():
    eps = 1e-7
    g = np.sqrt(1 - eps * eps)
    d = np.array([[0, 0, 1], [g, 0, eps], [0, -g, eps], [1, 0, 0], [0.6, 0, 0.8], [-0.6, 0, 0.8],
                  [0.3, 0.4, -np.sqrt(0.75)], [0, 0, -1], [0.577, 0.577, 0.578]], float)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


@pytest.mark.parametrize("rho", [0.0, 1.0])
def test_stability_grid(rho):
    d = hard_directions()
    pairs = np.array(list(itertools.product(range(len(d)), repeat=2)))
    wi = np.concatenate([d[pairs[:, 0]], -d])  # wi = -wo too
    wo = np.concatenate([d[pairs[:, 1]], d])
    b = load(reflectance=rho)
    f, pdf = (to_np(x) for x in b.eval_pdf(mi.BSDFContext(), interaction(wi), vec(wo)))
    assert np.isfinite(f).all() and (f >= 0).all() and np.isfinite(pdf).all() and (pdf >= 0).all()
    u = np.array([0, 1e-7, 0.5, 1 - 2**-24])
    g1, g2, g3, gi = np.meshgrid(u, u, u, np.arange(len(d)), indexing="ij")
    bs, w = b.sample(mi.BSDFContext(), interaction(d[gi.ravel()]), mi.Float(g1.ravel()),
                     mi.Point2f(g2.ravel(), g3.ravel()))
    w, wo_s = to_np(w), to_np(bs.wo)
    assert np.isfinite(w).all() and (w >= 0).all() and np.isfinite(to_np(bs.pdf)).all()
    if rho > 0:  # (a black surface has no lobe to sample)
        np.testing.assert_allclose(np.linalg.norm(wo_s, axis=1), 1, atol=1e-5)


# -- renders -------------------------------------------------------------------------------------

@pytest.mark.parametrize("integrator", ["path", "direct"])
def test_render_llvm(integrator):
    img = np.array(mi.render(small_scene({"type": PLUGIN, "reflectance": 0.8}, integrator=integrator), spp=4))
    assert np.isfinite(img).all() and img.mean() > 1e-3


def test_render_scalar_rgb():
    mi.set_variant("scalar_rgb")
    img = np.array(mi.render(small_scene({"type": PLUGIN}, res=6), spp=2))
    assert np.isfinite(img).all() and img.mean() > 1e-3


@pytest.mark.parametrize("variant", ["llvm_ad_spectral", "scalar_spectral"])
def test_spectral_variants(variant):
    mi.set_variant(variant)
    b = mi.load_dict({"type": PLUGIN, "reflectance": {"type": "rgb", "value": [0.9, 0.5, 0.2]}})
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(0, 0, 1)
    si.wavelengths = mi.Spectrum(450, 500, 600, 650)
    v = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(0.6, 0, 0.8)))
    assert np.isfinite(v).all() and (v > 0).all()
    if variant.startswith("llvm"):
        img = np.array(mi.render(small_scene({"type": PLUGIN}, res=8), spp=2))
        assert np.isfinite(img).all() and img.mean() > 1e-3
