"""Roughness instead of exponents: Beckmann-equivalent cosine-power lobes.

A cos^p lobe of the half vector matches the Beckmann distribution
exp(-tan^2 / alpha^2) / (pi alpha^2 cos^4) when p = 2 / alpha^2 - 2 (Walter et al. 2007,
sec. 5.2): near the peak both fall like exp(-theta^2 / alpha^2) to leading order in
1 / alpha^2 (cos^p ~ exp(-p theta^2 / 2), tan^2 ~ theta^2), and with the -2 the normalised
distributions (p + 2) / (2 pi) cos^p and Beckmann's have the same peak value 1 / (pi alpha^2).
Models parameterised by Phong exponents
(``ashikhmin_shirley``, ``blinn_phong``, ``phong``) accept ``alpha`` (or ``alpha_u`` /
``alpha_v``) instead, as Mitsuba's ``roughconductor`` and ``roughplastic`` take them, so a scene
switches between those plugins by its plugin name.

A lobe around the mirror direction (``phong``) moves twice as fast as the half vector: the
mirror direction of l turns by 2 theta when h turns by theta. Its exponent for the same
highlight is a quarter of the half-vector one, p = (2 / alpha^2 - 2) / 4
(``mirror_lobe_exponent``).

The match is of leading order: at normal incidence the half width at half maximum of the
highlight is that of ``roughconductor`` (Beckmann) within 0.5% for alpha <= 0.05 and 1.5%
at alpha = 0.1, and 5-6% narrower at alpha = 0.2, 11-15% at alpha = 0.3, for all three
models alike (measured in ``tests/test_phong.py`` and ``tests/test_ashikhmin_shirley.py``).

References: B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for
Refraction through Rough Surfaces", EGSR 2007.
"""
from .params import float32

__all__ = ["ALPHA_MIN", "ALPHA_MAX", "half_vector_exponent", "beckmann_alpha",
           "mirror_lobe_exponent", "roughness_relations", "read_roughness"]

#: range of the roughness; the lower end as float32 rounds it, since textures hold float32.
#: alpha = 1.5e-3 is a half-vector exponent of 8.9e5, inside the exponents' range
#: [0, MAX_EXPONENT] (a lobe ~1.5e-3 rad wide); alpha = 1 a constant lobe
ALPHA_MIN, ALPHA_MAX = min(1.5e-3, float32(1.5e-3)), 1.0


def half_vector_exponent(alpha):
    """p = 2 / alpha^2 - 2: the cos^p(theta_h) lobe of Beckmann roughness alpha."""
    return 2 / (alpha * alpha) - 2


def beckmann_alpha(p):
    """alpha = sqrt(2 / (p + 2)): the Beckmann roughness of the cos^p(theta_h) lobe (the
    inverse of ``half_vector_exponent``)."""
    return (2.0 / (p + 2.0)) ** 0.5


def mirror_lobe_exponent(alpha):
    """p = (2 / alpha^2 - 2) / 4: the cos^p lobe around the mirror direction whose highlight
    is as wide as that of Beckmann roughness alpha."""
    return 0.5 / (alpha * alpha) - 0.5


def roughness_relations(exponents, anisotropic):
    """The relations (``core.relations``) of the roughness parameters of a model that
    otherwise takes the Phong exponents named in ``exponents``: exponents or a roughness,
    ``alpha`` or ``alpha_u``/``alpha_v`` (``anisotropic`` models; the others refuse those)
    and the pair together."""
    from .relations import Absent, Excludes, Together
    pair = ("alpha_u", "alpha_v")
    if not anisotropic:
        return (Absent(pair, "the lobe is isotropic, its roughness is 'alpha'"),
                Excludes(("alpha",), exponents, "Phong exponents or a roughness, not both"))
    return (Excludes(("alpha",) + pair, exponents, "Phong exponents or a roughness, not both"),
            Excludes(pair, ("alpha",), "'alpha' sets alpha_u = alpha_v"),
            Together(*pair, why=f"a roughness in [{ALPHA_MIN:g}, {ALPHA_MAX:g}]"))


def read_roughness(r):
    """Read the roughness parameters of a model that otherwise takes Phong exponents
    (their relations, ``roughness_relations``, are checked before).

    Returns None when no roughness parameter is given (the model reads its exponents),
    else the roughness textures (alpha_u, alpha_v): ``alpha`` gives the same texture twice.
    """
    what = "a roughness"
    if "alpha" in r.props:
        alpha = r.scalar("alpha", 0.1, ALPHA_MIN, ALPHA_MAX, what=what)
        return alpha, alpha
    if "alpha_u" not in r.props:
        return None
    return (r.scalar("alpha_u", 0.1, ALPHA_MIN, ALPHA_MAX, what=what),
            r.scalar("alpha_v", 0.1, ALPHA_MIN, ALPHA_MAX, what=what))
