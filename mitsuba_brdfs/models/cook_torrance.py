"""Cook-Torrance microfacet BRDF (``cook_torrance``), as the lecture writes it.

References: the lecture "BRDF models" (Politecnico di Milano), section "Cook-Torrance";
R. L. Cook, K. E. Torrance, "A Reflectance Model for Computer Graphics", ACM TOG 1(1), 1982;
B. Walter et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007 (GGX).

Parameters
----------
=========================  ================  ==============================================
``diffuse_reflectance``    spectrum/texture  m_D, colour of the Lambertian part, in [0, 1].
                                             (Default: 0.5)
``specular_reflectance``   spectrum/texture  m_S, colour of the specular part, in [0, 1].
                                             (Default: 1.0)
``k``                      float/texture     share of the diffuse part, in [0, 1]; the
                                             specular part gets 1 - k. (Default: 0.5)
``roughness``              float/texture     rho in [0, 1]: 0 smooth, 1 very rough.
                                             Values below 1e-4 act as 1e-4. (Default: 0.3)
``f0``                     spectrum/texture  F0, Fresnel reflectance at normal incidence,
                                             in [0, 1]. (Default: 0.04)
``specular_scale``         float/texture     extension (not in the lecture): a factor >= 0
                                             on the specular part, for fits whose lobe
                                             outweighs what (1 - k) m_S <= 1 allows
                                             (the ``ngan2005`` presets, see below).
                                             (Default: 1)
``distribution``           string            D: ``beckmann``, ``blinn`` or ``ggx``.
                                             (Default: ``beckmann``)
``geometry``               string            G: ``cook_torrance`` (the V-groove
                                             "microfacet" term) or ``ggx`` (Smith).
                                             (Default: ``cook_torrance``)
``sample_visible``         boolean           with ``distribution = ggx``, sample the
                                             normals visible from wi instead of D cos.
                                             Ignored by the other distributions.
                                             (Default: true)
``energy_compensation``    string            the light lost by single scattering given
                                             back: ``none`` (the lecture's model),
                                             ``kulla_conty`` (a multiple-scattering lobe,
                                             reciprocal) or ``turquin`` (the specular lobe
                                             scaled, not reciprocal); see below.
                                             (Default: ``none``)
=========================  ================  ==============================================

Values outside the ranges above (NaN included) are refused with an error naming the
plugin, the parameter and its range, at load and when ``params.update()`` sets them.

The six colour/float parameters are exposed by ``traverse`` and differentiable.

The model (lecture, with l the light direction and v the viewer, h = normalize(l + v)):

    f_r        = k f_diffuse + (1 - k) f_specular
    f_diffuse  = m_D / pi
    f_specular = m_S D F G / (4 (n.l)(n.v))
    F          = F0 + (1 - F0)(1 - v.h)^5                                     (Schlick)
    D_beckmann = exp(-tan^2(alpha) / rho^2) / (pi rho^2 cos^4(alpha)),  cos(alpha) = n.h
    D_blinn    = (n.h)^(2 / rho^2 - 2) / (pi rho^2)
    D_ggx      = rho^2 / (pi ((n.h)^2 (rho^2 - 1) + 1)^2)
    G_ct       = min(1, 2 (n.h)(n.v) / (v.h), 2 (n.h)(n.l) / (v.h))
    G_ggx      = g(n.l) g(n.v),  g(c) = 2 / (1 + sqrt(1 + rho^2 (1 - c^2) / c^2))

``eval`` returns f_r (n.l); ``specular_scale`` s multiplies (1 - k) f_specular. Ngan,
Durand and Matusik's fits to the MERL measurements (EGSR 2005, the ``ngan2005`` presets)
use albedo D F G / (pi (n.l)(n.v)) (Cook and Torrance 1982's pi with a normalised
Beckmann D and F0 = their ``eta``) plus a Lambertian d / pi: k = 1/2, m_D = 2 d, m_S = albedo,
s = 8 / pi gives it exactly (one fit, colonial-maple-223, has albedo 0.98 and d 0.1, which
no (1 - k) m_S <= 1 reaches). Decisions where the lecture is loose:

- The lecture writes f_diffuse = m_D and folds n.l into f_r; following the package's convention the
  diffuse term is m_D / pi (a white Lambertian surface then reflects all light), and
  ``eval`` adds the cosine as every Mitsuba BSDF does. k weighs the whole diffuse and
  specular BRDFs (the lecture's linear interpolation), so with k = 0 the model is a
  microfacet metal of colour m_S and with k = 1 a Lambertian surface of colour m_D.
- The lecture's final slide writes f_specular with a single 4 (n.v) in the denominator
  because n.l is already folded in; the BRDF is the Blinn (1977) form above, with both
  cosines.
- Every D is normalised (D cos integrates to 1, checked in tests/test_microfacet.py); the
  lecture's Blinn D is the normalised cos^p lobe (p + 2) / (2 pi) cos^p with
  p = 2 / rho^2 - 2, the Torrance-Sparrow distribution.
- Schlick's F is taken at v.h (= l.h); F0 may be a colour.
- rho is restricted to [0, 1], the lecture's range (Blinn's exponent stays >= 0).

Sampling: the specular lobe draws h from D(h) cos(theta_h) (``core.microfacet``) or, for
GGX with ``sample_visible``, from the normals visible from wi (Heitz 2018; pdf
G1(wi) (wi.h) D(h) / cos(theta_i)), and reflects wi about h (Jacobian 1 / (4 wo.h)).
The diffuse lobe is cosine-weighted. The lobe is chosen in proportion to
(1 - k) mean(m_S F(cos theta_i)) against k mean(m_D), and the pdf is their mixture.

Lobes: glossy (index 0) and diffuse (index 1). A constant k = 1 or m_S = 0 leaves the
specular lobe out of sampling and of the kernel, a constant k = 0 or m_D = 0 the diffuse
one (both components stay declared: an update brings a lobe back).
The model is reciprocal. With k = 0, m_S = 1, F0 = 1 and GGX for both D and G it equals
Mitsuba's ``roughconductor`` (``distribution = ggx``, ``alpha = rho``, ``material =
none``) in eval and pdf (tested).

Energy compensation (``core.energy``; an extension, not in the lecture): the specular
lobe with F = 1 reflects E(mu) < 1 of the light at mu = cos(theta_i) (a white GGX metal
with Smith G: 0.31 at normal incidence for rho = 1, 0.83 for rho = 0.35; Beckmann with the
V-groove G: 0.45 for rho = 1): the rest is what real rough surfaces reflect after several
bounces between microfacets. ``kulla_conty`` adds Kulla & Conty's (2017) lobe
(1 - k) s m_S F_ms (1 - E(mu_i)) (1 - E(mu_o)) / (pi (1 - E_avg)), F_ms = F_avg^2 E_avg /
(1 - F_avg (1 - E_avg)), F_avg = F0 + (1 - F0) / 21, sampled cosine-weighted as a lobe of
its own (part of the glossy component); ``turquin`` multiplies f_specular by
1 + F0 (1 - E(mu_v)) / E(mu_v), mu_v the viewer's cosine (Turquin 2019: no extra lobe, not
reciprocal: under importance transport the roles of wi and wo are swapped). E and E_avg
come from tables of each D x G measured with this plugin's own ``sample()`` (F0 = 1),
interpolated bilinearly in (mu, rho) (``core/energy_tables.json``); derivatives with
respect to rho flow through the interpolation. A white metal then reflects all the light
(within 0.2% up to 80 degrees for rho in [0.1, 1], every D and G, by quadrature; tested
to 1%); with ``none`` nothing of it is traced and the values are those of the lecture's
model, bit for bit.

Albedo AOV (``eval_diffuse_reflectance``, the ``aov`` integrator's ``albedo``): k m_D,
the diffuse term's albedo; where it is black (a metal: k = 0 or m_D = 0), (1 - k) s m_S f0,
the specular lobe's Fresnel colour at normal incidence (clipped to 1). Never above 1.

XML::

    <bsdf type="cook_torrance">
        <rgb name="diffuse_reflectance" value="0.6, 0.2, 0.1"/>
        <float name="k" value="0.7"/>
        <float name="roughness" value="0.2"/>
        <string name="distribution" value="ggx"/>
        <string name="geometry" value="ggx"/>
    </bsdf>

Python: ``mi.load_dict({'type': 'cook_torrance', 'roughness': 0.2, 'distribution': 'ggx'})``
"""

