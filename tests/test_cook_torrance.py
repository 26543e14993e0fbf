"""The cook_torrance plugin: eval, pdf, sampling, energy, lobes, parameters, renders, and
agreement with Mitsuba's roughconductor where the two models coincide."""
import itertools
from functools import partial

import mitsuba as mi
import numpy as np
import pytest

from checks import (working_lobes, albedo, check_albedo_at_most_one, check_albedo_is_one,
                    check_context_selects_lobes, check_eval, check_glossy_and_diffuse_lobes, check_prb_gradients, check_render, check_sample_weight_is_eval_over_pdf, check_update_changes_lobes, check_update_changes_render, check_updates_reuse_kernel,
                    check_zero_below_horizon, eval_np, eval_pairs,
                    load_bsdf, load_xml, pdf_np, random_pairs, unit_f32)
from checks import sample_bsdf, small_scene, sph, to_np

from reference import cook_torrance as ref_cook_torrance

PLUGIN = "cook_torrance"
DISTS = ["beckmann", "blinn", "ggx"]
GEOMS = ["cook_torrance", "ggx"]
COMBOS = list(itertools.product(DISTS, GEOMS))
F = mi.BSDFFlags
load = partial(load_bsdf, PLUGIN)


PARAMS = [
    dict(m_d=[0.5, 0.5, 0.5], m_s=[1.0, 1.0, 1.0], k=0.5, rho=0.3, f0=[0.04, 0.04, 0.04]),
    dict(m_d=[0.7, 0.2, 0.1], m_s=[0.9, 0.6, 0.3], k=0.2, rho=0.08, f0=[0.9, 0.7, 0.4]),
    dict(m_d=[0.0, 0.0, 0.0], m_s=[1.0, 0.8, 0.6], k=0.0, rho=0.6, f0=[1.0, 1.0, 1.0]),
    dict(m_d=[0.3, 0.6, 0.9], m_s=[0.5, 0.5, 0.5], k=0.8, rho=1.0, f0=[0.0, 0.0, 0.0]),
]


def bsdf_of(p, dist, geom, **extra):
    return load(diffuse_reflectance=p["m_d"], specular_reflectance=p["m_s"], k=p["k"],
                roughness=p["rho"], f0=p["f0"], distribution=dist, geometry=geom, **extra)


# -- eval against the float64 transcription ---------------------------------------------------

def test_eval_below_horizon_and_backfacing_is_zero():
    check_zero_below_horizon(load())


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
    check_eval(ours, wi, wo, eval_np(theirs, wi, wo), rtol=2e-4)
    p_t = pdf_np(theirs, wi, wo)
    np.testing.assert_allclose(pdf_np(ours, wi, wo), p_t, rtol=2e-4, atol=1e-6 * p_t.max())
    for theta in (0, 60, 88):
        a_o, e_o = albedo(ours, theta, n=200_000, seed=1)
        a_t, e_t = albedo(theirs, theta, n=200_000, seed=2)
        assert np.all(np.abs(a_o - a_t) <= 5 * np.hypot(e_o, e_t) + 1e-4), (theta, a_o, a_t)


# -- sampling ------------------------------------------------------------------------------

THETAS = [0, 30, 60, 75, 85, 89]


@pytest.mark.parametrize("dist,geom", COMBOS)
def test_white_furnace_specular(dist, geom):
    """F = 1 (f0 = 1), k = 0: the microfacet lobe reflects at most what it receives, and all
    of it for a smooth surface away from grazing."""
    for rho in (1e-4, 0.1, 0.5, 1.0):
        b = load(k=0.0, f0=1.0, roughness=rho, distribution=dist, geometry=geom)
        for theta in THETAS:
            a, err = albedo(b, theta)
            check_albedo_at_most_one(a, err, (rho, theta))
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
        check_albedo_at_most_one(a, err, theta)


def test_white_furnace_lambert():
    """k = 1: a white Lambertian surface reflects everything (the package's 1/pi)."""
    check_albedo_is_one(load(k=1.0, diffuse_reflectance=1.0), THETAS)


# -- flags, components, contexts -----------------------------------------------------------

