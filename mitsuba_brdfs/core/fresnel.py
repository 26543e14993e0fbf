"""Fresnel reflectance approximations."""
import drjit as dr

from .numerics import pow5

__all__ = ["schlick"]


def schlick(f0, cos_t):
    """Schlick's approximation F = F0 + (1 - F0)(1 - cos)^5 (AS 2000 eq. 3).

    ``f0`` may be a colour (reflectance at normal incidence per channel) or a float.
    """
    c = dr.clip(cos_t, 0, 1)
    return f0 + (1 - f0) * pow5(1 - c)
