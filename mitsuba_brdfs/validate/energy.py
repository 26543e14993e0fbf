"""Energy checks: the directional albedo (white furnace) by Monte Carlo and its bounds."""
import numpy as np

from .directions import sph
from .probe import expect, sample_bsdf, to_np

__all__ = ["albedo_at", "albedo", "check_albedo_is_one", "check_albedo_at_most_one"]


def albedo_at(bsdf, wi, n=300_000, seed=0, ctx=None):
    """Monte Carlo directional albedo at wi (mean sample weight) and its standard error."""
    _, (_, weight) = sample_bsdf(bsdf, wi, n, seed=seed, ctx=ctx)
    w = to_np(weight)
    return w.mean(axis=0), w.std(axis=0) / np.sqrt(n)


def albedo(bsdf, theta, n=300_000, seed=0, ctx=None):
    """albedo_at theta_i = theta degrees (phi = 0.7)."""
    return albedo_at(bsdf, sph(np.radians(theta), 0.7)[0], n, seed=seed, ctx=ctx)


def check_albedo_is_one(bsdf, thetas):
    """The albedo at each theta_i in thetas (degrees) is 1 to 1e-5 (100 000 samples): for a
    white Lambertian lobe, whose sample weights are all exactly 1. Returns the albedos."""
    out = []
    for theta in thetas:
        a, _ = albedo(bsdf, theta, n=100_000)
        np.testing.assert_allclose(a, 1, atol=1e-5, err_msg=f"theta = {theta}")
        out.append(a)
    return out


def check_albedo_at_most_one(a, err, tag=None):
    """An albedo estimate (with its standard error) is finite and at most 1 (up to 4 standard
    errors and 1e-3). Returns its largest value."""
    expect(np.isfinite(a).all(), (tag, a))
    expect((a <= 1 + 4 * err + 1e-3).all(), (tag, a, err))
    return float(np.max(a))
