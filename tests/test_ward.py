"""The ward plugin: eval, pdf, sampling, energy, anisotropy, lobes, parameters, renders."""
import itertools

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

from conftest import interaction, random_upper, sample_bsdf, small_scene, sph, to_np, vec
from test_phong import as_f32_unit, bitmap, colour, eval_np, hard_directions, pdf_np, unit, write_bitmap

PLUGIN = "ward"
F = mi.BSDFFlags


def ward_reference(wi, wo, rs, rd, au, av):
    """The lecture's Ward model (first form, with angles), l = wo, v = wi, and the diffuse
    term rho_d / pi: (specular f, diffuse f), float64, without the cosine."""
    l, v = np.asarray(wo, float), np.asarray(wi, float)
    h = unit(l + v)
    delta = np.arccos(np.clip(h[:, 2], -1, 1))
    phi = np.arctan2(h[:, 1], h[:, 0])
    with np.errstate(over="ignore"):
        e = np.exp(-np.tan(delta) ** 2 * (np.cos(phi) ** 2 / au ** 2 + np.sin(phi) ** 2 / av ** 2))
    spec = colour(rs) * (e / (4 * np.pi * au * av * np.sqrt(l[:, 2] * v[:, 2])))[:, None]
    diff = colour(rd) / np.pi * np.ones((len(l), 1))
    return spec, diff


def load(**kw):
    d = {"type": PLUGIN}
    for k, v in kw.items():
        d[k] = {"type": "rgb", "value": v} if isinstance(v, (list, tuple)) else v
    return mi.load_dict(d)


def bsdf_of(p):
    return load(specular_reflectance=p["rs"], diffuse_reflectance=p["rd"],
                alpha_u=p["au"], alpha_v=p["av"])


def albedo(bsdf, wi, n=300_000, seed=0, ctx=None):
    _, (_, weight) = sample_bsdf(bsdf, wi, n, seed=seed, ctx=ctx)
    w = to_np(weight)
    return w.mean(axis=0), w.std(axis=0) / np.sqrt(n)


PARAMS = [
    dict(rs=[0.2, 0.2, 0.2], rd=[0.5, 0.5, 0.5], au=0.1, av=0.1),
    dict(rs=[0.9, 0.6, 0.3], rd=[0.0, 0.0, 0.0], au=0.05, av=0.3),
    dict(rs=[0.3, 0.4, 0.5], rd=[0.6, 0.2, 0.1], au=0.3, av=0.05),
    dict(rs=[1.0, 1.0, 1.0], rd=[0.0, 0.0, 0.0], au=1.0, av=1.0),
    dict(rs=[0.5, 0.5, 0.5], rd=[0.5, 0.5, 0.5], au=1e-3, av=0.2),
    dict(rs=[0.0, 0.0, 0.0], rd=[1.0, 1.0, 1.0], au=0.1, av=0.1),
]


# -- eval against the float64 transcription ----------------------------------------------------

@pytest.mark.parametrize("p", PARAMS)
def test_eval_matches_reference(p):
    rng = np.random.default_rng(7)
    wi, wo = random_upper(rng, 4000), random_upper(rng, 4000)
    # exact mirror pairs (h = n), the normal, and directions near the mirror (the lobe)
    near = unit(wi[:1000] * [-1, -1, 1] + rng.normal(scale=[p["au"], p["av"], 0], size=(1000, 3)))
    near[:, 2] = np.abs(near[:, 2])
    wi = np.concatenate([wi, wi[:200], [[0, 0, 1]], wi[:1000]])
    wo = np.concatenate([wo, wi[:200] * [-1, -1, 1], [[0, 0, 1]], near])
    wi32, wo32 = as_f32_unit(wi), as_f32_unit(wo)
    spec, diff = ward_reference(wi32, wo32, p["rs"], p["rd"], p["au"], p["av"])
    want = (spec + diff) * wo32[:, 2:3]
    got = eval_np(bsdf_of(p), wi, wo)
    np.testing.assert_allclose(got, want, rtol=5e-4, atol=1e-6 * want.max())


