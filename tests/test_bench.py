"""The performance study: its helpers, its method, and a whole ``bench --quick`` run."""
import json
import math
import os
import subprocess
import sys

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mitsuba_brdfs import bench, bench_error, bench_plugins
from mitsuba_brdfs.timing import kernel_stats, paired_fresh, sphere_scene

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


# -- helpers -----------------------------------------------------------------------------

def test_time_to_target_interpolates_and_extrapolates():
    pts = [(1.0, 0.4), (4.0, 0.2), (16.0, 0.1)]  # Monte Carlo: RMSE ~ time^-1/2
    t, extra = bench_error.time_to_target(pts, 0.2)
    assert t == pytest.approx(4.0) and not extra
    t, extra = bench_error.time_to_target(pts, math.sqrt(0.4 * 0.2))
    assert t == pytest.approx(2.0) and not extra
    t, extra = bench_error.time_to_target(pts, 0.05)
    assert t == pytest.approx(64.0) and extra
    assert bench_error.time_to_target(pts, 1.0) == (1.0, False)
    assert math.isnan(bench_error.time_to_target([], 0.1)[0])


def test_relative_rmse_subtracts_the_reference_variance():
    assert bench_error.relative_rmse(0.05, 0.01, 2.0) == pytest.approx(0.1)
    assert bench_error.relative_rmse(0.01, 0.02, 1.0) == 0.0


def test_git_info_names_the_commit():
    g = bench.git_info()
    assert len(g["commit"]) == 40 and g["date"]
    assert isinstance(g["dirty"], list)


# -- the study's plugins -------------------------------------------------------------------

@pytest.fixture
def bench_plugins_registered():
    bench_plugins.register()


def test_naive_forms_agree_with_the_stable_ones_at_moderate_exponents():
    from mitsuba_brdfs.core import warp
    rng = np.random.default_rng(0)
    u = mi.Point2f(*rng.uniform(0.01, 0.99, (2, 1000)).astype(np.float32))
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


# -- the method --------------------------------------------------------------------------

def test_every_live_bsdf_is_traced_into_a_render():
    """Why the study builds each scene afresh: a live BSDF elsewhere changes the kernel."""
    scene = sphere_scene({"type": "diffuse"}, 16, 4)
    alone = kernel_stats(scene)["instructions_max"]
    other = mi.load_dict({"type": "roughconductor"})  # noqa: F841  (alive, in no scene)
    with_other = kernel_stats(scene)["instructions_max"]
    del other
    import gc
    gc.collect()
    assert with_other > alone
    assert kernel_stats(scene)["instructions_max"] == alone


def test_rebuilt_scenes_reuse_their_kernels():
    """paired_fresh: no JIT compilation inside the timed runs."""
    builders = {"a": lambda: sphere_scene({"type": "ashikhmin_shirley"}, 16, 4),
                "b": lambda: sphere_scene({"type": "roughconductor"}, 16, 4)}
    paired_fresh(builders, runs=1)
    import gc
    for name in ("a", "b", "b", "a"):
        scene = builders[name]()
        st = kernel_stats(scene)
        assert st["cache_hits"] == st["kernels"], (name, st)
        del scene
        gc.collect()


# -- the whole quick study ---------------------------------------------------------------------

def _finite_positive(x):
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


@pytest.mark.slow
def test_bench_quick_writes_a_sane_study(tmp_path):
    r = subprocess.run([sys.executable, "-m", "mitsuba_brdfs", "bench", "--quick", "--out",
                        str(tmp_path)], cwd=ROOT, capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    doc = (tmp_path / "performance.md").read_text()
    res = json.loads((tmp_path / "perf" / "results.json").read_text())
    assert res["mode"] == "quick" and len(res["git"]["commit"]) == 40
    assert res["git"]["commit"] in doc and "--quick" in doc
    # the reduced run stays reduced (the study must not silently grow)
    assert res["total_seconds"] < 180, res["section_seconds"]
    for png in ("error_vs_time", "speed_vs_cpp", "effects", "stable_vs_naive", "memory"):
        p = tmp_path / "perf" / f"{png}.png"
        assert p.exists() and p.stat().st_size > 1000, png
        assert f"perf/{png}.png" in doc

    # 1. error against time: positive times, RMSE falling with spp under MIS
    err = res["error"]
    assert "ashikhmin_shirley" in res["available"] and "as_metal_1000" in err["scenes"]
    for key, sc in err["scenes"].items():
        for name, s in sc["strategies"].items():
            assert all(_finite_positive(t) for t in s["seconds"]), (key, name)
            assert all(math.isfinite(e) and e >= 0 for e in s["rel_rmse"]), (key, name)
            if "MIS" in name:
                assert s["rel_rmse"][-1] < s["rel_rmse"][0], (key, name, s["rel_rmse"])
    for row in err["bsdf_alone"]["incidences"].values():
        assert float(row["efficiency_ratio"]) > 10  # importance sampling wins by far

    # 2./4. every ratio finite and positive; compile and instruction counts reported
    for sec in ("cpp", "effects"):
        assert res[sec]["pairs"], sec
        for key, p in res[sec]["pairs"].items():
            assert all(_finite_positive(p[k]) for k in ("ratio", "ratio_min", "ratio_max",
                                                        "median_a", "median_b")), (sec, key)
            assert p["ratio_min"] <= p["ratio"] <= p["ratio_max"]
            assert p["instr_a"] > 0 and p["instr_b"] > 0 and p["compile_a"] >= 0
    # a lobe of constant zero weight is not traced
    for key, p in res["effects"]["pairs"].items():
        if p["kind"] == "lobe":
            assert p["instr_a"] < p["instr_b"], key
    for f, s in res["figures"]["scenes"].items():
        assert _finite_positive(s["ratio"]), f

    # 3. accuracy: the stable forms are exact to float32, their ratios finite
    forms = res["accuracy"]["stable_vs_naive"]["forms"]
    for name, row in forms.items():
        assert _finite_positive(row["ratio_naive_stable"]), name
        for e, er in row["error"].items():
            assert er["stable"]["nonfinite"] == 0 and float(er["stable"]["max"]) < 1e-3, (name, e)
    chi2 = res["accuracy"]["chi2"]["samples"]
    assert all(not r["clean"]["rejected"] for r in chi2.values())
    assert any(v["rejected"] for r in chi2.values() for v in r["scale"].values())

    # 5. memory: every CLI render succeeded and was measured
    for m in res["memory"]["renders"]:
        assert m["status"] == 0 and _finite_positive(m["peak_rss_mib"]), m
