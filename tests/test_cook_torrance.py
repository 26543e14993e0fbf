"""The cook_torrance plugin: eval, pdf, sampling, energy, lobes, parameters, renders, and
agreement with Mitsuba's roughconductor where the two models coincide."""
import itertools

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

from conftest import interaction, random_upper, sample_bsdf, small_scene, sph, to_np, vec

PLUGIN = "cook_torrance"
DISTS = ["beckmann", "blinn", "ggx"]
GEOMS = ["cook_torrance", "ggx"]
COMBOS = list(itertools.product(DISTS, GEOMS))
F = mi.BSDFFlags


# -- float64 transcription of the lecture's Cook-Torrance -----------------------------------

def ref_cook_torrance(l, v, m_d, m_s, k, rho, f0, dist, geom):
    """The lecture's f_r(l, v) without the cosine: (specular, diffuse), each (N, C).

    The diffuse term carries 1/pi (MODELS.md); everything else is the lecture's slide."""
    l, v = np.asarray(l, float), np.asarray(v, float)
    m_d = np.atleast_1d(np.asarray(m_d, float))[None, :]
    m_s = np.atleast_1d(np.asarray(m_s, float))[None, :]
    f0 = np.atleast_1d(np.asarray(f0, float))[None, :]
    h = l + v
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    nh, nl, nv, vh = h[:, 2], l[:, 2], v[:, 2], np.sum(v * h, axis=1)
    alpha = np.arccos(np.clip(nh, -1, 1))
    if dist == "beckmann":
        D = np.exp(-(np.tan(alpha) / rho) ** 2) / (np.pi * rho ** 2 * np.cos(alpha) ** 4)
    elif dist == "blinn":
        D = nh ** (2 / rho ** 2 - 2) / (np.pi * rho ** 2)
    else:
        D = rho ** 2 / (np.pi * (nh ** 2 * (rho ** 2 - 1) + 1) ** 2)
    Fr = f0 + (1 - f0) * (1 - np.clip(vh, 0, 1))[:, None] ** 5
    if geom == "cook_torrance":
        G = np.minimum(1, np.minimum(2 * nh * nv / vh, 2 * nh * nl / vh))
    else:
        g = lambda c: 2 / (1 + np.sqrt(1 + rho ** 2 * (1 - c ** 2) / c ** 2))
        G = g(nv) * g(nl)
    spec = (1 - k) * m_s * Fr * (D * G / (4 * nl * nv))[:, None]
    diff = k * m_d / np.pi + 0 * spec
    return spec, diff


def load(**kw):
    d = {"type": PLUGIN}
    for key, val in kw.items():
        d[key] = {"type": "rgb", "value": val} if isinstance(val, (list, tuple)) else val
    return mi.load_dict(d)


def eval_np(bsdf, wi, wo, ctx=None):
    return to_np(bsdf.eval(ctx or mi.BSDFContext(), interaction(wi), vec(wo)))


def pdf_np(bsdf, wi, wo, ctx=None):
    return to_np(bsdf.pdf(ctx or mi.BSDFContext(), interaction(wi), vec(wo)))


def unit_f32(d):
    d = np.asarray(d, float).astype(np.float32).astype(float)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


PARAMS = [
    dict(m_d=[0.5, 0.5, 0.5], m_s=[1.0, 1.0, 1.0], k=0.5, rho=0.3, f0=[0.04, 0.04, 0.04]),
    dict(m_d=[0.7, 0.2, 0.1], m_s=[0.9, 0.6, 0.3], k=0.2, rho=0.08, f0=[0.9, 0.7, 0.4]),
    dict(m_d=[0.0, 0.0, 0.0], m_s=[1.0, 0.8, 0.6], k=0.0, rho=0.6, f0=[1.0, 1.0, 1.0]),
    dict(m_d=[0.3, 0.6, 0.9], m_s=[0.5, 0.5, 0.5], k=0.8, rho=1.0, f0=[0.0, 0.0, 0.0]),
]


def bsdf_of(p, dist, geom, **extra):
    return load(diffuse_reflectance=p["m_d"], specular_reflectance=p["m_s"], k=p["k"],
                roughness=p["rho"], f0=p["f0"], distribution=dist, geometry=geom, **extra)


