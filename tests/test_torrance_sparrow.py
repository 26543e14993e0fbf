"""The torrance_sparrow plugin: eval, pdf, sampling, energy, lobes, parameters, renders, and
agreement with cook_torrance where the two models coincide."""
from functools import partial

import mitsuba as mi
import numpy as np
import pytest

import checks
from checks import (working_lobes, check_albedo_at_most_one, check_albedo_is_one, check_context_selects_lobes, check_eval, check_glossy_and_diffuse_lobes, check_prb_gradients, check_render, check_update_changes_lobes, check_update_changes_render, check_zero_below_horizon, eval_left_right, eval_np, eval_pairs,
                    load_bsdf, load_xml, pdf_np, random_pairs, unit_f32,
                    write_halves)
from checks import sample_bsdf, small_scene, sph, to_np
from mitsuba_brdfs.models.torrance_sparrow import schlick_r0

from reference import torrance_sparrow as ref_torrance_sparrow

PLUGIN = "torrance_sparrow"
F = mi.BSDFFlags
load = partial(load_bsdf, PLUGIN)
#: Monte Carlo directional albedo and its standard error, from 200 000 samples
albedo = partial(checks.albedo, n=200_000)
#: an eta whose R0 is 1 to float32 precision (F = 1): a perfect mirror's microfacets
ETA_MIRROR = 1e6


PARAMS = [
    dict(kd=[0.5, 0.5, 0.5], ks=[1.0, 1.0, 1.0], p=30.0, eta=1.5),
    dict(kd=[0.7, 0.2, 0.1], ks=[0.9, 0.6, 0.3], p=300.0, eta=2.4),
    dict(kd=[0.0, 0.0, 0.0], ks=[1.0, 0.8, 0.6], p=3.0, eta=ETA_MIRROR),
    dict(kd=[0.3, 0.6, 0.9], ks=[0.5, 0.5, 0.5], p=0.0, eta=1.0),
    dict(kd=[0.2, 0.2, 0.2], ks=[0.8, 0.8, 0.8], p=1.0, eta=1.33),
]


def bsdf_of(p, **extra):
    return load(diffuse_reflectance=p["kd"], specular_reflectance=p["ks"], exponent=p["p"],
                eta=p["eta"], **extra)


def test_schlick_r0():
    """Eq. 14: R0(1) = 0, R0(1.5) = 0.04, symmetric in eta and 1 / eta, -> 1 for eta -> inf."""
    np.testing.assert_allclose([schlick_r0(e) for e in (1.0, 1.5, 2.0, 0.5)],
                               [0.0, 0.04, 1 / 9, 1 / 9], rtol=1e-12, atol=0)
    assert 1 - float(schlick_r0(mi.Float(ETA_MIRROR))[0]) < 1e-5


# -- eval against the float64 transcription ---------------------------------------------------

def test_eval_sharp_lobe_matches_reference():
    """p = 1e4, directions within the lobe (the float32 half vector costs ~p 1e-7 relative)."""
    wi = sph(np.radians(40), 0.3)
    rng = np.random.default_rng(2)
    wo = unit_f32(sph(np.radians(40) + rng.normal(0, 0.01, 2000), np.pi + 0.3 + rng.normal(0, 0.01, 2000)))
    wi = unit_f32(np.repeat(wi, len(wo), axis=0))
    spec, diff = ref_torrance_sparrow(wo, wi, [0.0] * 3, [1.0] * 3, 1e4, 1.5)
    want = (spec + diff) * wo[:, 2:3]
    assert want.max() > 15  # the peak (~21 with F(40 deg) ~ 0.04) is in the set
    check_eval(load(diffuse_reflectance=0.0, exponent=1e4), wi, wo, want, rtol=1e-3)


def test_eval_below_horizon_and_backfacing_is_zero():
    check_zero_below_horizon(load())


# -- the same model as cook_torrance ----------------------------------------------------------

