"""The plugins only the performance study uses: naive formulas and a cosine-sampling wrapper."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mitsuba_brdfs.bench import plugins as bench_plugins
from mitsuba_brdfs.sphere import sphere_scene
from mitsuba_brdfs.validate.probe import point2


@pytest.fixture
def bench_plugins_registered():
    bench_plugins.register()


def test_naive_forms_agree_with_the_stable_ones_at_moderate_exponents():
    from mitsuba_brdfs.core import warp
    rng = np.random.default_rng(0)
    u = point2(*rng.uniform(0.01, 0.99, (2, 1000)))
    h = warp.square_to_aniso_phong_half_vector(u, 20.0, 50.0)
    a = np.array(warp.aniso_phong_cos_power(h, 20.0, 50.0))
    b = np.array(bench_plugins.naive_aniso_phong_cos_power(h, 20.0, 50.0))
    np.testing.assert_allclose(b, a, rtol=1e-3, atol=1e-6)
    hn = np.array(bench_plugins.naive_aniso_phong_half_vector(u, 20.0, 50.0))
    np.testing.assert_allclose(hn, np.array(h), atol=2e-4)


def test_cosine_wrapper_keeps_eval_and_estimates_the_same_albedo(bench_plugins_registered):
    inner = {"type": "cook_torrance", "roughness": 0.5}
    wrapped = mi.load_dict({"type": "bench_cosine", "bsdf": inner})
    model = mi.load_dict(inner)
    n = 200_000
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(0.6, 0, 0.8)
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(1, n)
    ctx = mi.BSDFContext()
    bs, w = wrapped.sample(ctx, si, sampler.next_1d(), sampler.next_2d())
    np.testing.assert_allclose(np.array(wrapped.eval(ctx, si, bs.wo)), np.array(model.eval(ctx, si, bs.wo)))
    np.testing.assert_allclose(np.array(bs.pdf), np.array(bs.wo.z) / np.pi, rtol=1e-5)
    _, w_model = model.sample(ctx, si, sampler.next_1d(), sampler.next_2d())
    a, b = np.array(w).mean(axis=1), np.array(w_model).mean(axis=1)
    np.testing.assert_allclose(a, b, rtol=0.03)


def test_naive_plugin_renders(bench_plugins_registered):
    bsdf = {"type": "bench_as_naive", "nu": 100.0, "nv": 100.0, "diffuse_reflectance": 0.0,
            "specular_reflectance": 1.0}
    img = np.array(mi.render(sphere_scene(bsdf, 16, 4)))
    assert np.isfinite(img).all() and img.mean() > 0