def eval_pairs(n=3000, seed=7):
    rng = np.random.default_rng(seed)
    wi, wo = random_upper(rng, n), random_upper(rng, n)
    # mirror pairs (h = n) and the normal
    wi = np.concatenate([wi, wi[:100], [[0, 0, 1]]])
    wo = np.concatenate([wo, wi[:100] * [-1, -1, 1], [[0, 0, 1]]])
    return unit_f32(wi), unit_f32(wo)


# -- eval against the float64 transcription ---------------------------------------------------

@pytest.mark.parametrize("dist,geom", COMBOS)
@pytest.mark.parametrize("pi", range(len(PARAMS)))
def test_eval_matches_reference(dist, geom, pi):
    p = PARAMS[pi]
    wi, wo = eval_pairs()
    spec, diff = ref_cook_torrance(wo, wi, p["m_d"], p["m_s"], p["k"], p["rho"], p["f0"], dist, geom)
    want = (spec + diff) * wo[:, 2:3]
    got = eval_np(bsdf_of(p, dist, geom), wi, wo)
    np.testing.assert_allclose(got, want, rtol=5e-4, atol=1e-6 * want.max())


def test_eval_below_horizon_and_backfacing_is_zero():
    b = load()
    wi = np.array([[0, 0, 1], [0.6, 0, -0.8], [0.6, 0, 0.8], [0, 0, 1], [1, 0, 0]])
    wo = np.array([[0.6, 0, -0.8], [0, 0, 1], [-0.6, 0, -0.8], [0, 0, -1], [-1, 0, 0]])
    assert (eval_np(b, wi, wo) == 0).all()
    assert (pdf_np(b, wi, wo) == 0).all()


@pytest.mark.parametrize("dist,geom", COMBOS)
def test_reciprocity(dist, geom):
    rng = np.random.default_rng(3)
    a, b = random_upper(rng, 3000), random_upper(rng, 3000)
    for p in PARAMS[:2]:
        bsdf = bsdf_of(p, dist, geom)
        f_ab = eval_np(bsdf, a, b) / b[:, 2:3].astype(np.float32)
        f_ba = eval_np(bsdf, b, a) / a[:, 2:3].astype(np.float32)
        np.testing.assert_allclose(f_ab, f_ba, rtol=1e-3, atol=1e-6 * f_ab.max())


# -- the same model as Mitsuba's roughconductor --------------------------------------------------

@pytest.mark.parametrize("visible", [True, False])
@pytest.mark.parametrize("alpha", [0.05, 0.3, 1.0])
def test_ggx_metal_matches_roughconductor(alpha, visible):
    """k = 0, m_S = 1, F0 = 1 (F = 1), D and G GGX: Mitsuba's roughconductor with a perfect
    conductor ('material': 'none' gives F = 1) and alpha = rho, in eval, pdf and albedo."""
    ours = load(k=0.0, specular_reflectance=1.0, f0=1.0, roughness=alpha, distribution="ggx",
                geometry="ggx", sample_visible=visible)
    theirs = mi.load_dict({"type": "roughconductor", "distribution": "ggx", "alpha": alpha,
                           "material": "none", "sample_visible": visible})
    wi, wo = eval_pairs(4000, seed=11)
    f_t = eval_np(theirs, wi, wo)
    np.testing.assert_allclose(eval_np(ours, wi, wo), f_t, rtol=2e-4, atol=1e-6 * f_t.max())
    p_t = pdf_np(theirs, wi, wo)
    np.testing.assert_allclose(pdf_np(ours, wi, wo), p_t, rtol=2e-4, atol=1e-6 * p_t.max())
    for theta in (0, 60, 88):
        a_o, e_o = albedo(ours, theta, n=200_000, seed=1)
        a_t, e_t = albedo(theirs, theta, n=200_000, seed=2)
        assert np.all(np.abs(a_o - a_t) <= 5 * np.hypot(e_o, e_t) + 1e-4), (theta, a_o, a_t)


# -- sampling ------------------------------------------------------------------------------

