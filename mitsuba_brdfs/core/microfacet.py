"""Microfacet reflection: distributions of normals, shadowing-masking, the specular term.

A microfacet BRDF (Cook & Torrance 1982; Torrance & Sparrow 1967) is

    f_s(l, v) = D(h) F(v.h) G(l, v) / (4 cos(theta_l) cos(theta_v)),   h = normalize(l + v)

and is importance-sampled by drawing a microfacet normal h, reflecting the incident
direction about it and dividing the density of h by the Jacobian 4 (v.h) of h -> wo
(``warp.reflection_jacobian``).

Distributions (the lecture's parameterisation by the roughness rho; each one is normalised
so that D(h) cos(theta_h) integrates to 1 over the hemisphere):

- ``Beckmann``: D = exp(-tan^2 / rho^2) / (pi rho^2 cos^4);
- ``Blinn``: D = (p + 2) / (2 pi) cos^p, with p = 2 / rho^2 - 2 when built from a
  roughness (the lecture's "Blinn" D, = cos^p / (pi rho^2)), or from an exponent p
  directly (Akyuz eq. 11);
- ``GGX``: D = rho^2 / (pi (cos^2 (rho^2 - 1) + 1)^2), with Smith's separable shadowing
  G1 = 2 / (1 + sqrt(1 + rho^2 tan^2)) and the sampling of visible normals.

Each has ``eval(h)``, ``sample(u)`` (h with density D(h) cos(theta_h)) and ``pdf(h)``
side by side; ``GGX`` also ``sample_visible(wi, u)`` / ``pdf_visible(wi, h)``. A roughness
below ``MIN_ROUGHNESS`` is raised to it (a mirror to float32 precision), so rho = 0 is a
valid input.

Numerics: tan^2 is sin^2 / cos^2 with sin^2 = h_x^2 + h_y^2 (no cancellation at h = n)
and the denominators clamped where the value is an exact 0 anyway; every function is
finite (and has finite derivatives) at h = n, at grazing angles and for rho in
[1e-4, 1], so derivatives through ``dr.select`` stay finite too.

The two-lobe model built on them (Lambertian diffuse + microfacet specular), which
``cook_torrance`` and ``torrance_sparrow`` specialise, is ``models/_microfacet_family.py``.

References: R. L. Cook, K. E. Torrance, "A Reflectance Model for Computer Graphics",
ACM TOG 1(1), 1982. B. Walter et al., "Microfacet Models for Refraction through Rough
Surfaces", EGSR 2007. E. Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT
7(4), 2018. J. Dupuy, A. Benyoub, "Sampling Visible GGX Normals with Spherical Caps",
CGF 42(8), 2023.
"""
import drjit as dr
import mitsuba as mi

from .frame import cos_theta
from .numerics import log1p, safe_div
from .roughness import half_vector_exponent
from .warp import aniso_phong_cos_power, aniso_phong_half_vector_pdf, reflection_jacobian, \
    square_to_aniso_phong_half_vector

__all__ = [
    "MIN_ROUGHNESS", "Beckmann", "Blinn", "GGX", "DISTRIBUTIONS",
    "vgroove_g", "smith_ggx_g1", "smith_ggx_g1_over_cos", "smith_ggx_g", "GEOMETRIES",
    "reflection_jacobian", "microfacet_specular",
]

#: smallest roughness used: D peaks at 1 / (pi rho^2) ~ 3e7, far from float32 limits
MIN_ROUGHNESS = 1e-4
#: cos^2(theta) below this is raised to it: exp(-tan^2 / rho^2) is an exact float32 zero
#: there for any rho <= 30, and 1 / cos^4 and its derivative stay finite
_MIN_COS2 = 1e-6
#: largest float32 below 1: keeps log(1 - u) and u / (1 - u) finite for u = 1
_ONE_MINUS_EPS = 1 - 2.0 ** -24


def _cos2_sin2(h):
    """(cos^2, sin^2) of the angle between a unit vector and n, sin^2 without cancellation."""
    return h.z * h.z, h.x * h.x + h.y * h.y


def _roughness(rho):
    return dr.maximum(rho, MIN_ROUGHNESS)


