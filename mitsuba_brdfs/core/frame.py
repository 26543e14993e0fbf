"""Local shading-frame helpers (z = normal, x = u tangent, y = v tangent)."""
import drjit as dr
import mitsuba as mi

__all__ = ["cos_theta", "reflect", "mirror", "half_vector", "same_hemisphere_up"]


def cos_theta(w):
    return w.z


def reflect(w, h):
    """Mirror ``w`` about the unit vector ``h``: 2 (w.h) h - w."""
    return 2 * dr.dot(w, h) * h - w


def mirror(w):
    """``w`` mirrored about the normal, 2 (n.w) n - w = (-w_x, -w_y, w_z) (exact)."""
    return mi.Vector3f(-w.x, -w.y, w.z)


def half_vector(wi, wo):
    """Unit half vector of two directions above the surface, and whether it exists.

    Returns (h, valid); where wi + wo vanishes (wi = -wo), h = n and valid is False.
    """
    s = wi + wo
    l2 = dr.squared_norm(s)
    valid = l2 > 0
    h = dr.select(valid, s * dr.rsqrt(dr.select(valid, l2, 1)), mi.Vector3f(0, 0, 1))
    return h, valid


def same_hemisphere_up(wi, wo):
    """Both directions strictly above the surface (one-sided BSDFs)."""
    return (cos_theta(wi) > 0) & (cos_theta(wo) > 0)
