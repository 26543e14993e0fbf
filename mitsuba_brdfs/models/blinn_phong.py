"""Blinn-Phong BRDF in its original, modified and normalized forms (``blinn_phong``).

References: A. O. Akyuz, "BRDF Summary" (2018), sec. 5-7 (equation numbers below are its);
the lecture "BRDF models" (Politecnico di Milano), "Blinn"; J. F. Blinn, "Models of Light
Reflection for Computer Synthesized Pictures", SIGGRAPH 1977; F. Giesen, "On the
Normalization of Phong/Blinn-Phong" (2009), for the exact normalisation below.

Parameters
----------
=========================  ================  ==============================================
``diffuse_reflectance``    spectrum/texture  kd, diffuse albedo in [0, 1] (the diffuse term
                                             is kd / pi in every form). (Default: 0.5)
``specular_reflectance``   spectrum/texture  ks, weight of the specular lobe, in [0, 1].
                                             (Default: 0.2)
``exponent``               float/texture     p, the Phong exponent, in [0, 1e6]; larger
                                             is sharper. (Default: 30)
``alpha``                  float/texture     instead of ``exponent``: a Beckmann roughness
                                             in [1.5e-3, 1], as Mitsuba's ``roughconductor``
                                             takes it; p = 2 / alpha^2 - 2 (see below).
                                             Not with ``exponent``. (Default: unused)
``form``                   string            ``original`` (eq. 7), ``modified`` (eq. 8) or
                                             ``normalized`` (eq. 9). (Default:
                                             ``normalized``)
``normalization``          string            N(p) of the normalized form: ``exact`` (the
                                             factor below) or ``approximate`` (eq. 9's
                                             (p + 8) / (8 pi), up to 7.5% too large);
                                             only with ``form = normalized``.
                                             (Default: ``exact``)
=========================  ================  ==============================================

Values outside the ranges above (NaN included) are refused with an error naming the
plugin, the parameter and its range, at load and when ``params.update()`` sets them.

The three colour/float parameters (``alpha`` when given instead of ``exponent``) are exposed
by ``traverse`` and differentiable.

Roughness: ``alpha`` sets p = 2 / alpha^2 - 2 (``core.roughness``; Walter et al. 2007): the
half-vector lobe cos^p(alpha_h) then has the width and peak of the Beckmann distribution of
that roughness, so a scene written for Mitsuba's ``roughconductor`` or ``roughplastic``
switches to this model by its plugin name (alpha = 1 is p = 0, alpha = 0.1 is p = 198).

With l the light direction (Mitsuba's ``wo``), v the viewer (``si.wi``), h = (l + v) / |l + v|
the half vector (eq. 6) and alpha_h the angle between h and the normal n:

    original     f = kd / pi + ks cos^p(alpha_h) / cos(theta_l)           (eq. 7)
    modified     f = kd / pi + ks cos^p(alpha_h)                          (eq. 8)
    normalized   f = kd / pi + ks N(p) cos^p(alpha_h)                     (eq. 9)
    N(p)         = (p + 2)(p + 4) / (8 pi (p + 2^(-p/2)))        (normalization = exact)
    N(p)         = (p + 8) / (8 pi)                              (normalization = approximate)

``eval`` returns f cos(theta_l); for the original form that is the lecture's scan-line term
ks clamp(n . h)^p itself.

Decisions (see ``_phong_family`` for the shared ones):

- Eq. 9 writes cos^n(alpha_r), the Phong angle: the Blinn-Phong lobe is cos^p(alpha_h)
  (as the text's own derivation says), as in eq. 7 and 8.
- Eq. 9's factor (p + 8) / (8 pi) does not make the form energy conserving, although the
  text derives it from the conservation condition (eq. 4): it is an approximation, and
  with it the specular albedo at normal incidence (where it is largest) is above ks by up to
  7.5% (1.024 at p = 1, 1.075 at p = 10, 1.048 at p = 30, 1.018 at p = 100; checked
  numerically). Following the stated property, N(p) is the exact value of eq. 4
  at normal incidence: 1 / integral of cos^p(alpha_h) cos(theta_l) dl with v = n, computed
  in closed form. It equals (p + 8) / (8 pi) at p = 0 and differs from it by less than 8%
  everywhere; with it the specular albedo is exactly ks at normal incidence and less
  elsewhere, so the normalized form conserves energy when kd + ks <= 1. N(p) is written as
  (p + 2) / (8 pi) * (p + 4) / (p + 2^(-p/2)), which does not overflow for huge p.
  ``normalization = approximate`` gives the text's factor for users reproducing it, with
  the albedo excess above; it is the ratio of the two factors, at most 1.075 (near p = 9)
  and tending to 1 for p -> 0 and p -> infinity.
- The original and modified forms do not conserve energy. Their specular albedo per unit ks
  at normal incidence is 8 pi (1 - 2^(-(p+2)/2)) / (p + 2) (original: 6.28 at p = 0, 2.06
  at p = 10, 0.79 at p = 30) and 8 pi (p + 2^(-p/2)) / ((p + 2)(p + 4)) (modified: 3.14,
  1.50, 0.69), falling at grazing incidence; kd + ks * that exceeds 1 for broad lobes
  (e.g. kd = 0.5, ks = 0.5, p = 1: about 3.2 original, 1.9 modified).
- The original form is not reciprocal (``RECIPROCAL = False``, wi and wo swap roles under
  ``TransportMode.Importance``); the modified and normalized forms are (h is symmetric).

Numerics: cos^p(alpha_h) comes from ``core.warp.aniso_phong_cos_power`` with nu = nv = p
(sin^2 from the tangential components of h, the power in log space), so exponents from 0 to
1e6 stay finite and keep their width in float32.

Sampling: the specular lobe draws h from the half-vector density (p + 1) / (2 pi)
cos^p(alpha_h) (``core.warp.square_to_aniso_phong_half_vector`` with nu = nv = p, i.e.
Ashikhmin-Shirley's sampler), reflects wi about h and has the density p_h / (4 wi.h);
directions below the surface get zero weight. The diffuse lobe is cosine-weighted. The lobe
is chosen in proportion to mean(kd) against ks times the form's specular albedo at normal
incidence (above), times ~((p + 1) cos(theta_v) + 1) / (p + 2) for the forms that carry
cos(theta_l) (see ``_phong_family``).

Lobes: glossy (index 0) and diffuse (index 1); a constant zero ks or kd leaves its lobe out
of sampling and of the kernel (both components stay declared).

Albedo AOV (``eval_diffuse_reflectance``, the ``aov`` integrator's ``albedo``): kd;
where kd is black (a pure specular surface), ks, clamped to [0, 1].

XML::

    <bsdf type="blinn_phong">
        <rgb name="diffuse_reflectance" value="0.5, 0.1, 0.08"/>
        <float name="specular_reflectance" value="0.3"/>
        <float name="exponent" value="60"/>
        <string name="form" value="modified"/>
    </bsdf>

Python::

    bsdf = mi.load_dict({'type': 'blinn_phong', 'exponent': 60.0, 'form': 'original'})
    akyuz = mi.load_dict({'type': 'blinn_phong', 'normalization': 'approximate'})
"""
import drjit as dr

