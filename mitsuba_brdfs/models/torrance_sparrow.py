"""Torrance-Sparrow microfacet BRDF (``torrance_sparrow``), as Akyuz summarises it.

References: A. O. Akyuz, "BRDF Summary", 2018, section 8, eq. 10-14 (numbers below);
K. E. Torrance, E. M. Sparrow, "Theory for Off-Specular Reflection from Roughened
Surfaces", JOSA 57(9), 1967; J. F. Blinn, "Models of Light Reflection for Computer
Synthesized Pictures", SIGGRAPH 1977 (the cosine-power distribution); C. Schlick,
"An Inexpensive BRDF Model for Physically-based Rendering", CGF 13(3), 1994.

Parameters
----------
=========================  ================  ==============================================
``diffuse_reflectance``    spectrum/texture  k_d, Lambertian reflectance, in [0, 1].
                                             (Default: 0.5)
``specular_reflectance``   spectrum/texture  k_s, weight of the microfacet term, in
                                             [0, 1]. (Default: 1.0)
``exponent``               float/texture     p, exponent of Blinn's distribution, in
                                             [0, 1e6]: 0 very rough, 1e6 nearly a
                                             mirror. (Default: 30)
``eta``                    float/texture     eta, refractive index of the material
                                             relative to the outside, >= 1; it enters
                                             only through Schlick's R0. (Default: 1.5)
``energy_compensation``    string            as cook_torrance takes it: ``none``
                                             (Akyuz's model), ``kulla_conty`` (a
                                             reciprocal multiple-scattering lobe) or
                                             ``turquin`` (the lobe scaled up, not
                                             reciprocal), by the exponent's tables; see
                                             below. (Default: ``none``)
=========================  ================  ==============================================

Values outside the ranges above (NaN included) are refused with an error naming the
plugin, the parameter and its range, at load and when ``params.update()`` sets them.

All four parameters are exposed by ``traverse`` and differentiable.

The model (eq. 10), w_h the half vector of w_i and w_o, alpha its angle to n:

    f  = k_d / pi + k_s D(alpha) F(beta) G(w_i, w_o) / (4 cos(theta) cos(phi))    (eq. 10)
    D  = (p + 2) / (2 pi) cos(alpha)^p                                            (eq. 11)
    G  = min(1, 2 (n.w_h)(n.w_o) / (w_o.w_h), 2 (n.w_h)(n.w_i) / (w_o.w_h))        (eq. 12)
    F  = R0 + (1 - R0)(1 - cos(beta))^5,  cos(beta) = w_o.w_h                     (eq. 13)
    R0 = (eta - 1)^2 / (eta + 1)^2                                                (eq. 14)

``eval`` returns f cos(theta_o). The model is reciprocal (w_i.w_h = w_o.w_h and eq. 10-12
are symmetric), so Mitsuba's wi/wo may be taken either way round.

Decisions where Akyuz's summary is loose:

- Angles of eq. 10: theta and phi are the polar angles of the two directions (the summary's
  figure, lost in the text), not an azimuth: 4 cos(theta_i) cos(theta_o) is the
  microfacet Jacobian. Checked numerically (tests): with F = 1 and a large p the
  specular albedo is 1 within 1% away from grazing, as a mirror's, and <= 1 everywhere.
- The diffuse term is k_d / pi, as eq. 10 writes it (and the package's convention), and is
  not weighted by 1 - F: with k_d + k_s > 1 the model can reflect more than it receives,
  as the summary's does.
- Normalisation: eq. 11 normalises a microfacet distribution (D cos(alpha) integrates to
  1 over the hemisphere of w_h), not the Blinn-Phong BRDF (that is eq. 9's
  (p + 8) / (8 pi)); it is used as written.
- One-sided: eq. 10 asks theta_i < 90 degrees; as every plugin of the package, both directions must
  be above the surface, else f = 0.
- eta >= 1. Eq. 14 is symmetric in eta and 1 / eta, so every R0 in [0, 1) is reached
  from [1, inf): rejecting eta < 1 loses nothing and catches an R0 passed as eta
  (eta = 0.04 would silently mean R0 = 0.85). eta = 1 gives R0 = 0 (F is then
  (1 - cos(beta))^5 alone: the lobe stays, it grows to 1 at grazing angles).
- F is Schlick's (eq. 13), the summary names no full Fresnel; it may be a colour only
  through k_s (eta is a float).
- Everything but the parameters is ``cook_torrance``'s machinery (``core.microfacet``):
  this is ``cook_torrance`` with the ``blinn`` distribution given by its exponent, the
  V-groove geometry, F0 = R0 and lobe weights k_d, k_s instead of k m_D, (1 - k) m_S
  (tested: equal to ``cook_torrance`` with k = 1/2, m_D = 2 k_d, m_S = 2 k_s,
  rho = sqrt(2 / (p + 2))).

Sampling: w_h is drawn from D(w_h) cos(alpha) (the cos^(p+1) half-vector lobe of
``core.warp``, stable from p = 0 to p = 1e6 and beyond), w_o is w_i reflected about w_h
(density divided by 4 w_o.w_h; zero weight below the horizon); the diffuse lobe is
cosine-weighted. Lobes are chosen in proportion to mean(k_s F(cos theta_i)) and mean(k_d),
and the pdf is their mixture.

Lobes: glossy (index 0) and diffuse (index 1); a constant zero k_s or k_d leaves its lobe
out of sampling and of the kernel (both components stay declared). D and F are never zero everywhere, whatever p and eta.

Energy compensation (an extension, not in Akyuz's summary), as ``cook_torrance``'s: with
F = 1 the specular lobe reflects E(mu) < 1 (0.60 at normal incidence for p = 2), and
``kulla_conty`` adds k_s F_ms (1 - E(mu_i)) (1 - E(mu_o)) / (pi (1 - E_avg)) (F_avg =
R0 + (1 - R0) / 21), ``turquin`` scales the specular term by 1 + R0 (1 - E(mu_v)) / E(mu_v)
(not reciprocal). E comes from a table measured with this plugin's own ``sample()``
(R0 = 1), indexed by r = sqrt(2 / (p + 2)) (so p from 0 to 1e6 spans r in [0.0014, 1]);
with ``none`` nothing of it is traced.

Energy compensation (an extension, not in Akyuz's summary), as ``cook_torrance``'s
(``core.energy``): with F = 1 the specular lobe reflects E(mu) < 1 of the light (0.60 at
normal incidence for p = 2); ``kulla_conty`` adds Kulla & Conty's lobe
k_s F_ms (1 - E(mu_i)) (1 - E(mu_o)) / (pi (1 - E_avg)), F_ms = F_avg^2 E_avg /
(1 - F_avg (1 - E_avg)), F_avg = R0 + (1 - R0) / 21, sampled cosine-weighted as a lobe of
its own; ``turquin`` scales the specular term by 1 + R0 (1 - E(mu_v)) / E(mu_v), mu_v the
viewer's cosine (not reciprocal). E comes from a table measured with this plugin's own
``sample()`` (R0 = 1), indexed by r = sqrt(2 / (p + 2)) (p from 0 to 1e6 spans r in
[0.0014, 1]) and interpolated bilinearly; derivatives with respect to p flow through it.
A white lobe then reflects all the light (within 0.4% up to 80 degrees for p >= 2, by
quadrature; tested to 1%); with ``none`` nothing of it is traced.

Albedo AOV (``eval_diffuse_reflectance``, the ``aov`` integrator's ``albedo``): k_d;
where k_d is black (a metal), k_s R0, the specular colour at normal incidence (eq. 13
at beta = 0). Never above 1.

XML::

    <bsdf type="torrance_sparrow">
        <rgb name="diffuse_reflectance" value="0.4, 0.1, 0.1"/>
        <float name="exponent" value="200"/>
        <float name="eta" value="1.6"/>
    </bsdf>

Python: ``mi.load_dict({'type': 'torrance_sparrow', 'exponent': 200.0})``
"""
from ..core.energy import COMPENSATIONS, roughness_of_exponent
from ..core.facts import RED, Facts, rgb, white
from ..core.microfacet import GEOMETRIES, Blinn
from ..core.registry import bsdf_plugin
from ..core.roughness import beckmann_alpha
from ..core.warp import MAX_EXPONENT
from ._microfacet_family import MicrofacetModel, MicrofacetPoint

