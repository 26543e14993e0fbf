"""Helpers and checkers shared by the per-model test files.

A checker asserts one property of a BSDF; what differs between the models (the plugin, the
tolerances, the reference lobes) comes in as arguments, so that the test calling it still
says what it checks. Directions are local-frame unit vectors, numpy arrays of shape (N, 3).
"""
import itertools

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

from conftest import interaction, random_upper, sample_bsdf, small_scene, sph, to_np, vec

F = mi.BSDFFlags


# -- loading, evaluating, directions -----------------------------------------------------------

def load_bsdf(plugin, **kw):
    """The plugin with the given parameters; lists and tuples become RGB colours."""
    d = {"type": plugin}
    for k, v in kw.items():
        d[k] = {"type": "rgb", "value": v} if isinstance(v, (list, tuple)) else v
    return mi.load_dict(d)


def eval_np(bsdf, wi, wo, ctx=None):
    return to_np(bsdf.eval(ctx or mi.BSDFContext(), interaction(wi), vec(wo)))


def pdf_np(bsdf, wi, wo, ctx=None):
    return to_np(bsdf.pdf(ctx or mi.BSDFContext(), interaction(wi), vec(wo)))


def context(**attrs):
    """A BSDFContext with the given attributes set (component, type_mask, ...)."""
    ctx = mi.BSDFContext()
    for k, v in attrs.items():
        setattr(ctx, k, v)
    return ctx


def unit(a):
    a = np.asarray(a, float)
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


def unit_f32(a):
    """The float32 directions the plugin sees, back in float64 (and renormalised)."""
    return unit(np.asarray(a, np.float32).astype(float))


def colour(c):
    """A scalar or RGB value as a (1, C) row, to broadcast against (N, 1) columns."""
    return np.atleast_1d(np.asarray(c, float))[None, :]


def random_pairs(seed, n):
    """n pairs (wi, wo) of random directions over the upper hemisphere."""
    rng = np.random.default_rng(seed)
    return random_upper(rng, n), random_upper(rng, n)


def mirror_pairs(n, seed, mirrors):
    """n random pairs, then `mirrors` exact mirror pairs (h = n) and the normal with itself."""
    wi, wo = random_pairs(seed, n)
    wi = np.concatenate([wi, wi[:mirrors], [[0, 0, 1]]])
    wo = np.concatenate([wo, wi[:mirrors] * [-1, -1, 1], [[0, 0, 1]]])
    return wi, wo


def eval_pairs(n=3000, seed=7):
    """mirror_pairs with 100 mirror pairs, as the float32 directions the plugin sees."""
    wi, wo = mirror_pairs(n, seed, mirrors=100)
    return unit_f32(wi), unit_f32(wo)


def hard_directions():
    eps = 1e-7
    g = np.sqrt(1 - eps * eps)
    d = np.array([
        [0, 0, 1],                                  # the normal (h = n with itself)
        [g, 0, eps], [0, g, eps], [-g, 0, eps],     # grazing, cos = 1e-7
        [1, 0, 0], [0, -1, 0],                      # exactly at the horizon
        [0.6, 0, 0.8], [-0.6, 0, 0.8],              # a mirror pair
        [0, 0.6, 0.8], [0, -0.6, 0.8],
        [0.3, 0.4, -np.sqrt(0.75)], [0, 0, -1],     # below the horizon
        [0.577, 0.577, 0.578],
    ], float)
    return unit(d)


def hard_pairs(d, mirrored=None):
    """Every ordered pair (wi, wo) of the directions d, then wi = -wo for the first
    `mirrored` of them (all by default)."""
    pairs = np.array(list(itertools.product(range(len(d)), repeat=2)))
    k = len(d) if mirrored is None else mirrored
    return (np.concatenate([d[pairs[:, 0]], -d[:k]]), np.concatenate([d[pairs[:, 1]], d[:k]]))


#: corner values of a sample dimension: 0, just above 0, the middle, the largest float32 below 1
CORNERS = np.array([0, 1e-7, 0.5, 1 - 2**-24])
CORNERS_FINE = np.array([0, 1e-7, 0.25, 0.5, 0.75, 1 - 2**-24])


