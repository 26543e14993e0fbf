"""Shared math: stable elementary functions, Schlick Fresnel, the AS half-vector warp."""
import mitsuba as mi
import numpy as np
import pytest

from mitsuba_brdfs.core import numerics, warp
from mitsuba_brdfs.core.fresnel import schlick
from reference import ashikhmin_shirley_half_pdf
from checks import floats, point2, to_np, vec, warp_chi2


def f32(x):
    return floats(x)


X_SMALL = np.concatenate([-np.logspace(-12, -0.01, 60), np.logspace(-12, 2, 60), [0.0]])


def test_log1p_matches_float64():
    x = X_SMALL[X_SMALL > -1]
    got = to_np(numerics.log1p(f32(x)))
    want = np.log1p(x.astype(np.float32).astype(np.float64))
    np.testing.assert_allclose(got, want, rtol=3e-7, atol=0)


def test_expm1_matches_float64():
    x = np.concatenate([X_SMALL[np.abs(X_SMALL) < 50], [-200.0, -1e30]])
    got = to_np(numerics.expm1(f32(x)))
    want = np.expm1(x.astype(np.float32).astype(np.float64))
    np.testing.assert_allclose(got, want, rtol=3e-7, atol=1e-30)


def test_log_cos_over_sin2_is_finite_and_accurate():
    # theta from exactly 0 to just below pi/2
    theta = np.concatenate([[0.0], np.logspace(-8, np.log10(np.pi / 2 - 1e-6), 200)])
    c = np.cos(theta).astype(np.float32)
    s2 = (np.sin(theta) ** 2).astype(np.float32)
    got = to_np(numerics.log_cos_over_sin2(f32(c), f32(s2)))
    s64 = s2.astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        # near the pole from sin^2, near the horizon from cos (as float32 gave them)
        want = np.where(s64 == 0, -0.5, np.where(s64 < 0.5, 0.5 * np.log1p(-s64) / s64,
                                                 np.log(c.astype(np.float64)) / s64))
    assert np.isfinite(got).all()
    np.testing.assert_allclose(got, want, rtol=2e-5)


def test_schlick_limits():
    rs = mi.Color3f(0.1, 0.5, 1.0)
    assert np.allclose(to_np(schlick(rs, mi.Float(1.0))), [[0.1, 0.5, 1.0]])
    assert np.allclose(to_np(schlick(rs, mi.Float(0.0))), [[1.0, 1.0, 1.0]])
    assert np.allclose(to_np(schlick(mi.Float(0.2), mi.Float(0.5))), 0.2 + 0.8 * 0.5 ** 5)


@pytest.mark.parametrize("nu,nv", [(0, 0), (1, 1), (10, 1000), (1e6, 1e6), (1e6, 0), (1e-3, 1e4)])
def test_half_vector_warp_unit_and_upper(nu, nv):
    # a grid of samples including the corners and the quadrant borders of xi_1
    u1 = np.array([0, 1e-7, 0.125, 0.25 - 1e-7, 0.25, 0.5, 0.75, 0.999999, 1.0])
    u2 = np.array([0, 1e-7, 0.5, 0.999999, 1.0 - 2**-24])
    g1, g2 = np.meshgrid(u1, u2)
    h = warp.square_to_aniso_phong_half_vector(
        point2(g1, g2), nu, nv)
    hn = to_np(h)
    assert np.isfinite(hn).all()
    np.testing.assert_allclose(np.linalg.norm(hn, axis=1), 1, atol=1e-6)
    assert (hn[:, 2] >= 0).all()
    pdf = to_np(warp.aniso_phong_half_vector_pdf(h, nu, nv))
    assert np.isfinite(pdf).all() and (pdf >= 0).all()


@pytest.mark.parametrize("nu,nv", [(1, 1), (20, 20), (10, 1000), (1000, 10), (0, 50)])
def test_half_vector_pdf_matches_eq6(nu, nv):
    rng = np.random.default_rng(1)
    h = rng.normal(size=(2000, 3))
    h[:, 2] = np.abs(h[:, 2])
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    got = to_np(warp.aniso_phong_half_vector_pdf(vec(h), nu, nv))
    want = ashikhmin_shirley_half_pdf(h.astype(np.float32).astype(float), nu, nv)
    np.testing.assert_allclose(got, want, rtol=3e-4, atol=1e-6 * want.max())


@pytest.mark.parametrize("nu,nv,ires", [(1, 1, 8), (10, 10, 8), (10, 1000, 32), (1000, 10, 32), (0, 0, 4)])
def test_half_vector_warp_chi2(nu, nv, ires):
    """The samples of eq. 9-10 (with the quadrant mapping) follow the density of eq. 6."""
    ok, messages = warp_chi2(lambda u: warp.square_to_aniso_phong_half_vector(u, nu, nv),
                             lambda h: warp.aniso_phong_half_vector_pdf(h, nu, nv), ires)
    assert ok, messages


def test_half_vector_warp_quadrant_mapping_is_continuous():
    """phi grows monotonically with xi_1 over all four quadrants."""
    u1 = np.linspace(0, 1 - 1e-6, 4001).astype(np.float32)
    h = to_np(warp.square_to_aniso_phong_half_vector(
        point2(u1, np.full_like(u1, 0.5)), 10.0, 1000.0))
    phi = np.unwrap(np.arctan2(h[:, 1], h[:, 0]))
    assert (np.diff(phi) >= -1e-6).all()
    assert abs(phi[-1] - phi[0] - 2 * np.pi) < 1e-2
    # each quadrant of xi_1 lands in its own quadrant of phi
    for q in range(4):
        sel = (u1 >= q / 4 + 1e-3) & (u1 < (q + 1) / 4 - 1e-3)
        p = np.mod(phi[sel] - phi[0], 2 * np.pi)
        assert ((p >= q * np.pi / 2 - 1e-4) & (p <= (q + 1) * np.pi / 2 + 1e-4)).all()


def test_every_option_a_model_lists_is_one_it_takes():
    """``OPTIONS`` (a model's load-time choices, which tests and the study enumerate) lists
    every value the plugin accepts, and the plugin refuses any other."""
    from mitsuba_brdfs.core.registry import models
    needs = {("oren_nayar", "cltc"): {"form": "energy_preserving"}}  # valid combinations
    for name, model in models().items():
        for option, choices in model.OPTIONS.items():
            for value in choices:
                bsdf = mi.load_dict({"type": name, option: value, **needs.get((name, value), {})})
                assert getattr(bsdf, option) == value, (name, option, value)
            if isinstance(choices[0], str):
                with pytest.raises(RuntimeError, match=f"{name}: parameter '{option}' must be one of"):
                    mi.load_dict({"type": name, option: "none_of_them"})
