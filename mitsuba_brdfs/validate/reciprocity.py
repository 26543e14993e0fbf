"""Reciprocity: f(a, b) = f(b, a), the BSDF without the cosine."""
import numpy as np

from .probe import close, eval_np, expect

__all__ = ["eval_both_ways", "reciprocity_error", "check_reciprocal"]


def eval_both_ways(bsdf, a, b):
    """f(a, b) and f(b, a), the BSDF without the cosine."""
    f_ab = eval_np(bsdf, a, b) / np.abs(b[:, 2:3]).astype(np.float32)
    f_ba = eval_np(bsdf, b, a) / np.abs(a[:, 2:3]).astype(np.float32)
    return f_ab, f_ba


def reciprocity_error(bsdf, a, b, rtol=1e-3):
    """How far f(a, b) is from f(b, a): a ``close`` record (to rtol, and to 1e-6 of the
    largest value) whose ``max_rel`` is the largest difference relative to the largest
    value."""
    f_ab, f_ba = eval_both_ways(bsdf, a, b)
    scale = float(np.abs(f_ab).max(initial=0.0)) or 1.0
    r = close(f_ab, f_ba, rtol, atol=1e-6 * scale)
    r["max_rel"] = float(np.abs(f_ab - f_ba).max(initial=0.0) / scale)
    return r


def check_reciprocal(bsdf, a, b, rtol=1e-3, err_msg=""):
    """f(a, b) = f(b, a) to rtol, and to 1e-6 of the largest value. Returns the largest
    difference relative to the largest value."""
    r = reciprocity_error(bsdf, a, b, rtol)
    expect(r["ok"], (err_msg, r))
    return r["max_rel"]