def test_below_horizon_and_backfacing_is_zero():
    b = load(alpha_u=1.0, alpha_v=1.0)
    wi = np.array([[0, 0, 1], [0.6, 0, -0.8], [0.6, 0, 0.8], [0, 0, 1], [1, 0, 0]])
    wo = np.array([[0.6, 0, -0.8], [0, 0, 1], [-0.6, 0, -0.8], [0, 0, -1], [-1, 0, 0]])
    assert (eval_np(b, wi, wo) == 0).all()
    assert (pdf_np(b, wi, wo) == 0).all()


@pytest.mark.parametrize("p", PARAMS[:4])
def test_reciprocity(p):
    rng = np.random.default_rng(3)
    a, b = random_upper(rng, 3000), random_upper(rng, 3000)
    bsdf = bsdf_of(p)
    f_ab = eval_np(bsdf, a, b) / b[:, 2:3].astype(np.float32)
    f_ba = eval_np(bsdf, b, a) / a[:, 2:3].astype(np.float32)
    np.testing.assert_allclose(f_ab, f_ba, rtol=1e-3, atol=1e-6 * f_ab.max())
    # importance transport gives the same values (the model is reciprocal)
    ctx = mi.BSDFContext(mi.TransportMode.Importance)
    np.testing.assert_array_equal(eval_np(bsdf, a, b, ctx), eval_np(bsdf, a, b))


def test_anisotropy_follows_u_and_v():
    """alpha_u stretches the highlight along u (the shape's dP/du), alpha_v along v."""
    b = load(diffuse_reflectance=0.0, alpha_u=0.05, alpha_v=0.3)
    wi = sph(np.radians(30), 0.0)
    tilt = np.radians(12)  # h tilts by ~6 degrees: tan = 0.1 = 2 alpha_u = alpha_v / 3
    along_u = sph(np.radians(30) + tilt, np.pi)                   # in the u-n plane
    m = sph(np.radians(30), np.pi)[0]
    along_v = unit(np.cos(tilt) * m + np.sin(tilt) * np.array([0, 1, 0]))[None]
    fu = eval_np(b, wi, along_u)[0, 0]
    fv = eval_np(b, wi, along_v)[0, 0]
    assert fv > 10 * fu, (fu, fv)
    # the sampled directions spread along v
    _, (bs, _) = sample_bsdf(b, wi[0], 50_000)
    wo = to_np(bs.wo)
    assert np.std(wo[:, 1]) > 3 * np.std(wo[:, 0])
    # swapping the alphas turns the lobe by 90 degrees
    b2 = load(diffuse_reflectance=0.0, alpha_u=0.3, alpha_v=0.05)
    wi_v = sph(np.radians(30), np.pi / 2)
    along_u2 = sph(np.radians(30) + tilt, -np.pi / 2)              # in the v-n plane
    np.testing.assert_allclose(eval_np(b2, wi_v, along_u2)[0, 0], fu, rtol=1e-3)


# -- sampling --------------------------------------------------------------------------------

