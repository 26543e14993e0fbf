"""The ashikhmin_shirley plugin: eval, pdf, sampling, energy, lobes, parameters, renders."""
import itertools
import subprocess
import sys
from functools import partial

import mitsuba as mi
import numpy as np
import pytest

import checks
from checks import (working_lobes, CORNERS, CORNERS_FINE, check_albedo_at_most_one, check_chi2,
                    check_context_selects_lobes, check_eval, check_eval_pdf_finite,
                    check_finite_gradients, check_glossy_and_diffuse_lobes, check_prb_gradients, check_render, check_sample_weight_is_eval_over_pdf, check_samples_finite,
                    check_update_changes_lobes, check_update_changes_render, check_updates_reuse_kernel,
                    check_zero_below_horizon, corner_samples, eval_left_right, eval_np,
                    hard_directions, hard_pairs, load_bsdf, mirror_pairs, param_key, pdf_np, random_pairs,
                    unit_f32,
                    write_halves)
from checks import sample_bsdf, small_scene, sph, to_np
from checks import half_width_at_normal_incidence, roughconductor_half_width
from reference import ashikhmin_shirley as ref_as

PLUGIN = "ashikhmin_shirley"
load = partial(load_bsdf, PLUGIN)
#: Monte Carlo directional albedo and its standard error, from 400 000 samples
albedo = partial(checks.albedo, n=400_000)


def bsdf_of(p, **extra):
    return load(specular_reflectance=p["rs"], diffuse_reflectance=p["rd"],
                nu=p["nu"], nv=p["nv"], **extra)


# -- eval against the float64 transcription of eq. 1-5 ---------------------------------------

def test_eval_below_horizon_and_backfacing_is_zero():
    check_zero_below_horizon(load())


# -- sampling ------------------------------------------------------------------------------

@pytest.mark.parametrize("theta", [0, 30, 60, 75, 85, 89])
@pytest.mark.parametrize("kind,params", [
    ("metal_broad", dict(specular_reflectance=1.0, diffuse_reflectance=0.0, nu=1.0, nv=1.0)),
    ("metal_aniso", dict(specular_reflectance=1.0, diffuse_reflectance=0.0, nu=10.0, nv=1000.0)),
    ("metal_sharp", dict(specular_reflectance=1.0, diffuse_reflectance=0.0, nu=1e4, nv=1e4)),
    ("diffuse", dict(specular_reflectance=0.0, diffuse_reflectance=1.0)),
    ("diffuse_lobe", dict(specular_reflectance=0.0, diffuse_reflectance=1.0, component=1)),
    ("mixed", dict(specular_reflectance=0.05, diffuse_reflectance=1.0, nu=100.0, nv=100.0)),
    ("mixed_strong", dict(specular_reflectance=0.5, diffuse_reflectance=1.0, nu=10.0, nv=10.0)),
])
def test_white_furnace(kind, params, theta):
    params, ctx = dict(params), mi.BSDFContext()
    if "component" in params:
        ctx.component = params.pop("component")
    a, err = albedo(mi.load_dict({"type": PLUGIN, **params}), theta, ctx=ctx)
    check_albedo_at_most_one(a, err, kind)
    if kind == "diffuse_lobe":  # eq. 5 integrates to Rd (1 - (1 - cos/2)^5) exactly
        want = 1 - (1 - np.cos(np.radians(theta)) / 2) ** 5
        np.testing.assert_allclose(a, want, atol=4 * err.max() + 2e-3)


@pytest.mark.parametrize("theta", [0, 50, 80])
@pytest.mark.parametrize("params", [
    dict(specular_reflectance=0.3, diffuse_reflectance=0.6, nu=10.0, nv=40.0),
    dict(specular_reflectance=1.0, diffuse_reflectance=0.0, nu=2.0, nv=20.0),
])
def test_importance_and_cosine_sampling_agree(params, theta):
    """Both estimators of the albedo are unbiased: the weights are right in expectation."""
    a_hv, e_hv = albedo(mi.load_dict({"type": PLUGIN, **params}), theta, n=1_000_000, seed=1)
    a_cos, e_cos = albedo(mi.load_dict({"type": PLUGIN, **params, "sampling": "cosine"}),
                          theta, n=1_000_000, seed=2)
    tol = 5 * np.sqrt(e_hv ** 2 + e_cos ** 2) + 1e-4
    assert (np.abs(a_hv - a_cos) <= tol).all(), (a_hv, a_cos, tol)


# -- flags, components, contexts -----------------------------------------------------------

F = mi.BSDFFlags