def as_cook_torrance(p, **extra):
    """cook_torrance with the blinn D of the same exponent, the V-groove G, F0 = R0 and
    k = 1/2, m_D = 2 k_d, m_S = 2 k_s (so k_d, k_s <= 1/2)."""
    rho = float(np.sqrt(2 / (p["p"] + 2)))
    return mi.load_dict({
        "type": "cook_torrance", "distribution": "blinn", "geometry": "cook_torrance",
        "k": 0.5, "roughness": rho, "f0": float(schlick_r0(p["eta"])),
        "diffuse_reflectance": {"type": "rgb", "value": [2 * c for c in p["kd"]]},
        "specular_reflectance": {"type": "rgb", "value": [2 * c for c in p["ks"]]}, **extra})


CT_PARAMS = [
    dict(kd=[0.25, 0.1, 0.05], ks=[0.5, 0.4, 0.3], p=30.0, eta=1.5),
    dict(kd=[0.5, 0.5, 0.5], ks=[0.2, 0.2, 0.2], p=0.0, eta=1.0),
    dict(kd=[0.1, 0.3, 0.2], ks=[0.45, 0.5, 0.35], p=2000.0, eta=4.0),
    dict(kd=[0.0, 0.0, 0.0], ks=[0.5, 0.5, 0.5], p=8.0, eta=1.2),
]


@pytest.mark.parametrize("pi", range(len(CT_PARAMS)))
def test_equals_cook_torrance_with_blinn(pi):
    p = CT_PARAMS[pi]
    ts, ct = bsdf_of(p), as_cook_torrance(p)
    assert ts.flags() == ct.flags() and ts.component_count() == ct.component_count()
    wi, wo = eval_pairs(3000, seed=13)
    # the exponent passes through rho = sqrt(2 / (p + 2)) in float32: relative error ~p 1e-7
    rtol = 1e-4 + 3e-7 * p["p"]
    check_eval(ts, wi, wo, eval_np(ct, wi, wo), rtol=rtol)
    p_ct = pdf_np(ct, wi, wo)
    np.testing.assert_allclose(pdf_np(ts, wi, wo), p_ct, rtol=rtol, atol=1e-6 * p_ct.max())
    # the same samples: the same directions and weights (a lobe choice may flip at a tie)
    for theta in (10, 70, 88):
        _, (bs_t, w_t) = sample_bsdf(ts, sph(np.radians(theta), 0.4)[0], 20000, seed=3)
        _, (bs_c, w_c) = sample_bsdf(ct, sph(np.radians(theta), 0.4)[0], 20000, seed=3)
        same = np.all(np.abs(to_np(bs_t.wo) - to_np(bs_c.wo)) < 1e-4, axis=1)
        assert same.mean() > 0.999, (theta, same.mean())
        np.testing.assert_allclose(to_np(w_t)[same], to_np(w_c)[same], rtol=10 * rtol, atol=1e-5)


# -- sampling ------------------------------------------------------------------------------

def test_sampled_half_vectors_follow_blinn():
    """The specular lobe alone: the half vectors of the samples have cos(alpha) distributed
    as D cos, i.e. P(cos(alpha) <= c) = 1 - ... = c^(p + 2) (eq. 11 integrated)."""
    p = 40.0
    ctx = mi.BSDFContext()
    ctx.component = 0
    wi = sph(np.radians(20), 0.0)[0]
    _, (bs, _) = sample_bsdf(load(exponent=p), wi, 100_000, ctx=ctx)
    h = to_np(bs.wo) + wi
    c = np.sort(h[:, 2] / np.linalg.norm(h, axis=1))
    ecdf = np.arange(1, len(c) + 1) / len(c)
    assert np.abs(ecdf - c ** (p + 2)).max() < 0.01


THETAS = [0, 30, 60, 75, 85, 89]


@pytest.mark.parametrize("p", [0.0, 1.0, 30.0, 1e3, 1e6])
def test_white_furnace_specular(p):
    """F = 1 (eta -> inf), k_d = 0, k_s = 1: the microfacet lobe with the V-groove G reflects
    at most what it receives, and all of it when smooth, away from grazing (a mirror; this
    fixes the reading of eq. 10's angles)."""
    b = load(diffuse_reflectance=0.0, exponent=p, eta=ETA_MIRROR)
    for theta in THETAS:
        a, err = albedo(b, theta)
        check_albedo_at_most_one(a, err, (p, theta))
        if p == 1e6 or (p == 1e3 and theta <= 75):
            assert (a >= 0.99).all(), (p, theta, a)