CHI2 = [
    # (name, params, theta_i degrees, ires)
    ("beckmann_ct_mixed", dict(distribution="beckmann", geometry="cook_torrance"), 30, 16),
    ("beckmann_ggx_metal_grazing", dict(distribution="beckmann", geometry="ggx", k=0.0, roughness=0.1), 85, 64),
    ("blinn_ct_metal", dict(distribution="blinn", geometry="cook_torrance", k=0.0, roughness=0.15, f0=0.5), 45, 32),
    ("blinn_ggx_mixed_grazing", dict(distribution="blinn", geometry="ggx", roughness=0.5, f0=0.3), 87, 16),
    ("ggx_ct_visible_grazing", dict(distribution="ggx", geometry="cook_torrance", k=0.0, roughness=0.2), 80, 32),
    ("ggx_ggx_visible", dict(distribution="ggx", geometry="ggx", roughness=0.3, f0=0.5), 0, 16),
    ("ggx_ggx_visible_89", dict(distribution="ggx", geometry="ggx", k=0.0, roughness=0.5), 89, 16),
    ("ggx_ggx_d_sampling", dict(distribution="ggx", geometry="ggx", k=0.0, roughness=0.3, sample_visible=False), 60, 16),
    ("ggx_ct_d_sampling_mixed", dict(distribution="ggx", geometry="cook_torrance", roughness=0.7, sample_visible=False), 75, 8),
    ("rough_one", dict(distribution="beckmann", geometry="cook_torrance", roughness=1.0, f0=1.0), 50, 8),
    ("diffuse_only", dict(k=1.0), 40, 8),
    ("diffuse_component", dict(component=1, roughness=0.2), 70, 8),
]


@pytest.mark.parametrize("name,params,theta,ires", CHI2, ids=[c[0] for c in CHI2])
def test_chi2(name, params, theta, ires):
    wi = sph(np.radians(theta), 0.3)[0]
    params = dict(params)
    ctx = mi.BSDFContext()
    if "component" in params:
        ctx.component = params.pop("component")
    sample_func, pdf_func = BSDFAdapter(PLUGIN, {"type": PLUGIN, **params},
                                        wi=mi.Vector3f(*map(float, wi)), ctx=ctx)
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func,
                         pdf_func=pdf_func, sample_dim=3, res=161, ires=ires)
    assert test.run(), test.messages


@pytest.mark.parametrize("dist,geom", COMBOS)
def test_sample_weight_is_eval_over_pdf(dist, geom):
    ctx = mi.BSDFContext()
    for p, theta in itertools.product(PARAMS[:3], [0, 40, 80, 89]):
        bsdf = bsdf_of(p, dist, geom)
        si, (bs, weight) = sample_bsdf(bsdf, sph(np.radians(theta), 1.0)[0], 20000)
        f, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
        w, f, pdf, bpdf = to_np(weight), to_np(f), to_np(pdf), to_np(bs.pdf)
        ok = bpdf > 0
        assert ok.mean() > 0.3, (p, theta)
        np.testing.assert_allclose(bpdf[ok], pdf[ok], rtol=1e-5)
        np.testing.assert_allclose(w[ok], f[ok] / pdf[ok, None], rtol=1e-4, atol=1e-7)
        assert (w[~ok] == 0).all()
        np.testing.assert_array_equal(f, to_np(bsdf.eval(ctx, si, bs.wo)))
        np.testing.assert_array_equal(pdf, to_np(bsdf.pdf(ctx, si, bs.wo)))


def albedo(bsdf, theta, n=300_000, seed=0, ctx=None):
    """Monte Carlo directional albedo (mean sample weight) and its standard error."""
    _, (bs, weight) = sample_bsdf(bsdf, sph(np.radians(theta), 0.7)[0], n, seed=seed, ctx=ctx)
    w = to_np(weight)
    return w.mean(axis=0), w.std(axis=0) / np.sqrt(n)


THETAS = [0, 30, 60, 75, 85, 89]


@pytest.mark.parametrize("dist,geom", COMBOS)
def test_white_furnace_specular(dist, geom):
    """F = 1 (f0 = 1), k = 0: the microfacet lobe reflects at most what it receives, and all
    of it for a smooth surface away from grazing."""
    for rho in (1e-4, 0.1, 0.5, 1.0):
        b = load(k=0.0, f0=1.0, roughness=rho, distribution=dist, geometry=geom)
        for theta in THETAS:
            a, err = albedo(b, theta)
            assert np.isfinite(a).all()
            assert (a <= 1 + 4 * err + 1e-3).all(), (rho, theta, a, err)
            if rho == 1e-4 or (rho == 0.1 and theta <= 30):
                assert (a >= 0.98).all(), (rho, theta, a)


