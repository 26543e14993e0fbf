"""Sample warps and their densities, each sampler beside its pdf.

The cosine-weighted hemisphere comes from Mitsuba (``mi.warp``); written here are the
anisotropic Phong half-vector distribution of Ashikhmin & Shirley (2000, eq. 6, 9, 10),
the Phong cosine lobe around an arbitrary axis (Lafortune & Willems 1994), and Walter's
sampling of the Ward half-vector distribution (B. Walter, "Notes on the Ward BRDF",
Technical Report PCG-05-06, Cornell University, 2005), and the clipped linearly transformed
cosine of Portsmouth, Kutz and Hill ("EON: A Practical Energy-Preserving Rough Diffuse BRDF",
JCGT 14(1), 2025).
"""
import drjit as dr
import mitsuba as mi

from .numerics import expm1, log1p, log_cos_over_sin2, safe_div

__all__ = [
    "MAX_EXPONENT",
    "aniso_phong_cos_power", "aniso_phong_norm",
    "square_to_aniso_phong_half_vector", "aniso_phong_half_vector_pdf",
    "phong_lobe_cos_power", "square_to_phong_lobe", "phong_lobe_pdf",
    "ward_half_vector_exp", "square_to_ward_half_vector", "ward_half_vector_pdf",
    "reflection_jacobian",
    "square_to_clipped_ltc", "clipped_ltc_pdf",
]


#: largest cosine-power exponent a plugin accepts: up to it the lobes and their samplers keep
#: their width in float32 (tested); beyond it a lobe is narrower than float32 resolves near
#: its axis (~1e-3 rad wide at 1e6) and its value and sampling are no longer trustworthy
MAX_EXPONENT = 1e6


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


def _cos_power_elevation(xi, e):
    """(cos theta, sin theta) distributed as (e + 1) cos^e(theta) sin(theta) on [0, pi/2].

    Inverting the marginal gives cos(theta) = (1 - xi)^(1 / (e + 1)), taken in log space;
    sin^2(theta) = -expm1(2 log1p(-xi) / (e + 1)) stays exact where cos(theta) rounds to 1
    (exponents up to 1e6).
    """
    lg = log1p(-xi) / (e + 1)
    return dr.exp(lg), dr.safe_sqrt(-expm1(2 * lg))


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

    cos_t, sin_t = _cos_power_elevation(u.y, e)

    sx = dr.select((q == 1) | (q == 2), -1.0, 1.0)
    sy = dr.select(q >= 2, -1.0, 1.0)
    return mi.Vector3f(sx * sin_t * cos_phi, sy * sin_t * sin_phi, cos_t)


# -- Phong cosine lobe around an axis ----------------------------------------------------------

def phong_lobe_cos_power(w, axis, p):
    """cos^p(alpha), alpha = angle(w, axis), for unit vectors; 0 where cos(alpha) <= 0.

    sin^2(alpha) is taken from the cross product |w x axis|^2, which keeps its relative
    precision near the axis (the dot product rounds to 1 there, and a lobe of exponent 1e6
    is only ~1e-3 rad wide); the power is exp(p sin^2 * log(cos) / sin^2) with the ratio of
    ``numerics.log_cos_over_sin2``, which uses sin^2 near the axis and the dot product away
    from it (as ``aniso_phong_cos_power`` does for h and n). p = 0 gives 1 on the
    hemisphere around the axis.
    """
    cos_a = dr.dot(w, axis)
    sin2 = dr.squared_norm(dr.cross(w, axis))
    lobe = dr.exp(p * sin2 * log_cos_over_sin2(cos_a, sin2))
    return dr.select(cos_a > 0, lobe, 0)


def phong_lobe_pdf(w, axis, p):
    """(p + 1) / (2 pi) cos^p(alpha): the density of ``square_to_phong_lobe`` (solid angle)."""
    return (p + 1) * dr.inv_two_pi * phong_lobe_cos_power(w, axis, p)


