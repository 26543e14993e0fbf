"""Reciprocity: f(a, b) = f(b, a), the BSDF without the cosine."""
import numpy as np

from .probe import eval_np

__all__ = ["eval_both_ways", "check_reciprocal"]


def eval_both_ways(bsdf, a, b):
    """f(a, b) and f(b, a), the BSDF without the cosine."""
    f_ab = eval_np(bsdf, a, b) / b[:, 2:3].astype(np.float32)
    f_ba = eval_np(bsdf, b, a) / a[:, 2:3].astype(np.float32)
    return f_ab, f_ba


def check_reciprocal(bsdf, a, b, rtol=1e-3, err_msg=""):
    """f(a, b) = f(b, a) to rtol, and to 1e-6 of the largest value. Returns the largest
    difference relative to the largest value."""
    f_ab, f_ba = eval_both_ways(bsdf, a, b)
    np.testing.assert_allclose(f_ab, f_ba, rtol=rtol, atol=1e-6 * f_ab.max(), err_msg=err_msg)
    return float(np.abs(f_ab - f_ba).max() / (np.abs(f_ab).max() or 1.0))