@pytest.mark.parametrize("params", [
    dict(diffuse_reflectance=0.5, specular_reflectance=0.5, eta=ETA_MIRROR, exponent=5.0),
    dict(diffuse_reflectance=0.7, specular_reflectance=0.3, eta=1.5),
    dict(diffuse_reflectance=0.2, specular_reflectance=0.8, eta=1.0, exponent=0.0),
])
def test_white_furnace_mixed(params):
    """k_d + k_s <= 1: at most what it receives."""
    b = load(**params)
    for theta in THETAS:
        a, err = albedo(b, theta)
        check_albedo_at_most_one(a, err, theta)


def test_diffuse_term_is_not_weighted_by_fresnel():
    """Eq. 10 as written: the albedo is k_d plus the specular lobe's (no 1 - F on the diffuse
    term), so k_d + k_s > 1 can reflect more than it receives where F grows to 1."""
    for theta in (0, 60, 85, 89):
        a, e = albedo(load(diffuse_reflectance=0.7), theta, seed=1)
        a_s, e_s = albedo(load(diffuse_reflectance=0.0), theta, seed=2)
        assert np.all(np.abs(a - (0.7 + a_s)) <= 5 * np.hypot(e, e_s) + 1e-4), (theta, a, a_s)
    a, e = albedo(load(diffuse_reflectance=0.7), 89)
    assert (a > 1.1).all(), a


def test_white_furnace_lambert():
    """k_s = 0: a white Lambertian surface reflects everything (k_d / pi of eq. 10)."""
    check_albedo_is_one(load(specular_reflectance=0.0, diffuse_reflectance=1.0), THETAS)


# -- flags, components, contexts -----------------------------------------------------------

def test_flags_and_components():
    b = load()
    check_glossy_and_diffuse_lobes(b)
    metal = load(diffuse_reflectance=0.0)
    assert working_lobes(metal) == 1 and metal.flags() == b.flags()
    matte = load(specular_reflectance=0.0)
    assert working_lobes(matte) == 1 and matte.flags() == b.flags()
    # eta = 1 (R0 = 0) and exponent 0 keep the specular lobe
    assert working_lobes(load(eta=1.0, exponent=0.0)) == 2
    assert working_lobes(load(diffuse_reflectance=1e-6, specular_reflectance=1e-6)) == 2
    black = load(diffuse_reflectance=0.0, specular_reflectance=0.0)
    assert working_lobes(black) == 0 and black.flags() == b.flags()
    _, (bs, w) = sample_bsdf(black, [0, 0, 1], 100)
    assert (to_np(w) == 0).all() and (to_np(bs.pdf) == 0).all()
    assert (eval_np(black, [[0, 0, 1]], [[0.6, 0, 0.8]]) == 0).all()
    # a metal never samples the diffuse lobe: every direction is a reflection about some h
    _, (bs, w) = sample_bsdf(metal, sph(np.radians(50), 0)[0], 2000)
    t = np.broadcast_to(to_np(bs.sampled_type), (2000,))[to_np(bs.pdf) > 0]
    assert (t == +b.flags(0)).all()


def test_context_selects_lobes():
    p = PARAMS[1]
    b = bsdf_of(p)
    wi, wo = (unit_f32(d) for d in random_pairs(5, 500))
    spec, diff = ref_torrance_sparrow(wo, wi, p["kd"], p["ks"], p["p"], p["eta"])
    # with lobe_pdf, a sample's pdf is the selected lobe's alone (for the glossy lobe: the mixture's
    # pdf minus its diffuse share)
    check_context_selects_lobes(b, wi, wo, spec, diff, rtol=1e-3, atol=lambda want: 1e-6 * want.max(),
                                lobe_pdf=True)


def test_to_string_lists_parameters():
    s = str(load(exponent=77.0, eta=1.7))
    assert s.startswith("TorranceSparrow[")
    for name in ("diffuse_reflectance", "specular_reflectance", "exponent", "eta"):
        assert f"{name} = " in s, name
    assert "77" in s and "1.7" in s