from ..core.facts import RED, Facts, rgb, white
from ..core.frame import half_vector, reflect
from ..core.registry import bsdf_plugin
from ..core.relations import Only
from ..core.warp import (aniso_phong_cos_power, aniso_phong_half_vector_pdf,
                         reflection_jacobian, square_to_aniso_phong_half_vector)
from ..core.roughness import beckmann_alpha, half_vector_exponent
from ._phong_family import FORMS, PhongFamily, generic_facts


__all__ = ["BlinnPhong", "NORMALIZATIONS"]


def normalization_exact(p):
    """1 / integral of cos^p(alpha_h) cos(theta_l) over l at normal incidence (eq. 4)."""
    return (p + 2) * (1 / (8 * dr.pi)) * ((p + 4) / (p + dr.exp2(-0.5 * p)))


def normalization_approximate(p):
    """Akyuz eq. 9's (p + 8) / (8 pi)."""
    return (p + 8) * (1 / (8 * dr.pi))


NORMALIZATIONS = {"exact": normalization_exact, "approximate": normalization_approximate}


@bsdf_plugin("blinn_phong")
class BlinnPhong(PhongFamily):

    OPTIONS = {"form": FORMS, "normalization": tuple(NORMALIZATIONS)}
    RELATIONS = PhongFamily.RELATIONS + (
        Only(("normalization",), "form", "normalized", default="normalized",
             why="the other forms have no normalisation factor"),)
    _normalization = staticmethod(normalization_exact)
    _exponent_from_alpha = staticmethod(half_vector_exponent)

    def _read_model_options(self, r):
        self.normalization = r.enum("normalization", "exact", self.OPTIONS["normalization"])
        # load-time choice: the kernel traces only this factor
        self._normalization = NORMALIZATIONS[self.normalization]

    def _options(self):
        opts = {"form": self.form}
        if self.form == "normalized":
            opts["normalization"] = self.normalization
        return opts

    @staticmethod
    def _lobe_integrals(p):
        """Integrals of cos^p(alpha_h) and of cos^p(alpha_h) cos(theta_l) at normal incidence.

        With v = n, theta_l = 2 alpha_h and dl = 4 cos(alpha_h) dh, over alpha_h < pi/4.
        """
        return (8 * dr.pi * (1 - dr.exp2(-0.5 * p - 1)) / (p + 2),
                8 * dr.pi * (p + dr.exp2(-0.5 * p)) / ((p + 2) * (p + 4)))

    def _cos_power(self, exponent, wi, wo):
        h, _ = half_vector(wi, wo)
        return aniso_phong_cos_power(h, exponent, exponent)

    def _glossy_pdf(self, p, wi, wo):
        h, cos_ih = half_vector(wi, wo)
        return aniso_phong_half_vector_pdf(h, p.exponent, p.exponent) * reflection_jacobian(cos_ih)

    def _glossy_sample(self, p, wi, u):
        return reflect(wi, square_to_aniso_phong_half_vector(u, p.exponent, p.exponent))