def test_flags_and_components():
    b = load()
    check_glossy_and_diffuse_lobes(b)
    for kw in (dict(k=0.0), dict(diffuse_reflectance=0.0)):
        metal = load(**kw)
        assert working_lobes(metal) == 1 and metal.flags() == b.flags(), kw
    for kw in (dict(k=1.0), dict(specular_reflectance=0.0)):
        matte = load(**kw)
        assert working_lobes(matte) == 1 and matte.flags() == b.flags(), kw
    # f0 = 0 keeps the specular lobe: Schlick's F grows to 1 at grazing angles
    assert working_lobes(load(f0=0.0)) == 2
    assert working_lobes(load(k=1e-6, diffuse_reflectance=1e-6)) == 2
    black = load(k=1.0, diffuse_reflectance=0.0)
    assert working_lobes(black) == 0 and black.flags() == b.flags()
    _, (bs, w) = sample_bsdf(black, [0, 0, 1], 100)
    assert (to_np(w) == 0).all() and (to_np(bs.pdf) == 0).all()
    assert (eval_np(black, [[0, 0, 1]], [[0.6, 0, 0.8]]) == 0).all()


def test_context_selects_lobes():
    p = PARAMS[1]
    b = bsdf_of(p, "ggx", "cook_torrance")
    wi, wo = (unit_f32(d) for d in random_pairs(5, 500))
    spec, diff = ref_cook_torrance(wi, wo, p["m_d"], p["m_s"], p["k"], p["rho"], p["f0"],
                                   "ggx", "cook_torrance")
    check_context_selects_lobes(b, wi, wo, spec, diff, rtol=1e-3, atol=1e-6)


# -- textures and parameters ---------------------------------------------------------------

def test_parameters_from_xml():
    b = load_xml(PLUGIN, '<string name="distribution" value="ggx"/><boolean name="sample_visible" value="false"/>'
                         '<float name="roughness" value="0.2"/>')
    assert "sample_visible = False" in str(b) and "distribution = ggx" in str(b)


# -- hard cases stay finite ----------------------------------------------------------------

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
    check_update_changes_render(scene, params, keys["roughness"], 0.6)
    # the diffuse lobe comes back
    check_update_changes_lobes(scene, params, keys["k"], 0.5, before=1, after=2)


def test_parameter_change_reuses_kernel():
    check_updates_reuse_kernel(small_scene({"type": PLUGIN, "distribution": "ggx"}, res=16),
                               "roughness.value", (0.5, 0.7))


# -- renders -------------------------------------------------------------------------------

def test_render_black_material():
    """No lobe at all (k = 1, m_D = 0): renders, and the sphere is black."""
    check_render({"type": PLUGIN, "k": 1.0, "diffuse_reflectance": 0.0}, res=8, spp=2, lit=False)


def test_render_prb_with_gradient():
    scene = small_scene({"type": PLUGIN, "distribution": "ggx"}, integrator="prb", res=12)
    check_prb_gradients(scene, ["roughness.value"], nonzero=True)


# -- extension: specular_scale (the ngan2005 presets) -----------------------------------------

def test_specular_scale_multiplies_the_specular_part():
    p = PARAMS[1]
    wi, wo = eval_pairs()
    spec, diff = ref_cook_torrance(wo, wi, p["m_d"], p["m_s"], p["k"], p["rho"], p["f0"],
                                   "beckmann", "cook_torrance")
    s = 8 / np.pi
    check_eval(bsdf_of(p, "beckmann", "cook_torrance", specular_scale=s), wi, wo,
               (s * spec + diff) * wo[:, 2:3], rtol=5e-4)
    for theta in (0, 60, 85):
        check_sample_weight_is_eval_over_pdf(
            bsdf_of(p, "beckmann", "cook_torrance", specular_scale=s), sph(np.radians(theta), 1.0)[0],
            min_valid=0.3, pdf_rtol=1e-5, weight_rtol=1e-4, weight_atol=1e-7)


def test_specular_scale_zero_drops_the_lobe_and_is_exposed():
    bsdf = load(specular_scale=0.0)
    wi, wo = eval_pairs()
    np.testing.assert_allclose(eval_np(bsdf, wi, wo), eval_np(load(k=1.0, diffuse_reflectance=0.25), wi, wo),
                               rtol=1e-6, atol=1e-9)
    params = mi.traverse(load())
    assert "specular_scale.value" in params.keys()
    with pytest.raises(Exception, match="specular_scale"):
        load(specular_scale=-1.0)