__all__ = ["TorranceSparrow", "schlick_r0"]


def schlick_r0(eta):
    """R0 = (eta - 1)^2 / (eta + 1)^2 (eq. 14), finite for every eta >= 0."""
    r = (eta - 1) / (eta + 1)
    return r * r


@bsdf_plugin("torrance_sparrow")
class TorranceSparrow(MicrofacetModel):
    OPTIONS = {"energy_compensation": COMPENSATIONS}

    def _read_parameters(self, r):
        self.kd = r.reflectance("diffuse_reflectance", 0.5)
        self.ks = r.reflectance("specular_reflectance", 1.0)
        self.exponent = r.scalar("exponent", 30.0, hi=MAX_EXPONENT, what="a Blinn exponent")
        self.eta = r.scalar("eta", 1.5, 1.0, what="a refractive index")
        self._geometry = GEOMETRIES["cook_torrance"]  # eq. 12, the V-groove G
        self._visible = False  # D cos(alpha) sampling (eq. 11)
        self._read_compensation(r, "torrance_sparrow")

    def _textures(self):
        return {"diffuse_reflectance": self.kd, "specular_reflectance": self.ks,
                "exponent": self.exponent, "eta": self.eta}

    def _options(self):
        return {"energy_compensation": self.energy_compensation}

    def _table_roughness(self, p):
        return roughness_of_exponent(p.dist.p)

    def _table_texture(self):
        return self.exponent, lambda p: (2 / (p + 2)) ** 0.5

    def _lobes_present(self):
        # D, F > 0 somewhere for every p and eta: only the weights drop a lobe
        return not self._is_constant(self.ks, 0.0), not self._is_constant(self.kd, 0.0)

    def _at(self, si, active):
        return MicrofacetPoint(kd=self.kd.eval(si, active), ks=self.ks.eval(si, active),
                               f0=schlick_r0(self.eta.eval_1(si, active)), rho=None,
                               dist=Blinn(self.exponent.eval_1(si, active)))