#: what the generic tests, the property table, the catalog and the benchmarks run of this
#: model (``core.facts``)
FACTS = Facts(
    colour="diffuse_reflectance",
    differentiable=("diffuse_reflectance", "specular_reflectance", "exponent"),
    non_default={"exponent": 60.0, "form": "modified"},
    edges=(dict(exponent=0.0, form="original"), dict(exponent=1e6, form="normalized"),
           dict(alpha=1.5e-3, normalization="approximate")),
    float64=((dict(exponent=30.0), 1e-4),),
    gradient_edges=(dict(exponent=0.0, form="modified"), dict(exponent=1e6, form="normalized")),
    zero_lobes=(("diffuse_reflectance", 0, 0.5, {}), ("specular_reflectance", 0, 0.5, {})),
    albedo=(({"diffuse_reflectance": rgb(0.1, 0.6, 0.3)}, [0.1, 0.6, 0.3]),
            ({"diffuse_reflectance": 0.0, "specular_reflectance": 1.0, "exponent": 1e4},
             [1.0] * 3)),
    on_request=({"alpha": 0.2},),
    traced_options=({"form": "modified"},),
    # the specular lobe alone and white (as phong's), and Akyuz's approximate factor
    # (p + 8) / (8 pi): largest excess near p = 10
    properties=tuple((f"{form} p={p:g}", {"form": form, "exponent": float(p),
                                          "diffuse_reflectance": 0.0, "specular_reflectance": 1.0})
                     for form in FORMS for p in (1, 10, 1000))
    + (("normalized approximate p=10", {"form": "normalized", "normalization": "approximate",
                                        "exponent": 10.0, "diffuse_reflectance": 0.0,
                                        "specular_reflectance": 1.0}),
       ("normalized alpha=0.1", {"alpha": 0.1, "diffuse_reflectance": 0.0,
                                 "specular_reflectance": 1.0})),
    catalog=tuple((form, {"form": form, "diffuse_reflectance": RED,
                          "specular_reflectance": white(0.3), "exponent": 60.0}) for form in FORMS)
    + (("normalized approximate", {"form": "normalized", "normalization": "approximate",
                                   "diffuse_reflectance": RED, "specular_reflectance": white(0.3),
                                   "exponent": 60.0}),
       # roughness instead of the exponent: alpha = 0.1 is p = 198
       ("alpha=0.1", {"diffuse_reflectance": RED, "specular_reflectance": white(0.3),
                      "alpha": 0.1})),
    cpp=(("", {"exponent": 100.0, "diffuse_reflectance": 0.5, "specular_reflectance": 0.2},
          {"type": "roughplastic", "distribution": "beckmann", "alpha": round(beckmann_alpha(100), 4)},
          "two lobes each, comparable glossy lobe"),),
    dropped_lobes=(("kd0_vs_kd_tiny", {"exponent": 100.0, "diffuse_reflectance": 0.0},
                    {"exponent": 100.0, "diffuse_reflectance": 1e-6},
                    "kd = 0 (diffuse dropped) / kd = 1e-6"),),
    **generic_facts(),
)