from ..core.energy import COMPENSATIONS
from ..core.facts import RED, Facts, rgb
from ..core.microfacet import DISTRIBUTIONS, GEOMETRIES
from ..core.registry import bsdf_plugin
from ._microfacet_family import MicrofacetModel, MicrofacetPoint

__all__ = ["CookTorrance"]


@bsdf_plugin("cook_torrance")
class CookTorrance(MicrofacetModel):
    OPTIONS = {"distribution": tuple(DISTRIBUTIONS), "geometry": tuple(GEOMETRIES),
               "sample_visible": (True, False), "energy_compensation": COMPENSATIONS}

    def _read_parameters(self, r):
        self.m_d = r.reflectance("diffuse_reflectance", 0.5)
        self.m_s = r.reflectance("specular_reflectance", 1.0)
        self.k = r.scalar("k", 0.5, 0.0, 1.0, what="a weight")
        self.roughness = r.scalar("roughness", 0.3, 0.0, 1.0, what="a roughness")
        self.f0 = r.reflectance("f0", 0.04)
        self.specular_scale = r.scalar("specular_scale", 1.0, what="a factor")
        self.distribution = r.enum("distribution", "beckmann", self.OPTIONS["distribution"])
        self.geometry = r.enum("geometry", "cook_torrance", self.OPTIONS["geometry"])
        self.sample_visible = r.boolean("sample_visible", True)
        # load-time choices: the kernel holds only the chosen D, G and sampler
        self._make_distribution = DISTRIBUTIONS[self.distribution]
        self._geometry = GEOMETRIES[self.geometry]
        self._visible = self.sample_visible and self.distribution == "ggx"
        self._read_compensation(r, f"{self.distribution}/{self.geometry}")

    def _textures(self):
        return {"diffuse_reflectance": self.m_d, "specular_reflectance": self.m_s,
                "k": self.k, "roughness": self.roughness, "f0": self.f0,
                "specular_scale": self.specular_scale}

    def _options(self):
        return {"distribution": self.distribution, "geometry": self.geometry,
                "sample_visible": self._visible,
                "energy_compensation": self.energy_compensation}

    def _lobes_present(self):
        # D, F and G are never all zero: only the weights (1 - k) m_S and k m_D drop a lobe
        has_specular = not (self._is_constant(self.k, 1.0) or self._is_constant(self.m_s, 0.0)
                            or self._is_constant(self.specular_scale, 0.0))
        has_diffuse = not (self._is_constant(self.k, 0.0) or self._is_constant(self.m_d, 0.0))
        return has_specular, has_diffuse

    def _at(self, si, active):
        k = self.k.eval_1(si, active)
        rho = self.roughness.eval_1(si, active)
        return MicrofacetPoint(kd=k * self.m_d.eval(si, active),
                               ks=(1 - k) * self.specular_scale.eval_1(si, active)
                               * self.m_s.eval(si, active),
                               f0=self.f0.eval(si, active), rho=rho,
                               dist=self._make_distribution(rho))