#: what the generic tests, the property table, the catalog and the benchmarks run of this
#: model (``core.facts``)
FACTS = Facts(
    colour="diffuse_reflectance",
    differentiable=("diffuse_reflectance", "specular_reflectance", "exponent", "eta"),
    non_default={"eta": 1.8, "exponent": 50.0},
    edges=(dict(exponent=0.0, eta=1.0), dict(exponent=1e6, eta=1e30),
           dict(exponent=0.0, eta=1.0, energy_compensation="kulla_conty"),
           dict(exponent=1e6, eta=1e30, energy_compensation="turquin")),
    float64=((dict(exponent=30.0), 1e-4), (dict(exponent=3000.0), 1e-3),
             (dict(exponent=4.0, eta=3.0, energy_compensation="kulla_conty"), 1e-4),
             (dict(exponent=4.0, energy_compensation="turquin"), 1e-4)),
    gradient_edges=(dict(exponent=0.0), dict(exponent=1e6),
                    dict(exponent=0.0, energy_compensation="kulla_conty"),
                    dict(exponent=1e6, energy_compensation="turquin")),
    traced_options=({"energy_compensation": "kulla_conty", "exponent": 5.0},),
    zero_lobes=(("diffuse_reflectance", 0, 0.5, {}), ("specular_reflectance", 0, 0.5, {})),
    albedo=(({"diffuse_reflectance": rgb(0.3, 0.3, 0.6)}, [0.3, 0.3, 0.6]),
            ({"diffuse_reflectance": 0.0, "specular_reflectance": 1.0, "eta": 1.5,
              "exponent": 1000.0}, [0.04] * 3)),
    properties=(
        ("p=30", {"exponent": 30.0, "diffuse_reflectance": 0.0}),
        ("p=1000", {"exponent": 1000.0, "diffuse_reflectance": 0.0}),
        # Akyuz's eq. 10 adds its diffuse term without a (1 - F) weight
        ("p=30 kd=0.9", {"exponent": 30.0, "diffuse_reflectance": 0.9}),
        # F = 1 (R0 = 1): the light single scattering loses, and given back
        ("p=2 F=1", {"exponent": 2.0, "diffuse_reflectance": 0.0, "eta": 1e30}),
        ("p=2 F=1 kulla_conty", {"exponent": 2.0, "diffuse_reflectance": 0.0, "eta": 1e30,
                                 "energy_compensation": "kulla_conty"}),
    ),
    catalog=(("p=60", {"diffuse_reflectance": RED, "specular_reflectance": white(1.0),
                       "exponent": 60.0}),),
    cpp=(("", {"exponent": 30.0, "eta": 1.5, "diffuse_reflectance": 0.5,
               "specular_reflectance": 1.0},
          {"type": "roughplastic", "distribution": "beckmann",
           "alpha": round(beckmann_alpha(30), 4), "int_ior": 1.5},
          "two lobes each, dielectric Fresnel in both"),),
    dropped_lobes=(("kd0_vs_kd_tiny", {"diffuse_reflectance": 0.0}, {"diffuse_reflectance": 1e-6},
                    "diffuse = 0 (dropped) / 1e-6"),),
    cases=tuple((dict(diffuse_reflectance=kd, specular_reflectance=ks, exponent=p, eta=eta), 5e-4)
                for kd, ks, p, eta in [
                    (0.5, 1.0, 30.0, 1.5), (rgb(0.7, 0.2, 0.1), rgb(0.9, 0.6, 0.3), 300.0, 2.4),
                    (0.0, rgb(1.0, 0.8, 0.6), 3.0, 1e30), (rgb(0.3, 0.6, 0.9), 0.5, 0.0, 1.0),
                    (0.2, 0.8, 1.0, 1.33)])
    + ((dict(exponent=4.0, eta=3.0, energy_compensation="kulla_conty"), 5e-4),
       (dict(diffuse_reflectance=0.0, exponent=4.0, eta=1e30, energy_compensation="turquin"),
        5e-4)),
    # Turquin's scaling is not reciprocal (documented)
    not_reciprocal=({"energy_compensation": "turquin"},),
    chi2=(("default_normal", {}, 0, 16), ("default_30", {}, 30, 16),
          ("metal_p200_60", dict(diffuse_reflectance=0.0, exponent=200.0, eta=1e30), 60, 32),
          ("mixed_p10_grazing_85", dict(exponent=10.0, eta=2.0), 85, 16),
          ("metal_p50_grazing_89", dict(diffuse_reflectance=0.0, exponent=50.0), 89, 32),
          ("metal_p0", dict(diffuse_reflectance=0.0, exponent=0.0, eta=1.0), 45, 8),
          ("mixed_p1000", dict(diffuse_reflectance=0.3, exponent=1000.0, eta=3.0), 40, 64),
          ("diffuse_only", dict(specular_reflectance=0.0), 40, 8),
          ("diffuse_component", dict(component=1, exponent=100.0), 70, 8),
          ("glossy_component", dict(component=0, exponent=20.0), 20, 16),
          ("kulla_conty", dict(diffuse_reflectance=0.0, exponent=3.0, eta=1e30,
                               energy_compensation="kulla_conty"), 45, 16),
          ("turquin", dict(exponent=3.0, energy_compensation="turquin"), 30, 16)),
    stability={"exponent": (0.0, 1.0, 1e6), "eta": (1.0, 1.5, 1e30),
               "diffuse_reflectance": (0.0, 0.5),
               "energy_compensation": ("none", "kulla_conty", "turquin")},
    renders=(("default", {}),
             ("metal_colour", dict(diffuse_reflectance=0.0, exponent=200.0, eta=1e30,
                                   specular_reflectance=rgb(0.9, 0.6, 0.3))),
             ("mirror_like", dict(diffuse_reflectance=0.0, exponent=1e6, eta=1e30)),
             ("rough", dict(exponent=0.0, eta=1.0)),
             ("matte", dict(specular_reflectance=0.0)),
             ("kulla_conty", dict(diffuse_reflectance=0.0, exponent=3.0, eta=1e30,
                                  energy_compensation="kulla_conty")),
             ("turquin", dict(diffuse_reflectance=0.0, exponent=3.0,
                              energy_compensation="turquin"))),
)