def test_flags_and_components():
    b = load()
    check_glossy_and_diffuse_lobes(b, F.GlossyReflection | F.Anisotropic | F.FrontSide)
    metal = load(diffuse_reflectance=0.0)
    assert working_lobes(metal) == 1 and metal.flags() == b.flags()
    # Rs = 0 keeps the specular lobe: Schlick's F is still (1 - k.h)^5
    assert working_lobes(load(specular_reflectance=0.0)) == 2
    mirror_coat = load(specular_reflectance=1.0, diffuse_reflectance=0.5)  # 1 - Rs = 0
    assert working_lobes(mirror_coat) == 1 and mirror_coat.flags() == b.flags()
    dark = load(specular_reflectance=0.0, diffuse_reflectance=0.0)
    assert working_lobes(dark) == 1 and dark.flags() == b.flags()
    # a tiny but non-zero reflectance keeps its lobe
    assert working_lobes(load(diffuse_reflectance=1e-6)) == 2


def test_context_selects_lobes():
    p = dict(rs=[0.3, 0.3, 0.3], rd=[0.6, 0.6, 0.6], nu=20.0, nv=200.0)
    b = bsdf_of(p)
    wi, wo = random_pairs(5, 500)
    spec, diff = ref_as(wi, wo, p["rs"], p["rd"], p["nu"], p["nv"])
    # sampling with a context draws only from the selected lobe
    check_context_selects_lobes(b, wi, wo, spec, diff, rtol=2e-3, atol=1e-6)


def test_metal_never_samples_diffuse():
    metal = load(diffuse_reflectance=0.0, specular_reflectance=0.9)
    _, (bs, _) = sample_bsdf(metal, [0.3, 0, 0.954], 10000)
    assert (to_np(bs.sampled_type) == +(F.GlossyReflection | F.Anisotropic | F.FrontSide)).all()
    assert (to_np(bs.sampled_component) == 0).all()


# -- textures and parameters ---------------------------------------------------------------

def test_spatially_varying_exponent_changes_lobe(tmp_path):
    """A bitmap exponent is looked up at the shading point's uv."""
    b = mi.load_dict({"type": PLUGIN, "diffuse_reflectance": 0.0,
                      "nu": write_halves(tmp_path / "n.exr", 10.0, 1000.0), "nv": 10.0})  # left 10, right 1000
    wo = sph(np.radians(8), 0.0)  # tilted along u
    f = eval_left_right(b, [0, 0, 1], wo)
    ref10 = eval_np(load(diffuse_reflectance=0.0, nu=10.0, nv=10.0), [0, 0, 1], wo)
    ref1000 = eval_np(load(diffuse_reflectance=0.0, nu=1000.0, nv=10.0), [0, 0, 1], wo)
    np.testing.assert_allclose(f[0], ref10[0], rtol=1e-5)
    np.testing.assert_allclose(f[1], ref1000[0], rtol=1e-5)


# -- roughness instead of the exponents --------------------------------------------------------

@pytest.mark.parametrize("au,av", [(0.1, 0.1), (0.05, 0.3), (1.0, 0.01), (1.5e-3, 0.5)])
def test_alpha_sets_the_exponents(au, av):
    """alpha_u, alpha_v give eq. 1-5 with nu = 2 / alpha_u^2 - 2, nv = 2 / alpha_v^2 - 2
    (float64 mapping); alpha is alpha_u = alpha_v."""
    wi, wo = mirror_pairs(2000, seed=9, mirrors=100)
    wi32, wo32 = unit_f32(wi), unit_f32(wo)
    nu, nv = 2 / au ** 2 - 2, 2 / av ** 2 - 2
    rs, rd = [0.2, 0.4, 0.1], [0.5, 0.3, 0.2]
    spec, diff = ref_as(wi32, wo32, rs, rd, nu, nv)
    b = load(alpha_u=au, alpha_v=av, specular_reflectance=rs, diffuse_reflectance=rd)
    check_eval(b, wi, wo, (spec + diff) * wo32[:, 2:3], rtol=5e-4)
    by_n = load(nu=nu, nv=nv, specular_reflectance=rs, diffuse_reflectance=rd)
    np.testing.assert_allclose(pdf_np(b, wi, wo), pdf_np(by_n, wi, wo), rtol=1e-4, atol=1e-6)
    if au == av:
        iso = load(alpha=au, specular_reflectance=rs, diffuse_reflectance=rd)
        np.testing.assert_array_equal(eval_np(iso, wi, wo), eval_np(b, wi, wo))


