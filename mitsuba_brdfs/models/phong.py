"""Phong BRDF in its original, modified and normalized forms (``phong``).

References: A. O. Akyuz, "BRDF Summary" (2018), sec. 2-4 (equation numbers below are its);
the lecture "BRDF models" (Politecnico di Milano), "Phong"; B. T. Phong, "Illumination for
Computer Generated Pictures", CACM 18(6), 1975; E. P. Lafortune, Y. D. Willems, "Using the
Modified Phong Reflectance Model for Physically Based Rendering", KU Leuven CW 197, 1994.

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
                                             takes it; p = (2 / alpha^2 - 2) / 4 (see
                                             below). Not with ``exponent``.
                                             (Default: unused)
``form``                   string            ``original`` (eq. 2), ``modified`` (eq. 3) or
                                             ``normalized`` (eq. 5). (Default:
                                             ``normalized``)
=========================  ================  ==============================================

Values outside the ranges above (NaN included) are refused with an error naming the
plugin, the parameter and its range, at load and when ``params.update()`` sets them.

The three colour/float parameters (``alpha`` when given instead of ``exponent``) are exposed
by ``traverse`` and differentiable.

Roughness: ``alpha`` sets p = (2 / alpha^2 - 2) / 4 (``core.roughness``), the lobe whose
highlight is as wide as Mitsuba's ``roughconductor`` with the Beckmann roughness alpha, so a
scene written for it (or ``roughplastic``) switches to this model by its plugin name. The
half-vector mapping 2 / alpha^2 - 2 (Walter et al. 2007, used by ``ashikhmin_shirley`` and
``blinn_phong``) would give a highlight half as wide here: the mirror direction of l turns
twice as fast as the half vector, so the Phong lobe needs a quarter of the exponent
(measured at normal incidence: half widths at half maximum 9.57 deg with this mapping,
9.71 deg for ``roughconductor``, 4.79 deg with 2 / alpha^2 - 2, alpha = 0.1). At oblique
incidence the Phong highlight stays round while the microfacet one stretches in the plane
of incidence. ``anisotropic`` roughness (``alpha_u``/``alpha_v``) is refused: the lobe is
isotropic. alpha = 1 is p = 0, alpha = 0.1 is p = 49.5.

With l the light direction (Mitsuba's ``wo``), v the viewer (``si.wi``), r = 2 (n.l) n - l
the mirror direction of l (the lecture's r_{l,x}) and alpha the angle between r and v:

    original     f = kd / pi + ks cos^p(alpha) / cos(theta_l)             (eq. 2)
    modified     f = kd / pi + ks cos^p(alpha)                            (eq. 3)
    normalized   f = kd / pi + ks (p + 2) / (2 pi) cos^p(alpha)           (eq. 5)

with cos(alpha) clamped at 0 (the lecture's clamp(omega_r . r)), so p = 0 gives a constant
lobe on the hemisphere around r. ``eval`` returns f cos(theta_l); for the original form that
is the lecture's scan-line specular term ks clamp(v . r)^p itself.

Decisions (see ``_phong_family`` for the shared ones):

- The diffuse term is kd / pi in all three forms, although eq. 2 and 3 write kd: those are
  scan-line forms (kd is then the colour under a unit light), and with 1/pi
  ``diffuse_reflectance`` is the diffuse albedo whatever the form.
- Eq. 5 writes cos^n(alpha_r); n is the exponent p. (p + 2) / (2 pi) makes the specular
  albedo exactly ks at normal incidence and less elsewhere (checked numerically), so the
  normalized form conserves energy when kd + ks <= 1.
- The original and modified forms do not conserve energy. Their specular albedo per unit
  ks at normal incidence is 2 pi / (p + 1) (original: 6.28 at p = 0, 0.57 at p = 10, 0.20
  at p = 30) and 2 pi / (p + 2) (modified: 3.14, 0.52, 0.20), falling at grazing
  incidence; kd + ks * that exceeds 1 for broad lobes (e.g. kd = 0.5, ks = 0.5, p = 1:
  about 2.1 original, 1.5 modified).
- The original form is not reciprocal (``RECIPROCAL = False``): under
  ``TransportMode.Importance`` wi is the light side and eval returns
  f(l = wi, v = wo) cos(theta_o). The other two forms are reciprocal (the mirror relation
  is symmetric: r(l) . v = r(v) . l).

Numerics: sin^2(alpha) is |wo x r(wi)|^2 (no cancellation near the mirror direction) and
the power is taken in log space (``core.warp.phong_lobe_cos_power``), so exponents from 0
to 1e6 stay finite and keep their width in float32.

Sampling: the specular lobe draws wo from (p + 1) / (2 pi) cos^p around the mirror direction
of wi (``core.warp.square_to_phong_lobe``); directions below the surface get zero weight.
The diffuse lobe is cosine-weighted. The lobe is chosen in proportion to mean(kd) against
an estimate of the specular albedo: ks times the lobe integral of the form at normal
incidence (2 pi / (p + 1) original, 2 pi / (p + 2) modified, 1 normalized), times the mean
cos(theta_l) over the lobe, ~((p + 1) cos(theta_v) + 1) / (p + 2), for the two forms that
carry cos(theta_l).

Lobes: glossy (index 0) and diffuse (index 1); a constant zero ks or kd leaves its lobe out
of sampling and of the kernel (both components stay declared).

Albedo AOV (``eval_diffuse_reflectance``, the ``aov`` integrator's ``albedo``): kd;
where kd is black (a pure specular surface), ks, clamped to [0, 1].

XML::

    <bsdf type="phong">
        <rgb name="diffuse_reflectance" value="0.5, 0.1, 0.08"/>
        <float name="specular_reflectance" value="0.3"/>
        <float name="exponent" value="60"/>
        <string name="form" value="modified"/>
    </bsdf>

Python: ``mi.load_dict({'type': 'phong', 'exponent': 60.0, 'form': 'original'})``
"""
import drjit as dr