def _from_polar(cos2, sin2, u_phi):
    """A unit vector from cos^2, sin^2 of theta and phi = 2 pi u_phi."""
    s, c = dr.sincos(dr.two_pi * u_phi)
    sin_t = dr.safe_sqrt(sin2)  # safe: sin = 0 at u = 0 has an infinite derivative
    return mi.Vector3f(sin_t * c, sin_t * s, dr.safe_sqrt(cos2))


# -- distributions ------------------------------------------------------------------------

class Beckmann:
    """Beckmann distribution of slopes (lecture "Beckmann"; Cook & Torrance 1982)."""

    def __init__(self, rho):
        self.rho = _roughness(rho)

    def eval(self, h):
        """D(h) = exp(-tan^2 / rho^2) / (pi rho^2 cos^4), zero below the surface."""
        a2 = self.rho * self.rho
        cos2, sin2 = _cos2_sin2(h)
        c2 = dr.maximum(cos2, _MIN_COS2)
        # two divisions: the derivative of x / b squares b, and (pi rho^2 cos^4)^2 underflows
        d = dr.exp(-sin2 / (c2 * a2)) / (c2 * c2) / (dr.pi * a2)
        return dr.select(h.z > 0, d, 0)

    def sample(self, u):
        """h with density D cos: tan^2 = -rho^2 log(1 - u_1), phi = 2 pi u_2."""
        tan2 = -(self.rho * self.rho) * log1p(-dr.minimum(u.x, _ONE_MINUS_EPS))
        cos2 = 1 / (1 + tan2)
        return _from_polar(cos2, tan2 * cos2, u.y)

    def pdf(self, h):
        return self.eval(h) * dr.maximum(h.z, 0)


class Blinn:
    """Blinn's normalised cosine-power distribution D = (p + 2) / (2 pi) cos^p (Akyuz eq. 11).

    D cos = (p + 2) / (2 pi) cos^(p + 1) is the isotropic case of Ashikhmin-Shirley's
    half-vector density with exponent p + 1, so its sampler and pdf are ``core.warp``'s
    (stable up to p = 1e6 and beyond: p = 2e8 at rho = 1e-4).
    """

    def __init__(self, exponent):
        self.p = exponent

    @classmethod
    def from_roughness(cls, rho):
        """The lecture's "Blinn" D = cos^(2 / rho^2 - 2) / (pi rho^2): p = 2 / rho^2 - 2."""
        return cls(half_vector_exponent(_roughness(rho)))

    def eval(self, h):
        d = (self.p + 2) * dr.inv_two_pi * aniso_phong_cos_power(h, self.p, self.p)
        return dr.select(h.z > 0, d, 0)

    def sample(self, u):
        return square_to_aniso_phong_half_vector(u, self.p + 1, self.p + 1)

    def pdf(self, h):
        return aniso_phong_half_vector_pdf(h, self.p + 1, self.p + 1)


class GGX:
    """GGX / Trowbridge-Reitz distribution (lecture "GGX"; Walter et al. 2007)."""

    def __init__(self, rho):
        self.rho = _roughness(rho)

    def eval(self, h):
        """D = rho^2 / (pi (cos^2 (rho^2 - 1) + 1)^2), the bracket written sin^2 + rho^2 cos^2."""
        a2 = self.rho * self.rho
        cos2, sin2 = _cos2_sin2(h)
        den = sin2 + a2 * cos2  # >= min(1, rho^2) for a unit h
        return dr.select(h.z > 0, a2 / (dr.pi * den * den), 0)

    def sample(self, u):
        """h with density D cos: tan^2 = rho^2 u_1 / (1 - u_1), phi = 2 pi u_2."""
        a2 = self.rho * self.rho
        u1 = dr.minimum(u.x, _ONE_MINUS_EPS)
        den = (1 - u1) + a2 * u1
        return _from_polar((1 - u1) / den, a2 * u1 / den, u.y)

    def pdf(self, h):
        return self.eval(h) * dr.maximum(h.z, 0)

    # -- visible normals --

    def sample_visible(self, wi, u):
        """h with Heitz's density of normals visible from wi (see ``pdf_visible``).

        The spherical-cap construction of Dupuy & Benyoub (2023): in the configuration
        stretched to rho = 1, the visible normals are wi plus a uniform point of the
        spherical cap z >= -wi_z; stretching back gives h. Exact for every incidence,
        with no tangent frame to build (no special case at wi = n).
        """
        a = self.rho
        w = dr.normalize(mi.Vector3f(a * wi.x, a * wi.y, wi.z))
        z = (1 - u.y) * (1 + w.z) - w.z                 # uniform in [-w_z, 1]
        s, c = dr.sincos(dr.two_pi * u.x)
        r = dr.safe_sqrt(1 - z * z)
        m = mi.Vector3f(r * c + w.x, r * s + w.y, z + w.z)
        m = mi.Vector3f(a * m.x, a * m.y, dr.maximum(m.z, 0))
        l2 = dr.squared_norm(m)
        ok = l2 > 0  # m = 0 only in the measure-zero case cap point = -w
        return dr.select(ok, m * dr.rsqrt(dr.select(ok, l2, 1)), mi.Vector3f(0, 0, 1))

    def pdf_visible(self, wi, h, cos_ih=None):
        """D_wi(h) = G1(wi) max(0, wi.h) D(h) / cos(theta_i) (Heitz 2018, eq. 1).

        G1(wi) / cos(theta_i) is taken in its closed form, finite at grazing wi. ``cos_ih``
        is wi.h when the caller has it in a stabler form (``frame.half_vector``).
        """
        if cos_ih is None:
            cos_ih = dr.dot(wi, h)
        return (smith_ggx_g1_over_cos(cos_theta(wi), self.rho)
                * dr.maximum(cos_ih, 0) * self.eval(h))

    def smith_g1(self, w):
        return smith_ggx_g1(cos_theta(w), self.rho)


