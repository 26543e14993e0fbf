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
    """Unit half vector h of two directions, and the cosine wi.h = wo.h = |wi + wo| / 2.

    The cosine is taken from the length of s = wi + wo, not from a dot product: when wi and
    wo are nearly opposite (both grazing, azimuths apart by almost pi), |s|^2 is ~1e-8 while
    float32 directions are unit only to ~6e-8, so dot(wi, h) = (|wi|^2 + wi.wo) / |s| loses
    every digit and may come out negative. s itself is exact there (the difference of two
    close floats), so h and |s| / 2 keep float32 precision, and the cosine is >= 0 always.
    Where s vanishes (wi = -wo, which needs a direction below the surface, where one-sided
    models return 0 anyway) the half vector is undefined: h = n and the cosine is 0.
    """
    s = wi + wo
    l2 = dr.squared_norm(s)
    valid = l2 > 0
    inv = dr.rsqrt(dr.select(valid, l2, 1))
    h = dr.select(valid, s * inv, mi.Vector3f(0, 0, 1))
    return h, dr.select(valid, 0.5 * l2 * inv, 0)


def same_hemisphere_up(wi, wo):
    """Both directions strictly above the surface (one-sided BSDFs)."""
    return (cos_theta(wi) > 0) & (cos_theta(wo) > 0)
