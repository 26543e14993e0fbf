"""The shared checks: they pass on Mitsuba's own ``diffuse``, fail on a BSDF with a known
flaw, return what they measured, and fail without pytest and under ``python -O``."""
import os
import subprocess
import sys

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import user_bsdf
from mitsuba_brdfs.validate import energy, reciprocity, sampling, stability
from mitsuba_brdfs.validate.directions import (half_vector_sphere, hard_directions, hard_pairs,
                                               lobe_sphere, random_pairs, sph)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FLAWS = ("pdf_shape", "asymmetric", "nan", "below")


@pytest.fixture
def flawed():
    """The user's plugin (``user_bsdf``) as ``flawed``, of reflectance 1, with a flaw each:
    a pdf that is not the density of the samples, an asymmetric eval, a NaN at grazing
    incidence, light below the horizon."""
    user_bsdf.register("flawed", reflectance=1.0)
    return {flaw: mi.load_dict({"type": "flawed", "flaw": flaw}) for flaw in FLAWS}


def test_chi2_passes_diffuse_and_rejects_a_pdf_that_is_not_the_density(flawed, tmp_path,
                                                                       monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert sampling.check_chi2("diffuse", {}, 30, 32, 4) > 0.01
    sampling.check_chi2("flawed", {"flaw": "asymmetric"}, 30, 32, 4)  # sampled as it claims
    with pytest.raises(AssertionError, match="p-value"):
        sampling.check_chi2("flawed", {"flaw": "pdf_shape"}, 30, 32, 4)
    assert os.listdir(tmp_path) == []  # the test runs quietly: no chi2_data.py
    # the measurements behind the verdict, for a command to print
    r = sampling.chi2(flawed["pdf_shape"], [0.3, 0.2, 0.9327379], res=32, ires=4)
    assert not r["ok"] and r["p_value"] < 1e-6 and r["histogram"].shape == (32, 16)
    assert r["expected"].shape == (32, 16) and r["pdf_sum"] > r["histogram_sum"]


def test_sample_weight_check_catches_weights_that_are_not_eval_over_pdf(flawed):
    wi = [0.3, 0.2, 0.9]
    bs, ok = sampling.check_sample_weight_is_eval_over_pdf(mi.load_dict({"type": "diffuse"}), wi,
                                                           0.99, 1e-5, 1e-5)
    assert ok.all() and dr.width(bs.wo) == 20000
    with pytest.raises(AssertionError):
        sampling.check_sample_weight_is_eval_over_pdf(flawed["pdf_shape"], wi, 0.99, 1e-3, 1e-3)


def test_furnace_checks_measure_and_bound_the_albedo():
    white = mi.load_dict({"type": "diffuse", "reflectance": 1.0})
    assert np.allclose(energy.check_albedo_is_one(white, [0, 60]), 1)
    with pytest.raises(AssertionError):
        energy.check_albedo_is_one(mi.load_dict({"type": "diffuse", "reflectance": 0.9}), [0])
    assert energy.check_albedo_at_most_one(np.array([0.9, 1.0005]), np.array([0.01, 0.0])) == 1.0005
    with pytest.raises(AssertionError, match="gold"):
        energy.check_albedo_at_most_one(np.array([1.01]), np.array([0.001]), tag="gold")
    with pytest.raises(AssertionError):
        energy.check_albedo_at_most_one(np.array([np.nan]), np.array([0.0]))


def test_reciprocity_check_catches_an_asymmetric_eval(flawed):
    a, b = random_pairs(3, 500)
    assert reciprocity.check_reciprocal(mi.load_dict({"type": "diffuse"}), a, b) < 1e-6
    with pytest.raises(AssertionError):
        reciprocity.check_reciprocal(flawed["asymmetric"], a, b)


def test_stability_checks_catch_nan_at_grazing_incidence(flawed):
    wi, wo = hard_pairs(hard_directions())
    ctx = mi.BSDFContext()
    f, pdf = stability.check_eval_pdf_finite(mi.load_dict({"type": "diffuse"}), ctx, wi, wo)
    assert f.shape == (len(wi), 3) and pdf.shape == (len(wi),)
    with pytest.raises(AssertionError, match="grid"):
        stability.check_eval_pdf_finite(flawed["nan"], ctx, wi, wo, tag="grid")
    samples = stability.corner_samples(hard_directions(), stability.CORNERS, stability.CORNERS)
    w, _ = stability.check_samples_finite(mi.load_dict({"type": "diffuse"}), ctx, samples)
    assert len(w) == len(hard_directions()) * len(stability.CORNERS) ** 3
    with pytest.raises(AssertionError):
        stability.check_samples_finite(flawed["nan"], ctx, samples)
    stability.check_zero_below_horizon(mi.load_dict({"type": "diffuse"}))
    with pytest.raises(AssertionError):
        stability.check_zero_below_horizon(flawed["below"])


def test_checks_fail_under_python_O():
    code = "from mitsuba_brdfs.validate.probe import expect; expect(1 > 2, 'kept')"
    r = subprocess.run([sys.executable, "-O", "-c", code], cwd=ROOT, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 1 and "AssertionError: kept" in r.stderr


def test_quadratures_cover_the_sphere_and_resolve_sharp_grazing_lobes():
    wi = sph(np.radians(89), 0.3)[0]
    for wo, dw in (half_vector_sphere(64, wi), half_vector_sphere(64, -wi), lobe_sphere(64, wi)):
        np.testing.assert_allclose(np.linalg.norm(wo, axis=1), 1, atol=1e-12)
        assert dw.sum() == pytest.approx(4 * np.pi, rel=1e-4)
    # a lobe squeezed to ~1e-4 rad at grazing incidence: the mean sample weight and the
    # integral of eval agree (a grid of directions misses the lobe and finds 0.06)
    sharp = mi.load_dict({"type": "ashikhmin_shirley", "nu": 1e4, "nv": 1e4})
    (f, f_err), (p, _) = energy.quadrature(sharp, wi, 128, same_side=True)
    a, err = energy.albedo_at(sharp, wi, n=200_000)
    assert abs(a[0] - f[0]) < 5 * err[0] + f_err[0] + 1e-3 and 0.6 < f[0] < 0.62
    assert 0.8 < p < 0.82  # the share of samples that stay above the horizon