CHI2 = [
    # (name, params, theta_i degrees, ires)
    ("mixed_0", dict(alpha_u=0.1, alpha_v=0.1, specular_reflectance=0.5, diffuse_reflectance=0.5), 0, 32),
    ("aniso_45", dict(alpha_u=0.05, alpha_v=0.3, specular_reflectance=0.8, diffuse_reflectance=0.0), 45, 64),
    ("aniso_mixed_80", dict(alpha_u=0.3, alpha_v=0.05, specular_reflectance=0.4, diffuse_reflectance=0.6), 80, 64),
    ("rough_89", dict(alpha_u=0.5, alpha_v=0.5, specular_reflectance=1.0, diffuse_reflectance=0.0), 89, 16),
    ("mixed_89", dict(alpha_u=0.2, alpha_v=0.1, specular_reflectance=0.5, diffuse_reflectance=0.5), 89, 32),
    ("broad_30", dict(alpha_u=1.0, alpha_v=1.0, specular_reflectance=1.0, diffuse_reflectance=0.0), 30, 8),
    ("pure_diffuse", dict(specular_reflectance=0.3, diffuse_reflectance=0.7, component=1), 60, 8),
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


@pytest.mark.parametrize("p", PARAMS)
@pytest.mark.parametrize("theta", [0, 45, 80, 89])
def test_sample_weight_is_eval_over_pdf(p, theta):
    bsdf = bsdf_of(p)
    wi = sph(np.radians(theta), 1.0)[0]
    n = 20000
    si, (bs, weight) = sample_bsdf(bsdf, wi, n)
    ctx = mi.BSDFContext()
    f, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
    w, f, pdf, bpdf = to_np(weight), to_np(f), to_np(pdf), to_np(bs.pdf)
    ok = bpdf > 0
    assert ok.mean() > 0.3
    np.testing.assert_allclose(bpdf[ok], pdf[ok], rtol=1e-5)
    np.testing.assert_allclose(w[ok], f[ok] / pdf[ok, None], rtol=1e-4, atol=1e-7)
    assert (w[~ok] == 0).all()
    np.testing.assert_allclose(np.linalg.norm(to_np(bs.wo), axis=1), 1, atol=1e-5)
    np.testing.assert_array_equal(f, to_np(bsdf.eval(ctx, si, bs.wo)))
    np.testing.assert_array_equal(pdf, to_np(bsdf.pdf(ctx, si, bs.wo)))


def test_sample_weight_is_walters():
    """Walter 2005: the specular sample weight is rho_s (v.h) cos^3(theta_h)
    sqrt(cos(theta_l) / cos(theta_v)) (a metal: every sample is specular)."""
    wi = sph(np.radians(40), 0.5)[0]
    _, (bs, w) = sample_bsdf(load(diffuse_reflectance=0.0, specular_reflectance=0.7,
                                  alpha_u=0.2, alpha_v=0.4), wi, 20000)
    wo, w = to_np(bs.wo).astype(float), to_np(w)[:, 0]
    ok = to_np(bs.pdf) > 0
    h = unit(wo + wi)
    want = 0.7 * np.sum(h * wi, axis=1) * h[:, 2] ** 3 * np.sqrt(np.clip(wo[:, 2], 0, None) / wi[2])
    np.testing.assert_allclose(w[ok], want[ok], rtol=2e-4, atol=1e-7)


# -- energy ----------------------------------------------------------------------------------

#: incidences (as cos(theta)) down to the documented limit of bounded albedo, cos = 0.01
COS_BOUNDED = [1.0, 0.866, 0.5, 0.17, 0.087, 0.0105]
ALPHAS = [(1e-4, 1e-4), (0.05, 0.05), (0.2, 0.2), (0.5, 0.5), (1.0, 1.0), (0.05, 0.3), (1e-4, 1.0)]


@pytest.mark.parametrize("cos_t", COS_BOUNDED)
def test_white_furnace(cos_t):
    """Albedo <= 1 (rho_s = 1, and rho_s + rho_d = 1) for every alpha down to cos = 0.01."""
    for (au, av), phi in itertools.product(ALPHAS, [0.0, np.pi / 2]):
        wi = sph(np.arccos(cos_t), phi)[0]
        for rs, rd in [(1.0, 0.0), (0.3, 0.7)]:
            b = load(specular_reflectance=rs, diffuse_reflectance=rd, alpha_u=au, alpha_v=av)
            a, err = albedo(b, wi, n=100_000)
            tag = (au, av, phi, rs, rd, a, err)
            assert np.isfinite(a).all(), tag
            assert (a <= 1 + 4 * err + 1e-3).all(), tag


def test_albedo_of_a_smooth_surface():
    """In the limit of small slopes Ward's normalisation makes the albedo rho_s at normal
    incidence and rho_s cos(theta_v) elsewhere: near the mirror direction l and v have the
    same elevation, and f cos(theta_l) / p(l) = rho_s (v.h) cos^3(theta_h) -> rho_s cos(theta_v)."""
    rs = np.array([0.9, 0.5, 0.2])
    b = load(specular_reflectance=rs.tolist(), diffuse_reflectance=0.0, alpha_u=1e-3, alpha_v=1e-3)
    for theta in (0, 40, 70):
        a, err = albedo(b, sph(np.radians(theta), 0.3)[0], n=50_000)
        np.testing.assert_allclose(a, rs * np.cos(np.radians(theta)), rtol=2e-3 + 4 * err.max())


def test_albedo_is_unbounded_at_grazing_incidence():
    """The documented defect of the original normalisation: below cos(theta_v) ~ 0.01 the
    albedo grows like 1 / sqrt(cos(theta_v)) (about 6 at cos = 1e-4 for alpha = 0.5)."""
    b = load(specular_reflectance=1.0, diffuse_reflectance=0.0, alpha_u=0.5, alpha_v=0.5)
    a1, _ = albedo(b, sph(np.arccos(1e-4), 0.0)[0])
    a2, _ = albedo(b, sph(np.arccos(1e-6), 0.0)[0])
    assert 5 < a1[0] < 7.5, a1
    np.testing.assert_allclose(a2 / a1, 10, rtol=0.1)


# -- flags, components, contexts --------------------------------------------------------------

def test_flags_and_components():
    b = load()
    assert b.component_count() == 2
    assert b.flags(0) == F.GlossyReflection | F.Anisotropic | F.FrontSide
    assert b.flags(1) == F.DiffuseReflection | F.FrontSide
    assert b.flags() == b.flags(0) | b.flags(1)
    metal = load(diffuse_reflectance=0.0)
    assert metal.component_count() == 1 and metal.flags() == b.flags(0)
    matte = load(specular_reflectance=0.0)
    assert matte.component_count() == 1 and matte.flags() == b.flags(1)
    black = load(specular_reflectance=0.0, diffuse_reflectance=0.0)
    assert black.component_count() == 0 and black.flags() == F.Empty
    assert load(specular_reflectance=1e-6).component_count() == 2
    _, (bs, _) = sample_bsdf(metal, [0.3, 0, 0.954], 5000)
    assert (to_np(bs.sampled_type) == +b.flags(0)).all()
    assert (to_np(bs.sampled_component) == 0).all()
    _, (bs, _) = sample_bsdf(matte, [0.3, 0, 0.954], 5000)
    assert (to_np(bs.sampled_type) == +b.flags(1)).all()
    s = str(b)
    assert all(k in s for k in ("alpha_u", "alpha_v", "specular_reflectance", "diffuse_reflectance"))


def test_context_selects_lobes():
    p = dict(rs=[0.3, 0.3, 0.3], rd=[0.6, 0.5, 0.4], au=0.1, av=0.3)
    b = bsdf_of(p)
    rng = np.random.default_rng(5)
    wi, wo = random_upper(rng, 500), random_upper(rng, 500)
    spec, diff = ward_reference(as_f32_unit(wi), as_f32_unit(wo), p["rs"], p["rd"], p["au"], p["av"])
    cases = {
        "component0": (dict(component=0), spec),
        "component1": (dict(component=1), diff),
        "glossy_mask": (dict(type_mask=+F.Glossy), spec),
        "diffuse_mask": (dict(type_mask=+F.Diffuse), diff),
        "nothing": (dict(type_mask=+F.Transmission), 0 * spec),
    }
    for name, (attrs, want) in cases.items():
        ctx = mi.BSDFContext()
        for k, v in attrs.items():
            setattr(ctx, k, v)
        got = eval_np(b, wi, wo, ctx)
        np.testing.assert_allclose(got, want * wo[:, 2:3], rtol=2e-3, atol=1e-6, err_msg=name)
        si, (bs, weight) = sample_bsdf(b, wi[7], 5000, ctx=ctx)
        pdf = to_np(bs.pdf)
        if name == "nothing":
            assert (to_np(weight) == 0).all() and (pdf == 0).all()
            continue
        t = np.broadcast_to(to_np(bs.sampled_type), (5000,))[pdf > 0]
        glossy = name in ("component0", "glossy_mask")
        assert (t == +b.flags(0 if glossy else 1)).all(), name
        np.testing.assert_allclose(pdf, to_np(b.pdf(ctx, si, bs.wo)), rtol=1e-6)
        if not glossy:
            np.testing.assert_allclose(pdf[pdf > 0], to_np(bs.wo)[pdf > 0, 2] / np.pi, rtol=1e-5)


# -- textures and parameters ------------------------------------------------------------------

def test_texture_parameters(tmp_path):
    rs = write_bitmap(tmp_path / "rs.exr", [0.2, 0.4, 0.6])
    rd = write_bitmap(tmp_path / "rd.exr", [0.5, 0.3, 0.1])
    au = write_bitmap(tmp_path / "au.exr", 0.08)
    av = write_bitmap(tmp_path / "av.exr", 0.25)
    textured = mi.load_dict({"type": PLUGIN, "specular_reflectance": bitmap(rs),
                             "diffuse_reflectance": bitmap(rd), "alpha_u": bitmap(au),
                             "alpha_v": bitmap(av)})
    const = load(specular_reflectance=[0.2, 0.4, 0.6], diffuse_reflectance=[0.5, 0.3, 0.1],
                 alpha_u=0.08, alpha_v=0.25)
    assert textured.flags() & F.SpatiallyVarying
    assert not const.flags() & F.SpatiallyVarying
    rng = np.random.default_rng(11)
    wi, wo = random_upper(rng, 1000), random_upper(rng, 1000)
    np.testing.assert_allclose(eval_np(textured, wi, wo), eval_np(const, wi, wo), rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(pdf_np(textured, wi, wo), pdf_np(const, wi, wo), rtol=1e-5, atol=1e-7)
    bad = write_bitmap(tmp_path / "bad.exr", 0.0)
    with pytest.raises(RuntimeError, match=r"ward: parameter 'alpha_v' must be an RMS slope in \[0.0001, 1\]"):
        mi.load_dict({"type": PLUGIN, "alpha_v": bitmap(bad)})


def test_spatially_varying_alpha(tmp_path):
    arr = np.zeros((2, 2, 1), np.float32)
    arr[:, 0], arr[:, 1] = 0.05, 0.4
    mi.Bitmap(arr).write(str(tmp_path / "a.exr"))
    b = mi.load_dict({"type": PLUGIN, "diffuse_reflectance": 0.0,
                      "alpha_u": bitmap(str(tmp_path / "a.exr")), "alpha_v": 0.1})
    wi = sph(np.radians(20), 0.0)
    wo = sph(np.radians(26), np.pi)
    si = interaction(np.repeat(wi, 2, axis=0))
    si.uv = mi.Point2f([0.25, 0.75], [0.5, 0.5])
    f = to_np(b.eval(mi.BSDFContext(), si, vec(np.repeat(wo, 2, axis=0))))
    for i, a in enumerate((0.05, 0.4)):
        ref = eval_np(load(diffuse_reflectance=0.0, alpha_u=a, alpha_v=0.1), wi, wo)
        np.testing.assert_allclose(f[i], ref[0], rtol=1e-5)
    assert abs(f[0, 0] - f[1, 0]) > 0.1 * f.max()


BAD = [
    ({"alpha_u": 0.0}, r"ward: parameter 'alpha_u' must be an RMS slope in \[0.0001, 1\] \(got 0"),
    ({"alpha_v": -0.1}, r"ward: parameter 'alpha_v' must be an RMS slope in \[0.0001, 1\] \(got -0.1\)"),
    ({"alpha_u": 1.5}, r"ward: parameter 'alpha_u' .*\(got 1.5\)"),
    ({"alpha_v": float("nan")}, r"ward: parameter 'alpha_v' .*\(got nan"),
    ({"alpha_u": "rough"}, r"ward: parameter 'alpha_u'"),
    ({"specular_reflectance": 1.5}, r"ward: parameter 'specular_reflectance' must be a reflectance in \[0, 1\]"),
    ({"diffuse_reflectance": -0.1}, r"ward: parameter 'diffuse_reflectance' must be a reflectance in \[0, 1\]"),
    ({"diffuse_reflectance": {"type": "rgb", "value": [0.2, 1.2, 0.3]}},
     r"ward: parameter 'diffuse_reflectance' must be a reflectance in \[0, 1\]"),
]


@pytest.mark.parametrize("params,msg", BAD)
def test_bad_parameters_raise_at_load(params, msg):
    with pytest.raises(RuntimeError, match=msg):
        mi.load_dict({"type": PLUGIN, **params})


def test_bad_parameters_from_xml():
    head = '<bsdf version="3.0.0" type="ward">'
    for body, msg in [('<rgb name="specular_reflectance" value="0.5, 2, 0.5"/>',
                       r"ward: parameter 'specular_reflectance'.*\[0, 1\]"),
                      ('<float name="alpha_u" value="0"/>', r"ward: parameter 'alpha_u'.*\[0.0001, 1\]")]:
        with pytest.raises(RuntimeError, match=msg):
            mi.load_string(head + body + "</bsdf>")
    b = mi.load_string(head + '<float name="alpha_u" value="0.0001"/><float name="alpha_v" value="1"/></bsdf>')
    assert b.component_count() == 2


# -- hard cases stay finite --------------------------------------------------------------------

@pytest.mark.parametrize("rs,rd", [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)])
def test_stability_grid(rs, rd):
    d = hard_directions()
    pairs = np.array(list(itertools.product(range(len(d)), repeat=2)))
    wi, wo = d[pairs[:, 0]], d[pairs[:, 1]]
    wi = np.concatenate([wi, -wo[:10]])  # wi = -wo as well
    wo = np.concatenate([wo, wo[:10]])
    u1 = np.array([0, 1e-7, 0.25, 0.5, 0.75, 1 - 2**-24])
    u2 = np.array([0, 1e-7, 0.25, 0.5, 1 - 2**-24])
    g1, g2, g3, gi = np.meshgrid(u1, u1, u2, np.arange(len(d)), indexing="ij")
    alphas = [1e-4, 0.01, 0.3, 1.0]
    for au, av in itertools.product(alphas, alphas):
        b = load(specular_reflectance=rs, diffuse_reflectance=rd, alpha_u=au, alpha_v=av)
        tag = f"au={au} av={av} rs={rs} rd={rd}"
        ctx = mi.BSDFContext()
        f, pdf = b.eval_pdf(ctx, interaction(wi), vec(wo))
        f, pdf = to_np(f), to_np(pdf)
        assert np.isfinite(f).all() and (f >= 0).all(), tag
        assert np.isfinite(pdf).all() and (pdf >= 0).all(), tag
        si = interaction(d[gi.ravel()])
        bs, w = b.sample(ctx, si, mi.Float(g1.ravel()), mi.Point2f(g2.ravel(), g3.ravel()))
        w, wo_s, bpdf = to_np(w), to_np(bs.wo), to_np(bs.pdf)
        assert np.isfinite(w).all() and (w >= 0).all(), tag
        assert np.isfinite(bpdf).all() and (bpdf >= 0).all(), tag
        assert np.isfinite(wo_s).all(), tag
        if rs or rd:
            np.testing.assert_allclose(np.linalg.norm(wo_s, axis=1), 1, atol=1e-5, err_msg=tag)


def test_smooth_lobe_is_not_lost_to_rounding():
    """At alpha = 1e-4 the albedo is cos(theta) (see above) and the samples spread around
    the mirror direction by ~1e-4 rad."""
    b = load(specular_reflectance=1.0, diffuse_reflectance=0.0, alpha_u=1e-4, alpha_v=1e-4)
    wi = sph(np.radians(30), 0.0)[0]
    _, (bs, w) = sample_bsdf(b, wi, 100_000)
    np.testing.assert_allclose(to_np(w).mean(axis=0), np.cos(np.radians(30)), rtol=2e-3)
    m = sph(np.radians(30), np.pi)[0]
    wo = to_np(bs.wo).astype(float)
    angle = np.linalg.norm(np.cross(wo, m), axis=1)
    # the angle of h to n is Rayleigh(alpha / sqrt 2)-like; wo moves twice as far
    assert 0.5e-4 < np.median(angle) < 4e-4, np.median(angle)


# -- parameters through mi.traverse, renders ---------------------------------------------------

def test_traverse_and_update():
    scene = small_scene({"type": PLUGIN, "id": "mat", "diffuse_reflectance": 0.0}, res=16)
    params = mi.traverse(scene)
    key = next(k for k in params.keys() if k.endswith("alpha_v.value"))
    img0 = np.array(mi.render(scene, spp=4, seed=0))
    params[key] = 0.4
    params.update()
    img1 = np.array(mi.render(scene, spp=4, seed=0))
    assert np.abs(img0 - img1).max() > 1e-3
    rd_key = next(k for k in params.keys() if k.endswith("diffuse_reflectance.value"))
    bsdf = scene.shapes()[0].bsdf()
    assert bsdf.component_count() == 1
    params[rd_key] = 0.5
    params.update()
    assert bsdf.component_count() == 2


RENDERS = {
    "default": dict(),
    "aniso_metal": dict(specular_reflectance=0.9, diffuse_reflectance=0.0, alpha_u=0.05, alpha_v=0.3),
    "smooth": dict(specular_reflectance=1.0, diffuse_reflectance=0.2, alpha_u=1e-4, alpha_v=1e-4),
    "rough": dict(specular_reflectance=0.5, diffuse_reflectance=0.5, alpha_u=1.0, alpha_v=1.0),
}


@pytest.mark.parametrize("integrator", ["path", "direct"])
@pytest.mark.parametrize("name", list(RENDERS))
def test_render_llvm(name, integrator):
    scene = small_scene({"type": PLUGIN, **RENDERS[name]}, integrator=integrator)
    img = np.array(mi.render(scene, spp=4))
    assert np.isfinite(img).all()
    assert img.mean() > 1e-3


def test_render_scalar_rgb():
    mi.set_variant("scalar_rgb")
    scene = small_scene({"type": PLUGIN, "alpha_u": 0.05, "alpha_v": 0.3}, res=6)
    img = np.array(mi.render(scene, spp=2))
    assert np.isfinite(img).all() and img.mean() > 1e-3


@pytest.mark.parametrize("variant", ["llvm_ad_spectral", "scalar_spectral"])
def test_spectral_variants(variant):
    mi.set_variant(variant)
    b = mi.load_dict({"type": PLUGIN, "specular_reflectance": {"type": "rgb", "value": [0.9, 0.5, 0.2]}})
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(0, 0, 1)
    si.wavelengths = mi.Spectrum(450, 500, 600, 650)
    v = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(0.1, 0, 0.995)))
    assert np.isfinite(v).all() and (v > 0).all()
    if variant.startswith("llvm"):
        img = np.array(mi.render(small_scene({"type": PLUGIN}, res=8), spp=2))
        assert np.isfinite(img).all() and img.mean() > 1e-3