@pytest.mark.parametrize("params", [
    dict(),
    dict(diffuse_reflectance=1.0, k=0.5, f0=1.0, roughness=0.2),
    dict(diffuse_reflectance=1.0, k=0.3, f0=0.5, distribution="ggx", geometry="ggx"),
])
def test_white_furnace_mixed(params):
    b = load(**params)
    for theta in THETAS:
        a, err = albedo(b, theta)
        assert (a <= 1 + 4 * err + 1e-3).all(), (theta, a, err)


def test_white_furnace_lambert():
    """k = 1: a white Lambertian surface reflects everything (the 1/pi of MODELS.md)."""
    b = load(k=1.0, diffuse_reflectance=1.0)
    for theta in THETAS:
        a, err = albedo(b, theta, n=100_000)
        np.testing.assert_allclose(a, 1, atol=1e-5)


# -- flags, components, contexts -----------------------------------------------------------

def test_flags_and_components():
    b = load()
    assert b.component_count() == 2
    assert b.flags(0) == F.GlossyReflection | F.FrontSide
    assert b.flags(1) == F.DiffuseReflection | F.FrontSide
    assert b.flags() == b.flags(0) | b.flags(1)
    for kw in (dict(k=0.0), dict(diffuse_reflectance=0.0)):
        metal = load(**kw)
        assert metal.component_count() == 1 and metal.flags() == b.flags(0), kw
    for kw in (dict(k=1.0), dict(specular_reflectance=0.0)):
        matte = load(**kw)
        assert matte.component_count() == 1 and matte.flags() == b.flags(1), kw
    # f0 = 0 keeps the specular lobe: Schlick's F grows to 1 at grazing angles
    assert load(f0=0.0).component_count() == 2
    assert load(k=1e-6, diffuse_reflectance=1e-6).component_count() == 2
    black = load(k=1.0, diffuse_reflectance=0.0)
    assert black.component_count() == 0 and black.flags() == F.Empty
    _, (bs, w) = sample_bsdf(black, [0, 0, 1], 100)
    assert (to_np(w) == 0).all() and (to_np(bs.pdf) == 0).all()
    assert (eval_np(black, [[0, 0, 1]], [[0.6, 0, 0.8]]) == 0).all()


def test_context_selects_lobes():
    p = PARAMS[1]
    b = bsdf_of(p, "ggx", "cook_torrance")
    rng = np.random.default_rng(5)
    wi, wo = unit_f32(random_upper(rng, 500)), unit_f32(random_upper(rng, 500))
    spec, diff = ref_cook_torrance(wo, wi, p["m_d"], p["m_s"], p["k"], p["rho"], p["f0"],
                                   "ggx", "cook_torrance")
    cases = {
        "component0": (dict(component=0), spec),
        "component1": (dict(component=1), diff),
        "glossy_mask": (dict(type_mask=+F.Glossy), spec),
        "diffuse_mask": (dict(type_mask=+F.Diffuse), diff),
        "nothing": (dict(type_mask=+F.Transmission), 0 * spec),
    }
    for name, (attrs, want) in cases.items():
        ctx = mi.BSDFContext()
        for key, val in attrs.items():
            setattr(ctx, key, val)
        np.testing.assert_allclose(eval_np(b, wi, wo, ctx), want * wo[:, 2:3], rtol=1e-3,
                                   atol=1e-6, err_msg=name)
        si, (bs, weight) = sample_bsdf(b, wi[7], 5000, ctx=ctx)
        bpdf = to_np(bs.pdf)
        if name == "nothing":
            assert (to_np(weight) == 0).all() and (bpdf == 0).all()
            continue
        t = np.broadcast_to(to_np(bs.sampled_type), (5000,))[bpdf > 0]
        glossy = name in ("component0", "glossy_mask")
        assert (t == +b.flags(0 if glossy else 1)).all(), name
        if not glossy:
            np.testing.assert_allclose(bpdf[bpdf > 0], to_np(bs.wo)[bpdf > 0, 2] / np.pi, rtol=1e-5)