def corner_samples(d, u1, u2):
    """Arguments (si, sample1, sample2) of BSDF.sample for every direction of d as wi with
    every combination of corner values: sample1 and sample2.x from u1, sample2.y from u2."""
    g1, g2, g3, gi = np.meshgrid(u1, u1, u2, np.arange(len(d)), indexing="ij")
    return interaction(d[gi.ravel()]), mi.Float(g1.ravel()), mi.Point2f(g2.ravel(), g3.ravel())


def albedo_at(bsdf, wi, n=300_000, seed=0, ctx=None):
    """Monte Carlo directional albedo at wi (mean sample weight) and its standard error."""
    _, (_, weight) = sample_bsdf(bsdf, wi, n, seed=seed, ctx=ctx)
    w = to_np(weight)
    return w.mean(axis=0), w.std(axis=0) / np.sqrt(n)


def albedo(bsdf, theta, n=300_000, seed=0, ctx=None):
    """albedo_at theta_i = theta degrees (phi = 0.7)."""
    return albedo_at(bsdf, sph(np.radians(theta), 0.7)[0], n, seed=seed, ctx=ctx)


def midpoint_hemisphere(n):
    """Midpoint quadrature of the upper hemisphere (n polar, 2 n azimuthal cells): the
    directions and the solid angle of each cell."""
    t, p = (np.arange(n) + 0.5) * (np.pi / 2 / n), (np.arange(2 * n) + 0.5) * (np.pi / n)
    tt, pp = np.meshgrid(t, p, indexing="ij")
    return sph(tt.ravel(), pp.ravel()), np.sin(tt.ravel()) * (np.pi / 2 / n) * (np.pi / n)


def eval_both_ways(bsdf, a, b):
    """f(a, b) and f(b, a), the BSDF without the cosine."""
    f_ab = eval_np(bsdf, a, b) / b[:, 2:3].astype(np.float32)
    f_ba = eval_np(bsdf, b, a) / a[:, 2:3].astype(np.float32)
    return f_ab, f_ba


# -- textures ------------------------------------------------------------------------------------

def bitmap(filename):
    """A bitmap texture of raw values, looked up without filtering."""
    return {"type": "bitmap", "filename": str(filename), "raw": True, "filter_type": "nearest"}


def write_bitmap(path, value, res=4):
    """A constant res x res image of value (a scalar or a colour); returns its file name."""
    arr = np.full((res, res, np.size(value)), value, dtype=np.float32)
    mi.Bitmap(arr).write(str(path))
    return str(path)


def write_halves(path, left, right):
    """A 2x2 image, `left` where u < 0.5 and `right` where u >= 0.5; returns its texture."""
    arr = np.zeros((2, 2, np.size(left)), np.float32)
    arr[:, 0], arr[:, 1] = left, right
    mi.Bitmap(arr).write(str(path))
    return bitmap(path)


def eval_left_right(bsdf, wi, wo):
    """eval at one pair of directions on the left (u = 0.25) and the right (u = 0.75) half
    of the uv square: shape (2, C)."""
    si = interaction(np.repeat(np.reshape(wi, (1, 3)), 2, axis=0))
    si.uv = mi.Point2f([0.25, 0.75], [0.5, 0.5])
    return to_np(bsdf.eval(mi.BSDFContext(), si, vec(np.repeat(np.reshape(wo, (1, 3)), 2, axis=0))))