#: distribution name -> constructor from the roughness rho (cook_torrance's ``distribution``)
DISTRIBUTIONS = {"beckmann": Beckmann, "blinn": Blinn.from_roughness, "ggx": GGX}


# -- shadowing and masking ----------------------------------------------------------------

def vgroove_g(cos_i, cos_o, cos_h, cos_ih):
    """Cook-Torrance's V-groove G = min(1, 2 (n.h)(n.wo) / (wo.h), 2 (n.h)(n.wi) / (wo.h)).

    ``cos_ih`` = wi.h = wo.h (h is the half vector); in [0, 1] for directions above the
    surface, 0 where wi.h = 0.
    """
    g = safe_div(2 * cos_h * dr.minimum(cos_i, cos_o), cos_ih)
    return dr.clip(g, 0, 1)


def smith_ggx_g1_over_cos(cos_t, rho):
    """G1 / cos(theta) = 2 / (cos + sqrt(rho^2 + cos^2 (1 - rho^2))), finite at cos = 0."""
    a2 = _roughness(rho) ** 2
    c = dr.clip(cos_t, 0, 1)
    return 2 / (c + dr.sqrt(a2 + c * c * (1 - a2)))


def smith_ggx_g1(cos_t, rho):
    """The lecture's g_GGX = 2 / (1 + sqrt(1 + rho^2 tan^2)), multiplied through by cos.

    0 at grazing and below the surface, 1 at normal incidence.
    """
    return dr.clip(cos_t, 0, 1) * smith_ggx_g1_over_cos(cos_t, rho)


def smith_ggx_g(cos_i, cos_o, rho):
    """Separable Smith G = G1(wi) G1(wo) (lecture "GGX" geometric term)."""
    return smith_ggx_g1(cos_i, rho) * smith_ggx_g1(cos_o, rho)


#: geometry name -> G(rho, cos_i, cos_o, cos_h, cos_ih) (cook_torrance's ``geometry``)
GEOMETRIES = {
    "cook_torrance": lambda rho, cos_i, cos_o, cos_h, cos_ih: vgroove_g(cos_i, cos_o, cos_h, cos_ih),
    "ggx": lambda rho, cos_i, cos_o, cos_h, cos_ih: smith_ggx_g(cos_i, cos_o, rho),
}


# -- the specular term -------------------------------------------------------------------------

def microfacet_specular(d, fresnel, g, cos_i):
    """D F G / (4 cos_i cos_o) times cos_o, i.e. the specular term as ``eval`` returns it.

    cos_o cancels exactly: writing D F G / (4 cos_i) keeps grazing wo free of 0/0 and
    of overflow. ``cos_i`` is the cosine of the other direction (si.wi).
    """
    return fresnel * safe_div(d * g, 4 * cos_i)
