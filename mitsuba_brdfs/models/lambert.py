"""Lambertian diffuse reflection (``lambert``).

Reference: the lecture "BRDF models" (Politecnico di Milano), section Lambert.

Parameters
----------
================  ================  ====================================================
``reflectance``   spectrum/texture  rho, the diffuse colour m_D, in [0, 1].
                                    Exposed, differentiable. (Default: 0.5)
================  ================  ====================================================

Values outside the ranges above (NaN included) are refused with an error naming the
plugin, the parameter and its range, at load and when ``params.update()`` sets them.

Light is reflected with the same radiance in every direction above the surface:

    f(light, viewer) = rho / pi

and ``eval`` returns f cos(theta_light) = rho / pi max(n.d, 0).

Correction of the lecture: it writes the constant BRDF as f = m_D (and, for scan-line
rendering, f = m_D max(d.n, 0), the cosine folded in). Without the 1/pi a white surface
would reflect pi times the light it receives. The package fixes the normalisation to
rho / pi, so a white Lambert surface reflects all the light (albedo 1 at every incidence),
and the lecture's m_D is our ``reflectance``; a pixel lit head-on by a white light of unit
irradiance shows m_D / pi of radiance instead of m_D.

Sampling: cosine-weighted directions (pdf cos(theta) / pi); the weight eval / pdf is rho,
exactly. The model is reciprocal. It is the same BRDF as Mitsuba's ``diffuse`` plugin
(tests compare the two value for value and render for render).

Lobes: one diffuse reflection component (index 0). A constant black reflectance does no
work (nothing sampled, nothing traced into the kernel); a reflectance set later through
``mi.traverse``, or differentiated, brings it back.

Albedo AOV (``eval_diffuse_reflectance``, the ``aov`` integrator's ``albedo``): rho, as
Mitsuba's ``diffuse`` returns its ``reflectance``.

XML::

    <bsdf type="lambert">
        <rgb name="reflectance" value="0.8, 0.2, 0.1"/>
    </bsdf>

Python: ``mi.load_dict({'type': 'lambert', 'reflectance': {'type': 'rgb', 'value': [0.8, 0.2, 0.1]}})``
"""

from ..core.lobes import Point, TwoLobeModel, lambert_f
from ..core.facts import RED, Facts, rgb
from ..core.registry import bsdf_plugin

__all__ = ["Lambert", "lambert_f"]


class _At(Point):
    """Parameter values at one shading point."""
    __slots__ = ("rho",)


@bsdf_plugin("lambert")
class Lambert(TwoLobeModel):
    LOBES = (False, True)

    def _read_parameters(self, r):
        self.rho = r.reflectance("reflectance", 0.5)

    def _textures(self):
        return {"reflectance": self.rho}

    def _lobes_present(self):
        return False, not self._is_constant(self.rho, 0.0)

    def _at(self, si, active):
        return _At(rho=self.rho.eval(si, active))

    def _diffuse_f(self, p, wi, wo):
        return lambert_f(p.rho, wo)

    # -- albedo AOV --------------------------------------------------------------------------

    def _diffuse_colour(self, p):
        return p.rho


#: what the generic tests, the property table, the catalog and the benchmarks run of this
#: model (``core.facts``)
FACTS = Facts(
    colour="reflectance",
    differentiable=("reflectance",),
    non_default={"reflectance": (0.8, 0.3, 0.1)},
    edges=(dict(reflectance=1.0),),
    float64=(({}, 1e-4),),
    zero_lobes=(("reflectance", 0, 0.5, {}),),
    albedo=(({"reflectance": rgb(0.8, 0.3, 0.1)}, [0.8, 0.3, 0.1]),),
    properties=(("", {"reflectance": 1.0}),),
    catalog=(("", {"reflectance": RED}),),
    cpp=(("", {"reflectance": 0.5}, {"type": "diffuse", "reflectance": 0.5}, "the same model"),),
    cases=((dict(reflectance=rgb(0.3, 0.6, 0.9)), 1e-5), (dict(reflectance=1.0), 1e-5)),
    chi2=(("normal", {}, 0, 8), ("45", {}, 45, 8), ("80", {}, 80, 8), ("89.5", {}, 89.5, 8)),
    stability={"reflectance": (0.0, 1.0)},
    renders=(("white", dict(reflectance=0.8)),),
)