def check_textured_equals_constant(textured, const):
    """A BSDF whose parameters are constant bitmaps is spatially varying and evaluates (eval
    and pdf) like the same BSDF with the constants."""
    assert textured.flags() & F.SpatiallyVarying
    assert not const.flags() & F.SpatiallyVarying
    wi, wo = random_pairs(11, 1000)
    np.testing.assert_allclose(eval_np(textured, wi, wo), eval_np(const, wi, wo), rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(pdf_np(textured, wi, wo), pdf_np(const, wi, wo), rtol=1e-5, atol=1e-7)


def check_refused(plugin, params, msg):
    """Loading the plugin with params raises a RuntimeError whose message matches msg."""
    with pytest.raises(RuntimeError, match=msg):
        mi.load_dict({"type": plugin, **params})


def load_xml(plugin, body):
    """The plugin from a scene-file description, with body (its parameter elements)."""
    return mi.load_string(f'<bsdf version="3.0.0" type="{plugin}">{body}</bsdf>')


def check_xml_refused(plugin, body, msg):
    """Loading the plugin from a scene file with body raises a RuntimeError matching msg."""
    with pytest.raises(RuntimeError, match=msg):
        load_xml(plugin, body)


# -- eval --------------------------------------------------------------------------------------

def check_eval(bsdf, wi, wo, want, rtol=5e-4, ctx=None):
    """eval(wi, wo) = want (with the cosine) to rtol, and to 1e-6 of the largest value."""
    np.testing.assert_allclose(eval_np(bsdf, wi, wo, ctx), want, rtol=rtol, atol=1e-6 * want.max())


def check_zero_below_horizon(bsdf):
    """eval and pdf vanish with either direction below or on the horizon."""
    wi = np.array([[0, 0, 1], [0.6, 0, -0.8], [0.6, 0, 0.8], [0, 0, 1], [1, 0, 0]])
    wo = np.array([[0.6, 0, -0.8], [0, 0, 1], [-0.6, 0, -0.8], [0, 0, -1], [-1, 0, 0]])
    assert (eval_np(bsdf, wi, wo) == 0).all()
    assert (pdf_np(bsdf, wi, wo) == 0).all()


def check_reciprocal(bsdf, a, b, rtol=1e-3, err_msg=""):
    """f(a, b) = f(b, a) to rtol, and to 1e-6 of the largest value."""
    f_ab, f_ba = eval_both_ways(bsdf, a, b)
    np.testing.assert_allclose(f_ab, f_ba, rtol=rtol, atol=1e-6 * f_ab.max(), err_msg=err_msg)


# -- sampling ----------------------------------------------------------------------------------

def check_chi2(plugin, params, theta, res, ires):
    """Chi^2 test of the sampled directions against the pdf at theta_i = theta degrees
    (phi = 0.3); a "component" entry of params selects that lobe through the context."""
    params, ctx = dict(params), mi.BSDFContext()
    if "component" in params:
        ctx.component = params.pop("component")
    wi = sph(np.radians(theta), 0.3)[0]
    sample_func, pdf_func = BSDFAdapter(plugin, {"type": plugin, **params},
                                        wi=mi.Vector3f(*map(float, wi)), ctx=ctx)
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func,
                         pdf_func=pdf_func, sample_dim=3, res=res, ires=ires)
    assert test.run(), test.messages


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
    assert ok.mean() > min_valid, tag
    np.testing.assert_allclose(bpdf[ok], pdf[ok], rtol=pdf_rtol)
    np.testing.assert_allclose(w[ok], f[ok] / pdf[ok, None], rtol=weight_rtol, atol=weight_atol)
    assert (w[~ok] == 0).all()
    if unit_wo:
        np.testing.assert_allclose(np.linalg.norm(to_np(bs.wo), axis=1), 1, atol=1e-5)
    np.testing.assert_array_equal(f, to_np(bsdf.eval(ctx, si, bs.wo)))
    np.testing.assert_array_equal(pdf, to_np(bsdf.pdf(ctx, si, bs.wo)))
    return bs, ok


# -- energy ------------------------------------------------------------------------------------

def check_albedo_is_one(bsdf, thetas):
    """The albedo at each theta_i in thetas (degrees) is 1 to 1e-5 (100 000 samples): for a
    white Lambertian lobe, whose sample weights are all exactly 1."""
    for theta in thetas:
        a, _ = albedo(bsdf, theta, n=100_000)
        np.testing.assert_allclose(a, 1, atol=1e-5, err_msg=f"theta = {theta}")


def check_albedo_at_most_one(a, err, tag=None):
    """An albedo estimate (with its standard error) is finite and at most 1 (up to 4 standard
    errors and 1e-3)."""
    assert np.isfinite(a).all(), (tag, a)
    assert (a <= 1 + 4 * err + 1e-3).all(), (tag, a, err)


# -- lobes and contexts --------------------------------------------------------------------------

def check_glossy_and_diffuse_lobes(bsdf, glossy=F.GlossyReflection | F.FrontSide):
    """Two lobes: component 0 with the flags `glossy`, component 1 a diffuse reflection."""
    assert bsdf.component_count() == 2
    assert bsdf.flags(0) == glossy
    assert bsdf.flags(1) == F.DiffuseReflection | F.FrontSide
    assert bsdf.flags() == bsdf.flags(0) | bsdf.flags(1)


