"""The error-against-time section of the performance study: its arithmetic."""
import math

import pytest

from mitsuba_brdfs.bench import error as bench_error


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
