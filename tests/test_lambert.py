"""The lambert plugin: against Mitsuba's ``diffuse``, the formula, sampling, energy, lobes,
parameters and renders."""
from functools import partial

import mitsuba as mi
import numpy as np
import pytest

from checks import (albedo, bitmap, check_diffuse_context, check_refused, check_render, eval_left_right, eval_np, load_bsdf, load_xml, midpoint_hemisphere, pdf_np,
                    write_bitmap, write_halves)
from checks import random_upper, sample_bsdf, small_scene, sph, to_np

from reference import lambert as ref_lambert

PLUGIN = "lambert"
F = mi.BSDFFlags
load = partial(load_bsdf, PLUGIN)


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


# -- sampling and energy -----------------------------------------------------------------------

@pytest.mark.parametrize("theta", [0, 30, 60, 85, 89.9])
def test_white_furnace(theta):
    """A white Lambert surface reflects all light: albedo 1 at every incidence. The
    estimate is checked against numerical quadrature of eval as well (no sampling)."""
    b = load(reflectance=1.0)
    a, _ = albedo(b, theta, n=100_000)
    np.testing.assert_allclose(a, 1.0, rtol=1e-5)
    # midpoint quadrature of the integral of eval over the hemisphere
    wo, dw = midpoint_hemisphere(400)
    wi = np.repeat(sph(np.radians(theta), 0.7), len(wo), axis=0)
    integral = np.sum(eval_np(b, wi, wo)[:, 0] * dw)
    assert abs(integral - 1.0) < 1e-4, integral


# -- flags, components, contexts -----------------------------------------------------------------

def test_flags_components_and_context():
    b = load()
    assert b.component_count() == 1
    assert b.flags() == b.flags(0) == F.DiffuseReflection | F.FrontSide
    assert b.flags() == mi.load_dict({"type": "diffuse"}).flags()
    black = load(reflectance=0.0)
    assert black.flags() == b.flags()  # the component stays declared: an update may need it
    wi, wo = random_upper(np.random.default_rng(2), 200), random_upper(np.random.default_rng(4), 200)
    want = ref_lambert(wi, wo, [0.5] * 3)
    cases = [({}, True), (dict(component=0), True), (dict(type_mask=+F.Diffuse), True),
             (dict(type_mask=+F.DiffuseReflection), True), (dict(type_mask=+F.Glossy), False),
             (dict(component=1), False), (dict(type_mask=+F.Transmission), False)]
    check_diffuse_context(b, wi, wo, want, cases, rtol=1e-5, atol=1e-8)
    # a black surface evaluates, samples and renders to zero
    assert (eval_np(black, wi, wo) == 0).all()
    _, (bs, w) = sample_bsdf(black, wi[0], 100)
    assert (to_np(w) == 0).all()
    check_render({"type": PLUGIN, "reflectance": 0.0}, res=8, spp=2, lit=False)


# -- textures and parameters -------------------------------------------------------------------

def test_bitmap_texture(tmp_path):
    left, right = [0.9, 0.1, 0.2], [0.1, 0.2, 0.8]
    b = mi.load_dict({"type": PLUGIN, "reflectance": write_halves(tmp_path / "rho.exr", left, right)})
    assert b.flags() & F.SpatiallyVarying
    f = eval_left_right(b, [0, 0, 1], sph(np.radians(30), 0.2))
    np.testing.assert_allclose(f, np.float32([left, right]) / np.pi * np.cos(np.radians(30)), rtol=1e-5)
    bad = write_bitmap(tmp_path / "bad.exr", [1.2, 1.2, 1.2], res=2)
    check_refused(PLUGIN, {"reflectance": bitmap(bad)},
                  r"lambert: parameter 'reflectance' must be a reflectance in \[0, 1\]")


def test_parameters_from_xml():
    ok = load_xml(PLUGIN, '<rgb name="reflectance" value="0.5, 0.2, 0.5"/>')
    assert "reflectance" in str(ok)


# -- hard cases ----------------------------------------------------------------------------------

# -- renders -------------------------------------------------------------------------------------

