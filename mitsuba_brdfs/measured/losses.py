"""The shape losses of a fit: how a model's f cos theta_o is compared with the data's.

Each loss maps both terms, the model's and the measured f cos (in units of the largest
measured one, so that the loss does not depend on the data's scale), through a function
g and takes the weighted mean of the squared differences per channel, each channel over a
black model's (``fitting``: 1 is as far off as black):

- ``l2cos`` (Ngan et al. 2005), g(x) = x: the cosine-weighted L2 of the BRDF itself. The
  highlight's peak and the energy dominate; it fits the shape of a sharp lobe and the
  albedo best, and weighs a dim diffuse base or a lobe's tails (what most of a rendered
  surface shows) next to nothing. The default, and the held-out loss's.
- ``log`` (Low et al. 2012), g(x) = log(1 + x): compresses the highlight, so that the
  tails and the diffuse base count as much as the peak; Low et al. find fits with it
  closer to renders of glossy materials, Kavoosighafi et al. (2025) find log-mapped losses
  the best for fitting. It helps where l2cos gets the peak and misses the look (a glossy
  film's haze, a paint's base colour); it cares less about the peak's exact height.
- ``cbrt`` (Fores et al. 2012), g(x) = (x + 1e-6)^(1/3): the cube root that CIELAB's
  lightness applies to luminance, a perceptual middle between the two: the peak counts
  more than in ``log``, the base more than in ``l2cos``. It helps where both matter (a
  coloured base under a visible highlight: plastics, paints, vinyl films). Its gradient is
  steep where the model is near 0 (1e-6 keeps it finite).

A negative measured value (an out-of-gamut colour, ``docs/measured.md``) is mapped as it is
(``log``: log(1 + x) of it, ``cbrt``: its signed cube root); the model is clipped at 0.

References: A. Ngan, F. Durand, W. Matusik, "Experimental Analysis of BRDF Models", EGSR
2005; J. Low, J. Kronander, A. Ynnerman, J. Unger, "BRDF Models for Accurate and Efficient
Rendering of Glossy Surfaces", ACM TOG 31(1), 2012; A. Fores, J. Ferwerda, J. Gu, "Toward
a Perceptually Based Metric for BRDF Modeling", Color and Imaging Conference 2012; B.
Kavoosighafi, J. Frisvad, S. Hajisharif, J. Unger, E. Miandji, "A Survey on Measured BRDF
Models and Fitting Metrics", Computer Graphics Forum 2025 (and their study of fitting
metrics).
"""
import numpy as np

__all__ = ["LOSSES", "EPSILON", "mapped", "mapped_np", "scaled"]

LOSSES = ("l2cos", "log", "cbrt")
#: the cube root's offset (in units of the largest measured value)
EPSILON = 1e-6


def scaled(kind):
    """Whether the loss compares values in units of the largest measured one (``log``
    compares f cos as it is, as Low et al.)."""
    return kind != "log"


def mapped(value, kind):
    """g of the model's values (Dr.Jit), clipped at 0 first for ``log`` and ``cbrt``."""
    import drjit as dr
    if kind == "log":
        return dr.log(1 + dr.maximum(value, 0))
    if kind == "cbrt":
        return dr.cbrt(dr.maximum(value, 0) + EPSILON)
    return value


def mapped_np(value, kind, model=False):
    """g of values (NumPy): the data's as they are (negative ones too), or a ``model``'s
    clipped at 0 as ``mapped`` does."""
    value = np.asarray(value, float)
    if model and kind != "l2cos":
        value = np.maximum(value, 0)
    if kind == "log":
        return np.log1p(np.maximum(value, -0.999))
    if kind == "cbrt":
        return np.cbrt(value + EPSILON)
    return value
