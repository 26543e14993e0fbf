"""Sample warps and their densities, each sampler beside its pdf.

The cosine-weighted hemisphere comes from Mitsuba (``mi.warp``); the anisotropic Phong
half-vector distribution of Ashikhmin & Shirley (2000, eq. 6, 9, 10) is written here.
"""
import drjit as dr
import mitsuba as mi

from .numerics import expm1, log1p, log_cos_over_sin2

__all__ = [
    "square_to_cosine_hemisphere", "square_to_cosine_hemisphere_pdf",
    "aniso_phong_cos_power", "aniso_phong_norm",
    "square_to_aniso_phong_half_vector", "aniso_phong_half_vector_pdf",
]


def square_to_cosine_hemisphere(u):
    return mi.warp.square_to_cosine_hemisphere(u)


def square_to_cosine_hemisphere_pdf(w):
    return mi.warp.square_to_cosine_hemisphere_pdf(w)


def aniso_phong_cos_power(h, nu, nv):
    """(n.h)^(nu cos^2 phi + nv sin^2 phi) for a unit half vector h above the surface.

    AS eq. 4 writes the exponent without trigonometry as
    (nu h_u^2 + nv h_v^2) / (1 - h_n^2); that quotient is 0/0 at h = n. Here
    1 - h_n^2 is taken as h_u^2 + h_v^2 (no cancellation) and the power is
    exp((nu h_u^2 + nv h_v^2) * log(h_n) / sin^2), whose ratio stays finite (-1/2 at h = n).
    """
    hu2, hv2 = h.x * h.x, h.y * h.y
    sin2 = hu2 + hv2
    return dr.exp((nu * hu2 + nv * hv2) * log_cos_over_sin2(h.z, sin2))


def aniso_phong_norm(nu, nv):
    """sqrt((nu + 1)(nv + 1)), as a product of roots so that huge exponents do not overflow."""
    return dr.sqrt(nu + 1) * dr.sqrt(nv + 1)


def aniso_phong_half_vector_pdf(h, nu, nv):
    """AS eq. 6: p_h(h) = sqrt((nu+1)(nv+1)) / (2 pi) (n.h)^(nu cos^2 phi + nv sin^2 phi).

    A density over the solid angle of h on the upper hemisphere (zero below).
    """
    p = aniso_phong_norm(nu, nv) * dr.inv_two_pi * aniso_phong_cos_power(h, nu, nv)
    return dr.select(h.z > 0, p, 0)


def square_to_aniso_phong_half_vector(u, nu, nv):
    """Sample h with density AS eq. 6 (eq. 9, 10 and the quadrant mapping of xi_1).

    xi_1 picks a quadrant ([0,.25), [.25,.5), [.5,.75), [.75,1)) and is stretched back
    to [0, 1) inside it, mirrored in odd quadrants so that phi grows continuously with
    xi_1 over [0, 2 pi): every quadrant is covered and stratified. Eq. 9 is evaluated
    without tan/atan: tan(phi) = sqrt((nu+1)/(nv+1)) tan(pi xi / 2) is the direction
    (sqrt(nv+1) cos(pi xi/2), sqrt(nu+1) sin(pi xi/2)), finite at every xi and exponent.
    Eq. 10, cos(theta) = (1 - xi_2)^(1/(E+1)), is taken in log space and
    sin^2(theta) = -expm1(2 log1p(-xi_2) / (E+1)), exact where cos(theta) rounds to 1.
    """
    x1 = 4 * u.x
    q = dr.minimum(dr.floor(x1), 3)  # quadrant 0..3
    t = x1 - q
    odd = (q == 1) | (q == 3)
    t = dr.select(odd, 1 - t, t)  # mirror: phi continuous across quadrant borders
    s0, c0 = dr.sincos(dr.pi * 0.5 * t)
    a, b = dr.sqrt(nv + 1) * c0, dr.sqrt(nu + 1) * s0
    r = dr.rsqrt(a * a + b * b)
    cos_phi, sin_phi = a * r, b * r
    e = nu * cos_phi * cos_phi + nv * sin_phi * sin_phi

    lg = log1p(-u.y) / (e + 1)
    cos_t = dr.exp(lg)
    sin_t = dr.safe_sqrt(-expm1(2 * lg))

    sx = dr.select((q == 1) | (q == 2), -1.0, 1.0)
    sy = dr.select(q >= 2, -1.0, 1.0)
    return mi.Vector3f(sx * sin_t * cos_phi, sy * sin_t * sin_phi, cos_t)