# -- textures and parameters ---------------------------------------------------------------

def write_bitmap(path, value, res=4):
    arr = np.full((res, res, np.size(value)), value, dtype=np.float32)
    mi.Bitmap(arr).write(str(path))
    return str(path)


def test_texture_parameters(tmp_path):
    values = {"diffuse_reflectance": [0.5, 0.3, 0.1], "specular_reflectance": [0.9, 0.7, 0.5],
              "k": 0.4, "roughness": 0.25, "f0": [0.2, 0.4, 0.6]}
    tex = lambda f: {"type": "bitmap", "filename": f, "raw": True, "filter_type": "nearest"}
    textured = mi.load_dict({"type": PLUGIN, "distribution": "ggx", **{
        name: tex(write_bitmap(tmp_path / f"{name}.exr", v)) for name, v in values.items()}})
    const = load(distribution="ggx", **values)
    assert textured.flags() & F.SpatiallyVarying
    rng = np.random.default_rng(11)
    wi, wo = random_upper(rng, 1000), random_upper(rng, 1000)
    np.testing.assert_allclose(eval_np(textured, wi, wo), eval_np(const, wi, wo), rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(pdf_np(textured, wi, wo), pdf_np(const, wi, wo), rtol=1e-5, atol=1e-7)
    bad = write_bitmap(tmp_path / "bad.exr", 1.5)
    with pytest.raises(RuntimeError, match=r"cook_torrance.*roughness.*\[0, 1\]"):
        mi.load_dict({"type": PLUGIN, "roughness": tex(bad)})


BAD = [
    ({"roughness": -0.1}, r"cook_torrance: parameter 'roughness' must be a roughness in \[0, 1\] \(got -0.1"),
    ({"roughness": 1.5}, r"parameter 'roughness' must be a roughness in \[0, 1\]"),
    ({"roughness": float("nan")}, r"parameter 'roughness'.*\(got nan"),
    ({"k": 1.2}, r"parameter 'k' must be a weight in \[0, 1\]"),
    ({"k": -0.5}, r"parameter 'k' must be a weight in \[0, 1\]"),
    ({"f0": 1.5}, r"parameter 'f0' must be a reflectance in \[0, 1\]"),
    ({"diffuse_reflectance": {"type": "rgb", "value": [0.2, 1.2, 0.3]}},
     r"parameter 'diffuse_reflectance' must be a reflectance in \[0, 1\]"),
    ({"specular_reflectance": -0.1}, r"parameter 'specular_reflectance' must be a reflectance"),
    ({"distribution": "phong"},
     r"parameter 'distribution' must be one of 'beckmann', 'blinn', 'ggx' \(got 'phong'\)"),
    ({"geometry": "smith"}, r"parameter 'geometry' must be one of 'cook_torrance', 'ggx' \(got 'smith'\)"),
    ({"sample_visible": "yes"}, r"parameter 'sample_visible' must be a boolean \(true or false\) \(got 'yes'\)"),
    ({"sample_visible": 1}, r"parameter 'sample_visible' must be a boolean"),
]


@pytest.mark.parametrize("params,msg", BAD)
def test_bad_parameters_raise_at_load(params, msg):
    with pytest.raises(RuntimeError, match=msg):
        mi.load_dict({"type": PLUGIN, **params})


def test_parameters_from_xml():
    xml = ('<bsdf version="3.0.0" type="cook_torrance"><string name="distribution" value="ggx"/>'
           '<boolean name="sample_visible" value="false"/><float name="roughness" value="0.2"/></bsdf>')
    b = mi.load_string(xml)
    assert "sample_visible = False" in str(b) and "distribution = ggx" in str(b)
    xml = '<bsdf version="3.0.0" type="cook_torrance"><float name="k" value="2"/></bsdf>'
    with pytest.raises(RuntimeError, match=r"cook_torrance: parameter 'k' must be a weight in \[0, 1\]"):
        mi.load_string(xml)
    xml = '<bsdf version="3.0.0" type="cook_torrance"><string name="geometry" value="beckmann"/></bsdf>'
    with pytest.raises(RuntimeError, match=r"parameter 'geometry' must be one of"):
        mi.load_string(xml)


# -- hard cases stay finite ----------------------------------------------------------------

def hard_directions():
    eps = 1e-7
    g = np.sqrt(1 - eps * eps)
    d = np.array([
        [0, 0, 1], [g, 0, eps], [0, g, eps], [-g, 0, eps], [1, 0, 0], [0, -1, 0],
        [0.6, 0, 0.8], [-0.6, 0, 0.8], [0, 0.6, 0.8], [0, -0.6, 0.8],
        [0.3, 0.4, -np.sqrt(0.75)], [0, 0, -1], [0.577, 0.577, 0.578],
    ], float)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


@pytest.mark.parametrize("dist,geom", COMBOS)
def test_stability_grid(dist, geom):
    d = hard_directions()
    pairs = np.array(list(itertools.product(range(len(d)), repeat=2)))
    wi = np.concatenate([d[pairs[:, 0]], -d[:10]])  # wi = -wo as well
    wo = np.concatenate([d[pairs[:, 1]], d[:10]])
    u1 = np.array([0, 1e-7, 0.25, 0.5, 0.75, 1 - 2**-24])
    u2 = np.array([0, 1e-7, 0.5, 1 - 2**-24])
    g1, g2, g3, gi = np.meshgrid(u1, u1, u2, np.arange(len(d)), indexing="ij")
    si_s = interaction(d[gi.ravel()])
    s1, s2 = mi.Float(g1.ravel()), mi.Point2f(g2.ravel(), g3.ravel())
    ctx = mi.BSDFContext()
    visibles = [True, False] if dist == "ggx" else [True]
    for rho, f0, k, visible in itertools.product([0.0, 1e-4, 1.0], [0.0, 1.0], [0.0, 0.5], visibles):
        b = load(roughness=rho, f0=f0, k=k, diffuse_reflectance=1.0, distribution=dist,
                 geometry=geom, sample_visible=visible)
        tag = f"rho={rho} f0={f0} k={k} visible={visible}"
        f, pdf = b.eval_pdf(ctx, interaction(wi), vec(wo))
        f, pdf = to_np(f), to_np(pdf)
        assert np.isfinite(f).all() and (f >= 0).all(), tag
        assert np.isfinite(pdf).all() and (pdf >= 0).all(), tag
        bs, w = b.sample(ctx, si_s, s1, s2)
        w, wo_s, bpdf = to_np(w), to_np(bs.wo), to_np(bs.pdf)
        assert np.isfinite(w).all() and (w >= 0).all(), tag
        assert np.isfinite(bpdf).all() and (bpdf >= 0).all(), tag
        assert np.isfinite(wo_s).all(), tag
        np.testing.assert_allclose(np.linalg.norm(wo_s, axis=1), 1, atol=1e-5, err_msg=tag)


@pytest.mark.parametrize("dist", DISTS)
def test_smooth_limit_is_a_mirror(dist):
    """rho = 1e-4: the samples leave within ~1e-3 rad of the mirror direction with weight F."""
    b = load(k=0.0, f0=1.0, roughness=1e-4, distribution=dist, geometry="ggx")
    wi = sph(np.radians(30), 0.0)[0]
    _, (bs, w) = sample_bsdf(b, wi, 50_000)
    wo = to_np(bs.wo)
    spread = np.arccos(np.clip(wo @ sph(np.radians(30), np.pi)[0], -1, 1))
    assert np.quantile(spread, 0.99) < 2e-3
    np.testing.assert_allclose(to_np(w), 1, atol=2e-3)


# -- parameters through mi.traverse ----------------------------------------------------------

def test_traverse_exposes_parameters_and_updates():
    scene = small_scene({"type": PLUGIN, "id": "mat", "k": 0.0}, res=16)
    params = mi.traverse(scene)
    keys = {}
    for name in ("diffuse_reflectance", "specular_reflectance", "k", "roughness", "f0"):
        keys[name] = next(key for key in params.keys() if key.endswith(f"{name}.value"))
        assert not params.flags(keys[name]) & mi.ParamFlags.NonDifferentiable.value, name
    img0 = np.array(mi.render(scene, spp=4, seed=0))
    params[keys["roughness"]] = 0.6
    params.update()
    img1 = np.array(mi.render(scene, spp=4, seed=0))
    assert np.abs(img0 - img1).max() > 1e-3
    bsdf = scene.shapes()[0].bsdf()
    assert bsdf.component_count() == 1
    params[keys["k"]] = 0.5  # the diffuse lobe comes back
    params.update()
    assert bsdf.component_count() == 2


def test_parameter_change_reuses_kernel():
    scene = small_scene({"type": PLUGIN, "distribution": "ggx"}, res=16)
    params = mi.traverse(scene)
    key = next(k for k in params.keys() if k.endswith("roughness.value"))
    dr.eval(mi.render(scene, spp=2))
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()
        for v in (0.5, 0.7):
            params[key] = v
            params.update()
            dr.eval(mi.render(scene, spp=2))
        hist = [h for h in dr.kernel_history() if h["type"] == dr.KernelType.JIT]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert hist and all(h.get("cache_hit", False) for h in hist), hist


# -- renders -------------------------------------------------------------------------------

RENDER_CONFIGS = {
    "default": dict(),
    "blinn_ggx": dict(distribution="blinn", geometry="ggx", roughness=0.2),
    "ggx_ct": dict(distribution="ggx", geometry="cook_torrance", roughness=0.4),
    "ggx_metal_visible": dict(distribution="ggx", geometry="ggx", k=0.0,
                              f0={"type": "rgb", "value": [0.9, 0.6, 0.3]}),
    "ggx_metal_d": dict(distribution="ggx", geometry="ggx", k=0.0, sample_visible=False),
    "mirror_like": dict(k=0.0, f0=1.0, roughness=1e-4),
    "rough": dict(roughness=1.0, distribution="beckmann", geometry="ggx"),
    "matte": dict(k=1.0),
}


@pytest.mark.parametrize("integrator", ["path", "direct"])
@pytest.mark.parametrize("name", list(RENDER_CONFIGS))
def test_render_llvm(name, integrator):
    scene = small_scene({"type": PLUGIN, **RENDER_CONFIGS[name]}, integrator=integrator)
    img = np.array(mi.render(scene, spp=4))
    assert np.isfinite(img).all()
    assert img.mean() > 1e-3


def test_render_black_material():
    """No lobe at all (k = 1, m_D = 0): renders, and the sphere is black."""
    scene = small_scene({"type": PLUGIN, "k": 1.0, "diffuse_reflectance": 0.0}, res=8)
    img = np.array(mi.render(scene, spp=2))
    assert np.isfinite(img).all()


def test_render_prb_with_gradient():
    scene = small_scene({"type": PLUGIN, "distribution": "ggx"}, integrator="prb", res=12)
    params = mi.traverse(scene)
    key = next(k for k in params.keys() if k.endswith("roughness.value"))
    dr.enable_grad(params[key])
    params.update()
    img = mi.render(scene, params, spp=4)
    dr.backward(dr.mean(img, axis=None))
    g = np.array(dr.grad(params[key]))
    assert np.isfinite(g).all() and np.abs(g).max() > 0


def test_render_scalar_rgb():
    mi.set_variant("scalar_rgb")
    scene = small_scene({"type": PLUGIN, "distribution": "ggx", "roughness": 0.2}, res=6)
    img = np.array(mi.render(scene, spp=2))
    assert np.isfinite(img).all() and img.mean() > 1e-3


@pytest.mark.parametrize("variant", ["llvm_ad_spectral", "scalar_spectral"])
def test_spectral_variants(variant):
    mi.set_variant(variant)
    b = mi.load_dict({"type": PLUGIN, "f0": {"type": "rgb", "value": [0.9, 0.5, 0.2]},
                      "distribution": "ggx"})
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(0, 0, 1)
    si.wavelengths = mi.Spectrum(450, 500, 600, 650)
    v = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(0.6, 0, 0.8)))
    assert np.isfinite(v).all() and (v > 0).all()
    if variant.startswith("llvm"):
        img = np.array(mi.render(small_scene({"type": PLUGIN}, res=8), spp=2))
        assert np.isfinite(img).all() and img.mean() > 1e-3