from ..core.facts import RED, Facts, rgb, white
from ..core.frame import mirror
from ..core.registry import bsdf_plugin
from ..core.warp import phong_lobe_cos_power, phong_lobe_pdf, square_to_phong_lobe
from ..core.roughness import beckmann_alpha, mirror_lobe_exponent
from ._phong_family import FORMS, PhongFamily, generic_facts


__all__ = ["Phong"]


@bsdf_plugin("phong")
class Phong(PhongFamily):

    _exponent_from_alpha = staticmethod(mirror_lobe_exponent)

    @staticmethod
    def _normalization(p):
        return (p + 2) * dr.inv_two_pi                                          # eq. 5

    @staticmethod
    def _lobe_integrals(p):
        """Integrals of cos^p(alpha) and of cos^p(alpha) cos(theta_l) at normal incidence."""
        return dr.two_pi / (p + 1), dr.two_pi / (p + 2)

    def _cos_power(self, exponent, wi, wo):
        # alpha between r(l) and v equals the angle between l and r(v)
        return phong_lobe_cos_power(wo, mirror(wi), exponent)

    def _glossy_pdf(self, p, wi, wo):
        return phong_lobe_pdf(wo, mirror(wi), p.exponent)

    def _glossy_sample(self, p, wi, u):
        return square_to_phong_lobe(u, mirror(wi), p.exponent)


#: what the generic tests, the property table, the catalog and the benchmarks run of this
#: model (``core.facts``)
FACTS = Facts(
    colour="diffuse_reflectance",
    differentiable=("diffuse_reflectance", "specular_reflectance", "exponent"),
    non_default={"form": "modified", "diffuse_reflectance": (0.2, 0.5, 0.3)},
    edges=tuple(dict(exponent=0.0, form=f) for f in FORMS) + (dict(exponent=1e6, form="original"),),
    float64=((dict(exponent=30.0), 1e-4),),
    gradient_edges=(dict(exponent=0.0, form="original"), dict(exponent=1e6, form="normalized")),
    zero_lobes=(("diffuse_reflectance", 0, 0.5, {}), ("specular_reflectance", 0, 0.5, {})),
    albedo=(({"diffuse_reflectance": rgb(0.6, 0.2, 0.2), "specular_reflectance": 0.3},
             [0.6, 0.2, 0.2]),
            ({"diffuse_reflectance": 0.0, "specular_reflectance": 0.7, "exponent": 1000.0,
              "form": "original"}, [0.7] * 3)),
    on_request=({"alpha": 0.2},),
    traced_options=({"form": "original"},),
    # the specular lobe alone and white: its own energy, which only the normalized form
    # bounds (the original and modified forms are not meant to conserve energy)
    properties=tuple((f"{form} p={p:g}", {"form": form, "exponent": float(p),
                                          "diffuse_reflectance": 0.0, "specular_reflectance": 1.0})
                     for form in FORMS for p in (1, 10, 1000))
    + (("normalized alpha=0.1", {"alpha": 0.1, "diffuse_reflectance": 0.0,
                                 "specular_reflectance": 1.0}),),
    catalog=tuple((form, {"form": form, "diffuse_reflectance": RED,
                          "specular_reflectance": white(0.3), "exponent": 60.0}) for form in FORMS)
    # roughness instead of the exponent: alpha = 0.1 is p = 49.5
    + (("alpha=0.1", {"diffuse_reflectance": RED, "specular_reflectance": white(0.3),
                      "alpha": 0.1}),),
    cpp=(("", {"exponent": 100.0, "diffuse_reflectance": 0.5, "specular_reflectance": 0.2},
          {"type": "roughplastic", "distribution": "beckmann", "alpha": round(beckmann_alpha(100), 4)},
          "two lobes each, comparable glossy lobe"),
         ("metal", {"exponent": 100.0, "diffuse_reflectance": 0.0, "specular_reflectance": 1.0},
          {"type": "roughconductor", "distribution": "beckmann",
           "alpha": round(beckmann_alpha(100), 4)}, "one glossy lobe each")),
    dropped_lobes=(("kd0_vs_kd_tiny", {"exponent": 100.0, "diffuse_reflectance": 0.0},
                    {"exponent": 100.0, "diffuse_reflectance": 1e-6},
                    "kd = 0 (diffuse dropped) / kd = 1e-6"),
                   ("ks0_vs_ks_tiny", {"exponent": 100.0, "specular_reflectance": 0.0},
                    {"exponent": 100.0, "specular_reflectance": 1e-6},
                    "ks = 0 (specular dropped) / ks = 1e-6")),
    **generic_facts(),
)