def test_alpha_highlight_as_wide_as_roughconductor():
    """Along u and along v the highlight is as wide as Mitsuba's anisotropic Beckmann
    roughconductor with the same alpha_u, alpha_v (normal incidence)."""
    b = load(alpha_u=0.05, alpha_v=0.1, diffuse_reflectance=0.0)
    for phi, rtol in ((0.0, 6e-3), (np.pi / 2, 0.02)):
        np.testing.assert_allclose(half_width_at_normal_incidence(b, phi),
                                   roughconductor_half_width(0.05, phi, alpha_v=0.1), rtol=rtol)


@pytest.mark.parametrize("theta", [0, 45, 85])
def test_alpha_sampling_and_furnace(theta):
    check_chi2(PLUGIN, dict(alpha_u=0.3, alpha_v=0.05, specular_reflectance=0.5,
                            diffuse_reflectance=0.5), theta, res=161, ires=32)
    for au, av in ((1.5e-3, 1.5e-3), (0.05, 0.3), (1.0, 1.0)):
        b = load(alpha_u=au, alpha_v=av, specular_reflectance=1.0, diffuse_reflectance=0.0)
        # (alpha = 1 is n = 0: at normal incidence 71% of the half vectors reflect below)
        check_sample_weight_is_eval_over_pdf(b, sph(np.radians(theta), 1.0)[0], min_valid=0.2,
                                             pdf_rtol=1e-5, weight_rtol=1e-4, weight_atol=1e-7)
        a, err = albedo(b, theta, n=100_000)
        check_albedo_at_most_one(a, err, (au, av))


def test_alpha_stability_and_gradients():
    d = hard_directions()
    wi, wo = hard_pairs(d, mirrored=10)
    samples = corner_samples(d, CORNERS_FINE, CORNERS)
    alphas = [1.5e-3, 1e-2, 0.5, 1.0]
    for au, av in itertools.product(alphas, alphas):
        b = load(alpha_u=au, alpha_v=av, specular_reflectance=1.0, diffuse_reflectance=1.0)
        tag = f"au={au} av={av}"
        check_eval_pdf_finite(b, mi.BSDFContext(), wi, wo, tag)
        check_samples_finite(b, mi.BSDFContext(), samples, tag)
        if au == av:
            check_finite_gradients(b, wi, wo, keys=["alpha_u.value", "alpha_v.value"])


def test_alpha_traverse_and_render():
    assert {"alpha.value"} <= set(mi.traverse(load(alpha=0.2)).keys())
    keys = set(mi.traverse(load(alpha_u=0.2, alpha_v=0.1)).keys())
    assert {"alpha_u.value", "alpha_v.value"} <= keys and "nu.value" not in keys
    scene = small_scene({"type": PLUGIN, "id": "mat", "alpha_u": 0.05, "alpha_v": 0.3,
                         "diffuse_reflectance": 0.0}, res=16)
    params = mi.traverse(scene)
    check_update_changes_render(scene, params, param_key(params, "alpha_v.value"), 0.05)
    check_render({"type": PLUGIN, "alpha": 0.1})


# -- hard cases stay finite ----------------------------------------------------------------

def test_sharp_lobe_is_not_lost_to_rounding():
    """At nu = nv = 1e6 the lobe (width ~1e-3 rad) keeps its full albedo (no cos -> 1 collapse)."""
    b = load(specular_reflectance=1.0, diffuse_reflectance=0.0, nu=1e6, nv=1e6)
    a, err = albedo(b, 30, n=100_000)
    assert np.all(np.abs(a - 1) < 0.01), a
    _, (bs, _) = sample_bsdf(b, sph(np.radians(30), 0.0)[0], 100_000)
    wo = to_np(bs.wo)
    spread = np.degrees(np.arccos(np.clip(wo @ sph(np.radians(30), np.pi)[0], -1, 1)))
    assert 0 < np.median(spread) < 0.2  # the samples spread around the mirror direction


# -- parameters through mi.traverse ----------------------------------------------------------

def test_traverse_exposes_parameters_and_updates():
    scene = small_scene({"type": PLUGIN, "id": "mat", "diffuse_reflectance": 0.0}, res=16)
    params = mi.traverse(scene)
    for key in ("specular_reflectance.value", "diffuse_reflectance.value", "nu.value", "nv.value"):
        assert f"ball.bsdf.{key}" in params or f"mat.{key}" in params, (key, list(params.keys()))
    check_update_changes_render(scene, params, param_key(params, "nu.value"), 5.0)
    # Rd from 0 to 0.5 brings the diffuse lobe back
    check_update_changes_lobes(scene, params, param_key(params, "diffuse_reflectance.value"), 0.5,
                               before=1, after=2)


def test_parameter_change_reuses_kernel():
    check_updates_reuse_kernel(small_scene({"type": PLUGIN}, res=16), "nv.value", (50.0, 70.0))


# -- renders -------------------------------------------------------------------------------

