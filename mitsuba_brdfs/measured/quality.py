"""How good a fit is, on samples it did or did not use: ``quality`` (the relative RMS error
per channel), ``shape_loss`` (the fit's shape term on other samples: the held-out loss),
``bound_warnings`` (the parameters a fit left on the ends of their ranges).
"""
import numpy as np

__all__ = ["quality", "shape_loss", "bound_warnings"]


def quality(bsdf, wi, wo, f, weights=None):
    """The scale-free error of ``bsdf`` against the measured samples, per channel:
    'relative_rms' [R, G, B] = sqrt(sum w (f_model cos - f cos)^2 / sum w (f cos)^2) over
    the pairs, with the fit's weights w (0: exact; 1: as far off as a black model), and
    'relative_rms_max' its largest channel."""
    model, fcos, w = _terms(bsdf, wi, wo, f, weights)
    err = np.sqrt(np.sum(w[:, None] * (model - fcos) ** 2, axis=0)
                  / np.maximum(np.sum(w[:, None] * fcos ** 2, axis=0), 1e-300))
    return {"relative_rms": err.tolist(), "relative_rms_max": float(err.max())}


def _terms(bsdf, wi, wo, f, weights):
    """(the model's f cos, the measured f cos, the weights), float64."""
    from ..validate.probe import eval_np
    wo = np.asarray(wo, float)
    w = np.ones(len(wo)) if weights is None else np.asarray(weights, float)
    return (np.asarray(eval_np(bsdf, wi, wo), float).reshape(len(wo), -1),
            np.asarray(f, float) * wo[:, 2:3], w)


def shape_loss(bsdf, wi, wo, f, weights=None, kind="l2cos"):
    """The shape term of ``fitting.fit``'s loss on these samples (the held-out loss on
    samples the fit did not use): the mean over channels of sum w d^2 / sum w r^2, d the
    difference of the mapped f cos (``losses``: ``l2cos``, ``log``, ``cbrt``), r the
    measured term mapped (1: as far off as a black model); NaN without samples."""
    from .losses import mapped_np, scaled
    if len(wi) == 0:
        return float("nan")
    model, fcos, w = _terms(bsdf, wi, wo, f, weights)
    scale = max(float(np.abs(fcos).max()), 1e-30) if scaled(kind) else 1.0
    model, fcos = mapped_np(model / scale, kind, model=True), mapped_np(fcos / scale, kind)
    unit = np.sum(w[:, None] * fcos * fcos, axis=0)
    err = np.sum(w[:, None] * (model - fcos) ** 2, axis=0)
    return float(np.mean(np.where(unit > 1e-300, err / np.maximum(unit, 1e-300), 0.0)))


def bound_warnings(at_bounds):
    """One sentence naming every parameter a fit left on an end of its range (``fit``'s
    'at_bounds'), or None."""
    if not at_bounds:
        return None
    items = ", ".join(f"{a['parameter']} = {a['value']:.7g} ({a['end']} bound)"
                      for a in at_bounds)
    return (f"on the end of its range: {items} (the data ask for more than the model "
            f"allows there, or the parameter does not matter)")