def check_context_selects_lobes(bsdf, wi, wo, spec, diff, rtol, atol, lobe_pdf=False):
    """A BSDF with a glossy lobe (component 0) and a diffuse one (component 1). A context that
    selects one lobe, by index or by type, evaluates to that lobe alone (spec or diff, without
    the cosine, at the pairs wi, wo; atol is a number or a function of those values) and
    samples only that lobe (the diffuse one with the cosine pdf); one that selects nothing
    evaluates and samples to zero. With lobe_pdf, a sample's pdf is also the selected lobe's
    own pdf (pdf and eval_pdf with the context), and nothing selected has pdf zero."""
    cases = {
        "component0": (dict(component=0), spec),
        "component1": (dict(component=1), diff),
        "glossy_mask": (dict(type_mask=+F.Glossy), spec),
        "diffuse_mask": (dict(type_mask=+F.Diffuse), diff),
        "nothing": (dict(type_mask=+F.Transmission), 0 * spec),
    }
    for name, (attrs, want) in cases.items():
        ctx = context(**attrs)
        tol = atol(want) if callable(atol) else atol
        np.testing.assert_allclose(eval_np(bsdf, wi, wo, ctx), want * wo[:, 2:3], rtol=rtol,
                                   atol=tol, err_msg=name)
        si, (bs, weight) = sample_bsdf(bsdf, wi[7], 5000, ctx=ctx)
        bpdf = to_np(bs.pdf)
        if name == "nothing":
            assert (to_np(weight) == 0).all() and (bpdf == 0).all()
            if lobe_pdf:
                assert (pdf_np(bsdf, wi, wo, ctx) == 0).all()
            continue
        # a single-lobe context returns the lobe's type broadcast (width 1)
        t = np.broadcast_to(to_np(bs.sampled_type), (5000,))[bpdf > 0]
        glossy = name in ("component0", "glossy_mask")
        assert (t == +bsdf.flags(0 if glossy else 1)).all(), name
        if lobe_pdf:
            _, pdf_ctx = bsdf.eval_pdf(ctx, si, bs.wo)
            np.testing.assert_allclose(bpdf, to_np(pdf_ctx), rtol=1e-6, err_msg=name)
            np.testing.assert_allclose(bpdf, to_np(bsdf.pdf(ctx, si, bs.wo)), rtol=1e-6, err_msg=name)
        if not glossy:
            np.testing.assert_allclose(bpdf[bpdf > 0], to_np(bs.wo)[bpdf > 0, 2] / np.pi, rtol=1e-5)


def check_diffuse_context(bsdf, wi, wo, want, cases, rtol, atol):
    """A BSDF with one diffuse lobe, for each (context attributes, selected) of cases: if
    selected, eval is want (with the cosine), the pdf is positive and every sample is a
    diffuse reflection with a positive weight; if not, eval, pdf and weights are zero."""
    for attrs, on in cases:
        ctx = context(**attrs)
        np.testing.assert_allclose(eval_np(bsdf, wi, wo, ctx), want if on else 0 * want, rtol=rtol,
                                   atol=atol, err_msg=str(attrs))
        assert (pdf_np(bsdf, wi, wo, ctx) > 0).all() == on, attrs
        _, (bs, w) = sample_bsdf(bsdf, wi[3], 1000, ctx=ctx)
        assert ((to_np(w) > 0).all() if on else (to_np(w) == 0).all()), attrs
        if on:
            t = np.broadcast_to(to_np(bs.sampled_type), (1000,))
            assert (t == +(F.DiffuseReflection | F.FrontSide)).all(), attrs


# -- hard cases --------------------------------------------------------------------------------

def check_eval_pdf_finite(bsdf, ctx, wi, wo, tag=""):
    """eval and pdf at every pair are finite and >= 0; returns them."""
    f, pdf = (to_np(x) for x in bsdf.eval_pdf(ctx, interaction(wi), vec(wo)))
    assert np.isfinite(f).all() and (f >= 0).all(), tag
    assert np.isfinite(pdf).all() and (pdf >= 0).all(), tag
    return f, pdf


def check_samples_finite(bsdf, ctx, samples, tag="", unit_wo=True):
    """Samples (arguments from corner_samples) have finite weights and pdfs >= 0 and finite
    directions; with unit_wo, unit vectors."""
    bs, w = bsdf.sample(ctx, *samples)
    w, wo_s, bpdf = to_np(w), to_np(bs.wo), to_np(bs.pdf)
    assert np.isfinite(w).all() and (w >= 0).all(), tag
    assert np.isfinite(bpdf).all() and (bpdf >= 0).all(), tag
    assert np.isfinite(wo_s).all(), tag
    if unit_wo:
        np.testing.assert_allclose(np.linalg.norm(wo_s, axis=1), 1, atol=1e-5, err_msg=tag)


