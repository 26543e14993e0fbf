"""Reflectance as a NumPy function: ``bsdf_evaluator`` (a loaded BSDF's eval on NumPy
directions, f cos theta_o) and ``is_isotropic`` (whether such a function is unchanged
when both directions turn about the normal: 2000 random pairs, 4 turns). ``sources``
(``to-rgl``'s sources) and ``data`` (a ``--target``'s samples) use them.
"""
import numpy as np

__all__ = ["bsdf_evaluator", "is_isotropic"]


def bsdf_evaluator(bsdf):
    """eval of a loaded Mitsuba BSDF on NumPy directions (the front side, radiance mode)."""
    from ..validate.probe import eval_np

    def evaluate(wi, wo):
        out = []
        for s in range(0, len(wi), 1 << 18):
            out.append(np.asarray(eval_np(bsdf, wi[s:s + (1 << 18)], wo[s:s + (1 << 18)]),
                                  float).reshape(len(wi[s:s + (1 << 18)]), -1))
        return np.concatenate(out) if out else np.zeros((0, 3))
    return evaluate



def _rotate(v, angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1], v[:, 2]], -1)


def is_isotropic(evaluate, pairs=2000, seed=3, rtol=1e-3):
    """Whether ``evaluate`` is unchanged (to ``rtol`` of its largest value) when both
    directions turn about the normal by the same angle."""
    from ..validate.directions import random_upper
    rng = np.random.default_rng(seed)
    wi, wo = random_upper(rng, pairs), random_upper(rng, pairs)
    base = evaluate(wi, wo)
    scale = max(float(np.abs(base).max()), 1e-12)
    for angle in (0.7, 1.9, 3.1, 4.4):
        turned = evaluate(_rotate(wi, angle), _rotate(wo, angle))
        if np.abs(turned - base).max() > rtol * scale:
            return False
    return True