def square_to_phong_lobe(u, axis, p):
    """Sample w with density (p + 1) / (2 pi) cos^p(angle(w, axis)) on the hemisphere
    around ``axis`` (a unit vector, e.g. the mirror direction).

    alpha from u_1 as AS eq. 10 draws theta_h (exact for p up to 1e6), phi = 2 pi u_2 around
    the axis, in the frame ``mi.Frame3f(axis)``.
    """
    cos_t, sin_t = _cos_power_elevation(u.x, p)
    s, c = dr.sincos(dr.two_pi * u.y)
    return mi.Frame3f(axis).to_world(mi.Vector3f(sin_t * c, sin_t * s, cos_t))


# -- Ward half-vector distribution (Walter 2005) -------------------------------------------------

#: cos^2(theta_h) below this is raised to it: exp(-tan^2 ...) is an exact float32 zero there
#: for alpha <= 1 (the exponent is then > 1e5), and 1 / cos^3 (and its derivative) stay finite
_WARD_MIN_COS2 = 1e-6


def _ward_tan2_term(h, au, av):
    """tan^2(theta_h) (cos^2 phi_h / au^2 + sin^2 phi_h / av^2) = ((h_u/au)^2 + (h_v/av)^2) / h_n^2."""
    x, y = h.x / au, h.y / av
    return (x * x + y * y) / dr.maximum(h.z * h.z, _WARD_MIN_COS2)


def ward_half_vector_exp(h, au, av):
    """exp(-tan^2(theta_h) (cos^2 phi_h / au^2 + sin^2 phi_h / av^2)), 0 below the surface.

    The exponential of Ward's lobe written without trigonometry (the lecture's second form);
    it underflows to an exact 0 far from n for small alphas, never to NaN.
    """
    return dr.select(h.z > 0, dr.exp(-_ward_tan2_term(h, au, av)), 0)


def ward_half_vector_pdf(h, au, av):
    """Density of ``square_to_ward_half_vector`` over the solid angle of h (Walter 2005):

        p_h(h) = exp(-tan^2(theta_h) (cos^2 phi_h / au^2 + sin^2 phi_h / av^2))
                 / (pi au av cos^3(theta_h)),

    i.e. D(h) cos(theta_h) for the anisotropic Gaussian-slope (Beckmann) distribution
    D = exp(...) / (pi au av cos^4), which integrates to 1 over the hemisphere.
    """
    c3 = dr.maximum(h.z * h.z, _WARD_MIN_COS2) * dr.maximum(h.z, 1e-3)
    return ward_half_vector_exp(h, au, av) / (dr.pi * au * av * c3)


def square_to_ward_half_vector(u, au, av):
    """Sample h with density ``ward_half_vector_pdf`` (Walter 2005, eq. 6 and 7).

    Walter's phi_h = atan(av/au tan(2 pi u_2)) is the direction of
    (au cos(2 pi u_2), av sin(2 pi u_2)): normalising that vector gives cos and sin of phi_h
    in the right quadrant, with no tan/atan (finite at u_2 = 1/4, 3/4). The angular factor
    cos^2 phi_h / au^2 + sin^2 phi_h / av^2 is then 1 / (au^2 cos^2 + av^2 sin^2) of that
    same vector. theta_h follows from tan^2(theta_h) = -log(1 - u_1) / (angular factor)
    (Walter writes -log(u_1); 1 - u_1 keeps u_1 = 0 finite and maps it to h = n), and
    cos^2 = 1 / (1 + tan^2), sin^2 = tan^2 cos^2 keep both exact for alpha = 1e-4.
    """
    s, c = dr.sincos(dr.two_pi * u.y)
    a, b = au * c, av * s
    r2 = a * a + b * b
    r = dr.rsqrt(r2)
    cos_phi, sin_phi = a * r, b * r
    # the largest float32 below 1 for u_1 = 1: tan^2 stays finite (16.6 r^2)
    tan2 = -log1p(-dr.minimum(u.x, 1 - 2.0 ** -24)) * r2
    cos2 = 1 / (1 + tan2)
    sin_t = dr.safe_sqrt(tan2 * cos2)
    return mi.Vector3f(sin_t * cos_phi, sin_t * sin_phi, dr.safe_sqrt(cos2))