def check_finite_gradients(bsdf, wi, wo, keys=None):
    """The derivatives of the summed eval w.r.t. the parameters `keys` (by default every
    differentiable one) and both directions are finite."""
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
        assert np.isfinite(np.array(g)).all()


# -- parameters through mi.traverse ------------------------------------------------------------

def param_key(params, suffix):
    """The first key of params that ends with suffix."""
    return next(k for k in params.keys() if k.endswith(suffix))


def check_update_changes_render(scene, params, key, value, msg=None):
    """Setting params[key] to value changes the rendered image (same seed)."""
    img0 = np.array(mi.render(scene, spp=4, seed=0))
    params[key] = value
    params.update()
    img1 = np.array(mi.render(scene, spp=4, seed=0))
    assert np.abs(img0 - img1).max() > 1e-3, msg


def working_lobes(bsdf):
    """How many of the BSDF's components do any work: evaluated alone (``ctx.component``),
    a component is non-zero for some pair of directions."""
    wi, wo = mirror_pairs(300, 3, mirrors=20)
    return sum(bool((eval_np(bsdf, wi, wo, context(component=i)) > 0).any())
               for i in range(bsdf.component_count()))


def check_update_changes_lobes(scene, params, key, value, before, after):
    """The sphere's BSDF has `before` working lobes, and `after` once params[key] is set to
    value; its components (which wrappers copy) stay the same."""
    bsdf = scene.shapes()[0].bsdf()
    flags = [bsdf.flags(i) for i in range(bsdf.component_count())]
    assert working_lobes(bsdf) == before
    params[key] = value
    params.update()
    assert working_lobes(bsdf) == after
    assert [bsdf.flags(i) for i in range(bsdf.component_count())] == flags


def check_updates_reuse_kernel(scene, suffix, values):
    """Rendering after setting the parameter ending with suffix to each of values launches
    only kernels from the cache."""
    params = mi.traverse(scene)
    key = param_key(params, suffix)
    dr.eval(mi.render(scene, spp=2))
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()  # clear
        for v in values:
            params[key] = v
            params.update()
            dr.eval(mi.render(scene, spp=2))
        hist = [h for h in dr.kernel_history() if h["type"] == dr.KernelType.JIT]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert hist and all(h.get("cache_hit", False) for h in hist), hist


# -- renders -----------------------------------------------------------------------------------

def check_render(bsdf, integrator="path", res=24, spp=4, lit=True, msg=None):
    """The sphere scene with bsdf (a dict) renders to finite values, and, if lit, not to
    black (mean > 1e-3)."""
    img = np.array(mi.render(small_scene(bsdf, res=res, integrator=integrator), spp=spp))
    assert np.isfinite(img).all(), msg
    if lit:
        assert img.mean() > 1e-3, msg


def check_prb_gradients(scene, suffixes, nonzero=True):
    """The scene renders with the prb integrator; the gradients of the mean pixel w.r.t. the
    parameters ending with suffixes are finite (and, with nonzero, not all zero)."""
    params = mi.traverse(scene)
    keys = [param_key(params, s) for s in suffixes]
    dr.enable_grad(*(params[k] for k in keys))
    params.update()
    img = mi.render(scene, params, spp=4)
    dr.backward(dr.mean(img, axis=None))
    for key in keys:
        g = np.array(dr.grad(params[key]))
        assert np.isfinite(g).all(), key
        if nonzero:
            assert np.abs(g).max() > 0, key


def check_spectral_eval_and_render(variant, bsdf, wi=(0, 0, 1), wo=(0.6, 0, 0.8), scene_bsdf=None):
    """In a spectral variant, bsdf (a dict) evaluates to finite positive values at four
    wavelengths and, in an llvm variant, the sphere with scene_bsdf (by default the plugin
    with its defaults) renders, not black."""
    mi.set_variant(variant)
    b = mi.load_dict(bsdf)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(*wi)
    si.wavelengths = mi.Spectrum(450, 500, 600, 650)
    v = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(*wo)))
    assert np.isfinite(v).all() and (v > 0).all()
    if variant.startswith("llvm"):
        check_render(scene_bsdf or {"type": bsdf["type"]}, res=8, spp=2)