#: what the generic tests, the property table, the catalog and the benchmarks run of this
#: model (``core.facts``)
FACTS = Facts(
    colour="diffuse_reflectance",
    differentiable=("diffuse_reflectance", "specular_reflectance", "k", "roughness", "f0"),
    non_default={"distribution": "ggx", "roughness": 0.2, "f0": (0.9, 0.6, 0.5)},
    edges=tuple(dict(roughness=r, distribution=d, geometry=g) for r in (0.0, 1.0)
                for d in DISTRIBUTIONS for g in GEOMETRIES)
    + (dict(roughness=0.0, distribution="ggx", geometry="ggx", energy_compensation="kulla_conty"),
       dict(roughness=1.0, distribution="blinn", geometry="cook_torrance",
            energy_compensation="turquin")),
    float64=tuple((dict(distribution=d, geometry=g, roughness=0.3), 1e-4)
                  for d in DISTRIBUTIONS for g in GEOMETRIES)
    # the compensated forms, with the shipped tables' E interpolated in float64
    + ((dict(distribution="ggx", geometry="ggx", roughness=0.6, f0=0.8,
             energy_compensation="kulla_conty"), 1e-4),
       (dict(distribution="beckmann", geometry="cook_torrance", roughness=0.45, f0=0.5,
             energy_compensation="turquin"), 1e-4)),
    gradient_edges=(
        dict(roughness=1e-4, f0=0.0, distribution="beckmann", geometry="cook_torrance"),
        dict(roughness=1e-4, f0=1.0, distribution="blinn", geometry="cook_torrance"),
        dict(roughness=1e-4, f0=0.0, distribution="ggx", geometry="ggx"),
        dict(roughness=1.0, f0=1.0, distribution="ggx", geometry="cook_torrance"),
        dict(roughness=1e-4, f0=0.0, distribution="ggx", geometry="ggx",
             energy_compensation="kulla_conty"),
        dict(roughness=1.0, f0=1.0, distribution="beckmann", geometry="cook_torrance",
             energy_compensation="turquin"),
    ),
    finite_difference=(dict(roughness=0.3, f0=0.2), ("roughness", "f0")),
    zero_lobes=(("diffuse_reflectance", 0, 0.5, {}), ("specular_reflectance", 0, 0.5, {}),
                ("k", 0, 0.5, {}),   # no diffuse lobe
                ("k", 1, 0.5, {})),  # no specular lobe
    albedo=(({"diffuse_reflectance": rgb(0.8, 0.4, 0.2), "k": 0.5}, [0.4, 0.2, 0.1]),
            ({"k": 0.0, "specular_reflectance": 1.0, "f0": rgb(0.95, 0.64, 0.54),
              "roughness": 0.1}, [0.95, 0.64, 0.54])),
    traced_options=({"distribution": "ggx", "geometry": "ggx"}, {"distribution": "blinn"},
                    {"energy_compensation": "kulla_conty", "roughness": 0.7},
                    {"energy_compensation": "turquin", "distribution": "ggx"}),
    properties=tuple((f"{d}/{g} rho={r:g}", {"distribution": d, "geometry": g, "roughness": r,
                                             "k": 0.0, "f0": 1.0, "specular_reflectance": 1.0})
                     for d in DISTRIBUTIONS for g in GEOMETRIES for r in (0.1, 0.5))
    # the light single scattering loses, given back
    + tuple((f"ggx/ggx rho=1 {form}", {"distribution": "ggx", "geometry": "ggx", "roughness": 1.0,
                                       "k": 0.0, "f0": 1.0, "specular_reflectance": 1.0,
                                       "energy_compensation": form})
            for form in ("none", "kulla_conty", "turquin")),
    catalog=tuple((f"{d}/{g}", {"distribution": d, "geometry": g, "diffuse_reflectance": RED,
                                "roughness": 0.2, "k": 0.5})
                  for d in DISTRIBUTIONS for g in GEOMETRIES),
    cpp=(("ggx_metal", {"distribution": "ggx", "geometry": "ggx", "roughness": 0.2, "k": 0.0,
                        "f0": 1.0, "specular_reflectance": 1.0},
          {"type": "roughconductor", "distribution": "ggx", "alpha": 0.2},
          "the same model (eval and pdf equal, tested), visible-normal sampling in both"),
         ("beckmann_plastic", {"distribution": "beckmann", "geometry": "cook_torrance",
                               "roughness": 0.2, "k": 0.5, "diffuse_reflectance": 0.5},
          {"type": "roughplastic", "distribution": "beckmann", "alpha": 0.2},
          "two lobes each (roughplastic: a rough dielectric coating over a diffuse base)")),
    dropped_lobes=(("k0_vs_k_tiny", {"k": 0.0, "roughness": 0.2}, {"k": 1e-6, "roughness": 0.2},
                    "k = 0 (diffuse dropped) / k = 1e-6"),
                   ("k1_vs_k_almost1", {"k": 1.0, "roughness": 0.2},
                    {"k": 1.0 - 1e-6, "roughness": 0.2}, "k = 1 (specular dropped) / k = 1 - 1e-6")),
    cases=tuple((dict(diffuse_reflectance=md, specular_reflectance=ms, k=k, roughness=rho, f0=f0,
                      distribution=d, geometry=g), 5e-4)
                for (md, ms, k, rho, f0), (d, g) in zip(
                    [(0.5, 1.0, 0.5, 0.3, 0.04),
                     (rgb(0.7, 0.2, 0.1), rgb(0.9, 0.6, 0.3), 0.2, 0.08, rgb(0.9, 0.7, 0.4)),
                     (0.0, rgb(1.0, 0.8, 0.6), 0.0, 0.6, 1.0),
                     (rgb(0.3, 0.6, 0.9), 0.5, 0.8, 1.0, 0.0)] * 2,
                    [(d, g) for g in GEOMETRIES for d in DISTRIBUTIONS] + [("ggx", "ggx")] * 2))
    + ((dict(roughness=0.6, k=0.2, f0=rgb(0.9, 0.6, 0.3), distribution="ggx", geometry="ggx",
             energy_compensation="kulla_conty"), 5e-4),
       (dict(roughness=0.8, k=0.0, f0=rgb(0.95, 0.64, 0.54), energy_compensation="turquin"),
        5e-4)),
    # Turquin's scaling is not reciprocal (documented)
    not_reciprocal=({"energy_compensation": "turquin"},),
    chi2=(("beckmann_ct_mixed", dict(distribution="beckmann", geometry="cook_torrance"), 30, 16),
          ("beckmann_ggx_metal_grazing", dict(distribution="beckmann", geometry="ggx", k=0.0,
                                              roughness=0.1), 85, 64),
          ("blinn_ct_metal", dict(distribution="blinn", geometry="cook_torrance", k=0.0,
                                  roughness=0.15, f0=0.5), 45, 32),
          ("blinn_ggx_mixed_grazing", dict(distribution="blinn", geometry="ggx", roughness=0.5,
                                           f0=0.3), 87, 16),
          ("ggx_ct_visible_grazing", dict(distribution="ggx", geometry="cook_torrance", k=0.0,
                                          roughness=0.2), 80, 32),
          ("ggx_ggx_visible", dict(distribution="ggx", geometry="ggx", roughness=0.3, f0=0.5),
           0, 16),
          ("ggx_ggx_visible_89", dict(distribution="ggx", geometry="ggx", k=0.0, roughness=0.5),
           89, 16),
          ("ggx_ggx_d_sampling", dict(distribution="ggx", geometry="ggx", k=0.0, roughness=0.3,
                                      sample_visible=False), 60, 16),
          ("ggx_ct_d_sampling_mixed", dict(distribution="ggx", geometry="cook_torrance",
                                           roughness=0.7, sample_visible=False), 75, 8),
          ("rough_one", dict(roughness=1.0, f0=1.0), 50, 8),
          ("diffuse_only", dict(k=1.0), 40, 8),
          ("diffuse_component", dict(component=1, roughness=0.2), 70, 8),
          ("kulla_conty", dict(distribution="ggx", geometry="ggx", k=0.0, roughness=0.7,
                               energy_compensation="kulla_conty"), 45, 16),
          ("turquin", dict(roughness=0.5, energy_compensation="turquin"), 30, 16)),
    # (visible normals are sampled with GGX alone)
    stability=tuple({"distribution": d, "geometry": tuple(GEOMETRIES), "sample_visible": v,
                     "roughness": (0.0, 1e-4, 1.0), "f0": (0.0, 1.0), "k": (0.0, 0.5),
                     "diffuse_reflectance": (1.0,)}
                    for d, v in ((("beckmann", "blinn"), (True,)), (("ggx",), (True, False))))
    + ({"energy_compensation": ("kulla_conty", "turquin"), "distribution": tuple(DISTRIBUTIONS),
        "roughness": (0.0, 1e-4, 1.0), "f0": (0.0, 1.0), "k": (0.0,)},),
    renders=(("default", {}),
             ("blinn_ggx", dict(distribution="blinn", geometry="ggx", roughness=0.2)),
             ("ggx_metal_visible", dict(distribution="ggx", geometry="ggx", k=0.0,
                                        f0=rgb(0.9, 0.6, 0.3))),
             ("ggx_ct_metal_d", dict(distribution="ggx", geometry="cook_torrance", k=0.0,
                                     sample_visible=False, roughness=0.4)),
             ("mirror_like", dict(k=0.0, f0=1.0, roughness=1e-4)),
             ("rough", dict(roughness=1.0, distribution="beckmann", geometry="ggx")),
             ("kulla_conty", dict(roughness=0.7, k=0.0, distribution="ggx", geometry="ggx",
                                  energy_compensation="kulla_conty")),
             ("turquin", dict(roughness=0.7, k=0.0, energy_compensation="turquin"))),
)
