"""Numerically careful elementary functions for float32 kernels.

Dr.Jit has no ``log1p``/``expm1``. The forms below are Kahan's: they cancel the rounding
error of ``1 + x`` (resp. ``exp(x)``) exactly, so they keep full relative precision for
tiny arguments, which the sharp lobes (exponents up to 1e6) need.
"""
import drjit as dr

__all__ = ["log1p", "expm1", "pow5", "one_minus_pow5", "safe_div", "channel_mean",
           "log_cos_over_sin2"]


def log1p(x):
    """log(1 + x), accurate for |x| << 1 (x >= -1)."""
    u = 1 + x
    d = u - 1
    # u == 1 means x is below half an ulp of 1: log(1 + x) = x to working precision.
    tiny = d == 0
    return dr.select(tiny, x, dr.log(u) * (x / dr.select(tiny, 1, d)))


def expm1(x):
    """exp(x) - 1, accurate for |x| << 1."""
    u = dr.exp(x)
    d = u - 1
    lu = dr.log(u)
    exact = (d == 0) | (lu == 0)
    # far below zero exp(x) underflows: the answer is -1
    return dr.select(exact, x, dr.select(u == 0, -1, d * (x / dr.select(exact, 1, lu))))


def pow5(x):
    """x^5 by multiplication (Schlick's weights)."""
    x2 = x * x
    return x2 * x2 * x


def one_minus_pow5(y):
    """1 - (1 - y)^5 for y in [0, 1], with full relative precision for small y.

    Written out, 1 - (1 - y)^5 = y (5 - 10 y + 10 y^2 - 5 y^3 + y^4): the subtraction from 1
    that cancels every digit below y ~ 1e-7 in float32 (1 - y rounds to 1) is done exactly
    on paper. The polynomial's terms alternate, but for y <= 1 it stays within a few ulps.
    """
    return y * (5 + y * (-10 + y * (10 + y * (-5 + y))))


def safe_div(a, b):
    """a / b where b != 0, else 0 (and a gradient-safe denominator)."""
    ok = b != 0
    return dr.select(ok, a / dr.select(ok, b, 1), 0)


def channel_mean(c):
    """Mean over the colour channels of an RGB or spectral value, per lane (a Float, of
    Python or of lanes, is one channel).

    The channels' sum divided by their number: ``dr.mean(c, axis=0)`` of a JIT colour
    scales its sum by the number of lanes and back (n / (3 n)) with n written into the
    kernel as a constant, so that every call at another number of lanes (a check's batch, a
    fit's directions) compiled the BSDF's kernels again; ``dr.sum(c, axis=0)`` does not."""
    if not dr.is_array_v(c) or dr.depth_v(c) < 2 and dr.size_v(c) == dr.Dynamic:
        return c
    return dr.sum(c, axis=0) * (1.0 / dr.size_v(c))


def log_cos_over_sin2(cos_t, sin2_t):
    """log(cos t) / sin^2(t), finite and accurate for every t in [0, pi/2).

    The anisotropic Phong exponent ``E = (nu h_u^2 + nv h_v^2) / sin^2(theta_h)`` is 0/0 at
    h = n, and ``cos^E`` is ``exp(E log cos)``; regrouping as ``(nu h_u^2 + nv h_v^2) *
    (log cos / sin^2)`` leaves a ratio that tends to -1/2 at h = n. Near the pole
    ``log cos = 0.5 log1p(-sin^2)`` keeps the precision that ``log(cos)`` loses when cos is
    within float rounding of 1; away from it ``log(cos)`` is exact enough.
    """
    small = sin2_t < 1e-4
    mid = sin2_t < 0.5
    s = dr.select(small, 1, sin2_t)  # gradient-safe denominator
    series = -0.5 - 0.25 * sin2_t - sin2_t * sin2_t / 6  # Taylor series of log1p(-s)/(2 s)
    near = 0.5 * log1p(-dr.select(mid, s, 0)) / s
    far = dr.log(dr.maximum(cos_t, 1e-30)) / s
    return dr.select(small, series, dr.select(mid, near, far))