# -- clipped linearly transformed cosine (Portsmouth, Kutz and Hill 2025) ------------------------
# A linearly transformed cosine (Heitz et al. 2016) is the cosine lobe wh ~ cos / pi mapped by
# a 3x3 matrix M, w = M wh / |M wh|. With M = [[a, 0, b], [0, c, 0], [d, 0, 1]] in the frame
# whose x axis is the azimuth of wi, only the part of the cosine lobe that M maps above the
# surface (d wh_x + wh_z > 0) is kept and renormalised: in the unit disk of the projected
# wh it is (for d <= 0, as EON's fit has it) the half disk x < 0 plus the half ellipse
# x >= 0, x^2 (1 + d^2) + y^2 < 1 (mirrored for d > 0), of area pi s with
# s = (1 + 1 / sqrt(1 + d^2)) / 2. Squeezing the disk's x by s maps it onto that region, so
# every sample lands above the surface and the density is wh_z / (pi s) times the Jacobian
# of wh -> w.

def _azimuth_frame(wi):
    """(x, y) axes of the frame whose x is the azimuth of wi (x = u where wi is the normal)."""
    l2 = wi.x * wi.x + wi.y * wi.y
    ok = l2 > 0
    inv = dr.rsqrt(dr.select(ok, l2, 1))
    x = mi.Vector3f(dr.select(ok, wi.x * inv, 1), dr.select(ok, wi.y * inv, 0), 0)
    return x, mi.Vector3f(-x.y, x.x, 0)


def _clipped_disk_scale(d):
    """s = (1 + 1 / sqrt(1 + d^2)) / 2, the area of the kept region over pi."""
    return 0.5 * (1 + dr.rsqrt(d * d + 1))


def square_to_clipped_ltc(u, wi, a, b, c, d):
    """A direction above the surface drawn from the clipped LTC of matrix (a, b, c, d)
    (see above), in the frame whose x axis is the azimuth of wi (EON's listing 2)."""
    r = dr.sqrt(u.x)
    sn, cs = dr.sincos(dr.two_pi * u.y)
    x, y = r * cs, r * sn
    s = _clipped_disk_scale(d)
    # the disk's x squeezed onto [-sqrt(1 - y^2), sqrt(1 - y^2) / sqrt(1 + d^2)] (d <= 0)
    x = dr.select(d > 0, 1.0, -1.0) * dr.lerp(dr.safe_sqrt(1 - y * y), x, s)
    wh = mi.Vector3f(x, y, dr.safe_sqrt(1 - x * x - y * y))
    w = dr.normalize(mi.Vector3f(a * wh.x + b * wh.z, c * wh.y, d * wh.x + wh.z))
    fx, fy = _azimuth_frame(wi)
    return w.x * fx + w.y * fy + mi.Vector3f(0, 0, w.z)


def clipped_ltc_pdf(w, wi, a, b, c, d):
    """Density of ``square_to_clipped_ltc`` over the solid angle of w:
    (|M| / |adj(M) w|^2)^2 max(0, (adj(M) w)_z) / (pi s) above the surface, 0 below."""
    fx, fy = _azimuth_frame(wi)
    lx, ly, lz = dr.dot(w, fx), dr.dot(w, fy), w.z
    det = c * (a - b * d)
    # adj(M) w = |M| M^-1 w, in the LTC frame
    hx, hy, hz = c * (lx - b * lz), (a - b * d) * ly, c * (a * lz - d * lx)
    len2 = hx * hx + hy * hy + hz * hz
    q = det / dr.select(len2 > 0, len2, 1)
    pdf = q * q * dr.maximum(hz, 0) / (dr.pi * _clipped_disk_scale(d))
    return dr.select((len2 > 0) & (w.z > 0), pdf, 0)


# -- from half vectors to reflected directions ---------------------------------------------------

def reflection_jacobian(cos_oh):
    """d omega_h / d omega_o = 1 / (4 wo.h) of the reflection wo = 2 (wi.h) h - wi
    (wo.h = wi.h): a density of h times this is the density of the reflected direction."""
    return safe_div(1.0, 4 * cos_oh)
