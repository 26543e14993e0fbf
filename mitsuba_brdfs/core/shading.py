"""Band functions of non-photorealistic (toon) shading.

A toon shader replaces a continuous shading term by a few flat colours chosen by
thresholds on a cosine. ``smooth_step`` is the switch between two bands: a hard step at
width 0 (the classic two-band formula), a Hermite smooth step over a window of the
given width centred on the threshold otherwise (the "small gradients added to smooth the
transitions" of the lecture). Both are branch-free (``dr.select``), so they trace into
rendering kernels and keep finite derivatives.
"""
import drjit as dr

from .numerics import safe_div

__all__ = ["smooth_step", "band"]


def smooth_step(x, edge, width):
    """0 below ``edge - width/2``, 1 above ``edge + width/2``, 3t^2 - 2t^3 in between.

    ``width = 0`` gives the hard step ``x >= edge``. ``width`` may vary per lane (a
    texture); its zero lanes take the hard step, with a gradient-safe denominator.
    """
    t = dr.clip(safe_div(x - edge, width) + 0.5, 0, 1)
    soft = t * t * (3 - 2 * t)
    return dr.select(width > 0, soft, dr.select(x >= edge, 1.0, 0.0))


def band(x, edge, width, upper, lower):
    """``upper`` where x is above the threshold ``edge``, ``lower`` below, blended by
    ``smooth_step`` (exactly ``upper`` / ``lower`` outside the transition window)."""
    s = smooth_step(x, edge, width)
    return dr.lerp(lower, upper, s)