def test_render_prb_with_gradient():
    """The plugin traces into the differentiable prb integrator and gives finite gradients."""
    scene = small_scene({"type": PLUGIN, "specular_reflectance": 0.3}, integrator="prb", res=12)
    check_prb_gradients(scene, ["nu.value"], nonzero=False)


# -- registration and LLVM ------------------------------------------------------------------

def test_registration_follows_variant():
    import mitsuba_brdfs
    mi.set_variant("scalar_rgb")
    assert mi.load_dict({"type": PLUGIN}).component_count() == 2
    mi.set_variant("llvm_ad_rgb")
    assert mi.load_dict({"type": PLUGIN}).component_count() == 2
    assert PLUGIN in mitsuba_brdfs.register()  # twice is harmless
    assert PLUGIN in mitsuba_brdfs.register()


def test_old_llvm_raises_clear_error():
    """With LLVM 15 the import raises an error saying what to install (no abort)."""
    import glob
    # Dr.Jit itself refuses LLVM < 15; 15 and 16 load and then abort at the first kernel
    old = sorted(glob.glob("/usr/lib/*/libLLVM-1[56].so*") + glob.glob("/usr/lib/*/libLLVM.so.1[56]*"))
    if not old:
        pytest.skip("no LLVM older than 17 on this machine to try")
    code = ("import mitsuba as mi; mi.set_variant('llvm_ad_rgb')\n"
            "try:\n    import mitsuba_brdfs\nexcept Exception as e:\n"
            "    print(type(e).__name__, e)\n")
    env = dict(__import__("os").environ, DRJIT_LIBLLVM_PATH=old[0])
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    assert "LLVMVersionError" in out.stdout and "libllvm19" in out.stdout, out.stdout


# -- extensions: specular_scale and diffuse_term = lambert (the ngan2005 presets) -------------

EXT = dict(rs=[0.25, 0.25, 0.25], rd=[0.3, 0.15, 0.05], nu=300.0, nv=300.0)
SCALE = [0.5, 0.3, 0.1]


def test_extensions_eval_matches_reference():
    """specular_scale multiplies eq. 4; diffuse_term = lambert replaces eq. 5 by Rd / pi."""
    wi, wo = mirror_pairs(4000, seed=7, mirrors=200)
    wi32, wo32 = unit_f32(wi), unit_f32(wo)
    spec, diff = ref_as(wo32, wi32, EXT["rs"], EXT["rd"], EXT["nu"], EXT["nv"])
    want = (spec * np.array(SCALE) + np.array(EXT["rd"]) / np.pi) * wo32[:, 2:3]
    check_eval(bsdf_of(EXT, specular_scale=SCALE, diffuse_term="lambert"), wi, wo, want, rtol=5e-4)
    # the defaults change nothing
    check_eval(bsdf_of(EXT, specular_scale=[1.0, 1.0, 1.0], diffuse_term="ashikhmin_shirley"),
               wi, wo, (spec + diff) * wo32[:, 2:3], rtol=5e-4)


@pytest.mark.parametrize("theta", [0, 45, 85])
def test_extensions_sampling(theta):
    bsdf = bsdf_of(EXT, specular_scale=SCALE, diffuse_term="lambert")
    check_sample_weight_is_eval_over_pdf(bsdf, sph(np.radians(theta), 1.0)[0], min_valid=0.3,
                                         pdf_rtol=1e-5, weight_rtol=1e-4, weight_atol=1e-7)
    a, err = albedo(bsdf, theta)
    check_albedo_at_most_one(a, err, "extensions")


def test_extensions_chi2():
    check_chi2(PLUGIN, dict(specular_reflectance=0.25, diffuse_reflectance=0.6, nu=100.0,
                            nv=100.0, specular_scale=0.4, diffuse_term="lambert"), 60, res=161, ires=16)


def test_lambert_diffuse_stays_with_rs_one():
    """Eq. 5 vanishes with Rs = 1 (its 1 - Rs); the Lambertian term does not."""
    bsdf = load(specular_reflectance=1.0, diffuse_reflectance=0.5, diffuse_term="lambert")
    assert bsdf.component_count() == 2
    v = eval_np(bsdf, sph(np.radians(30), 0.0), sph(np.radians(70), 2.0), checks.context(component=1))
    np.testing.assert_allclose(v, 0.5 / np.pi * np.cos(np.radians(70)), rtol=1e-5)


def test_extension_parameters_refused_out_of_range():
    with pytest.raises(Exception, match="specular_scale"):
        load(specular_scale=1.5)
    with pytest.raises(Exception, match="diffuse_term"):
        load(diffuse_term="oren_nayar")