# -- textures and parameters ---------------------------------------------------------------

def test_spatially_varying_exponent(tmp_path):
    """An exponent bitmap with two halves gives each half its own lobe."""
    b = mi.load_dict({"type": PLUGIN, "diffuse_reflectance": 0.0,
                      "exponent": write_halves(tmp_path / "p.exr", 10.0, 1000.0)})
    wi, wo = sph(np.radians(30), 0.0), sph(np.radians(30), np.pi)  # the mirror direction
    vals = eval_left_right(b, wi, wo)[:, 0]
    for val, p in zip(vals, (10.0, 1000.0)):
        spec, _ = ref_torrance_sparrow(wo, wi, 0.0, 1.0, p, 1.5)
        np.testing.assert_allclose(val, spec[0, 0] * wo[0, 2], rtol=1e-4)


def test_parameters_from_xml():
    b = load_xml(PLUGIN, '<float name="exponent" value="250"/><float name="eta" value="1.33"/>'
                         '<rgb name="diffuse_reflectance" value="0.4, 0.1, 0.1"/>')
    wi, wo = eval_pairs(200, seed=1)
    spec, diff = ref_torrance_sparrow(wo, wi, [0.4, 0.1, 0.1], 1.0, 250.0, 1.33)
    check_eval(b, wi, wo, (spec + diff) * wo[:, 2:3], rtol=5e-4)


# -- hard cases stay finite ----------------------------------------------------------------

def test_smooth_limit_is_a_mirror():
    """p = 1e6, F = 1: the samples leave within a few 1e-3 rad of the mirror direction (w_h
    within sqrt(-2 log(0.01) / p) = 3e-3 rad of n for 99% of them) with weight 1 (up to
    G (w_o.w_h) / (cos(theta_i) cos(alpha)) = 1 + O(tan(theta_i) alpha))."""
    b = load(diffuse_reflectance=0.0, exponent=1e6, eta=ETA_MIRROR)
    wi = sph(np.radians(30), 0.0)[0]
    _, (bs, w) = sample_bsdf(b, wi, 50_000)
    spread = np.arccos(np.clip(to_np(bs.wo) @ sph(np.radians(30), np.pi)[0], -1, 1))
    assert 3e-3 < np.quantile(spread, 0.99) < 7e-3
    np.testing.assert_allclose(to_np(w), 1, atol=5e-3)
    assert abs(to_np(w).mean() - 1) < 2e-4


# -- parameters through mi.traverse ----------------------------------------------------------

def test_traverse_exposes_parameters_and_updates():
    scene = small_scene({"type": PLUGIN, "diffuse_reflectance": 0.0}, res=16)
    params = mi.traverse(scene)
    keys = {}
    for name in ("diffuse_reflectance", "specular_reflectance", "exponent", "eta"):
        keys[name] = f"ball.bsdf.{name}.value"
        assert keys[name] in params, name
        assert not params.flags(keys[name]) & mi.ParamFlags.NonDifferentiable.value, name
    for key, val in (("exponent", 300.0), ("eta", 3.0)):
        check_update_changes_render(scene, params, keys[key], val, msg=key)
    # the diffuse lobe comes back, and the specular one goes
    check_update_changes_lobes(scene, params, keys["diffuse_reflectance"], 0.5, before=1, after=2)
    check_update_changes_lobes(scene, params, keys["specular_reflectance"], 0.0, before=2, after=1)
    # both components stay declared (wrappers copy the flags when they are built)
    assert scene.shapes()[0].bsdf().flags() == F.GlossyReflection | F.DiffuseReflection | F.FrontSide


# -- renders -------------------------------------------------------------------------------

def test_render_black_material():
    check_render({"type": PLUGIN, "specular_reflectance": 0.0, "diffuse_reflectance": 0.0}, res=8, spp=2,
                 lit=False)


def test_render_prb_with_gradient():
    scene = small_scene({"type": PLUGIN}, integrator="prb", res=12)
    check_prb_gradients(scene, ["ball.bsdf.exponent.value", "ball.bsdf.eta.value"], nonzero=True)


