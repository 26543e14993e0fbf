"""Ashikhmin-Shirley anisotropic Phong BRDF (``ashikhmin_shirley``).

References: M. Ashikhmin, P. Shirley, "An Anisotropic Phong BRDF Model",
Journal of Graphics Tools 5(2), 25-32, 2000 (equation numbers below are the paper's).

Parameters
----------
=========================  ================  ==============================================
``specular_reflectance``   spectrum/texture  Rs, specular reflectance at normal incidence,
                                             in [0, 1]. (Default: 0.05)
``diffuse_reflectance``    spectrum/texture  Rd, reflectance of the diffuse substrate,
                                             in [0, 1]. 0 makes a metal. (Default: 0.5)
``nu``                     float/texture     Phong exponent along the tangent u (the
                                             shape's dP/du), in [0, 1e6]. (Default: 100)
``nv``                     float/texture     Phong exponent along v, in [0, 1e6].
                                             (Default: 100)
``alpha_u``, ``alpha_v``   float/texture     instead of ``nu``, ``nv``: Beckmann roughness
                                             along u and v, in [1.5e-3, 1], as Mitsuba's
                                             ``roughconductor`` takes it; n = 2 / alpha^2 - 2
                                             (see below). Both or neither; not with
                                             ``nu``/``nv``. (Default: unused)
``alpha``                  float/texture     alpha_u = alpha_v = alpha, in [1.5e-3, 1];
                                             not with ``nu``/``nv`` nor ``alpha_u``/``alpha_v``.
                                             (Default: unused)
``specular_scale``         spectrum/texture  extension (not in the paper): a colour in
                                             [0, 1] multiplying the specular term (eq. 4),
                                             for fits that give the lobe its own albedo
                                             on top of F(k.h), as Ngan et al. 2005 do.
                                             (Default: 1)
``diffuse_term``           string            extension: ``ashikhmin_shirley`` (eq. 5) or
                                             ``lambert`` (Rd / pi, not coupled to Rs,
                                             the diffuse term of Ngan et al. 2005).
                                             (Default: ``ashikhmin_shirley``)
``sampling``               string            ``half_vector``: the paper's importance
                                             sampling; ``cosine``: cosine-weighted
                                             directions only (a baseline).
                                             (Default: ``half_vector``)
=========================  ================  ==============================================

Values outside the ranges above (NaN included) are refused with an error naming the
plugin, the parameter and its range, at load and when ``params.update()`` sets them.

All five reflectance/exponent parameters (``alpha_u``/``alpha_v`` or ``alpha`` when given
instead of the exponents) are exposed by ``traverse`` and differentiable.

Roughness: ``alpha_u``, ``alpha_v`` (or ``alpha``) set the exponents to nu = 2 / alpha_u^2 - 2,
nv = 2 / alpha_v^2 - 2 (``core.roughness``; Walter et al. 2007): the half-vector lobe
cos^n(theta_h) then has the width and peak of the Beckmann distribution of that roughness,
so a scene written for ``roughconductor`` or ``roughplastic`` switches to this model by its
plugin name. alpha = 1 is n = 0, alpha = 0.1 is n = 198, alpha = 1.5e-3 is n = 8.9e5. The
mapping is applied in the kernel, so the roughness stays differentiable.

The model (eq. 1) is a specular lobe plus a non-Lambertian diffuse term:

    rho_s = sqrt((nu+1)(nv+1)) / (8 pi) * (n.h)^E / ((h.k) max(n.k1, n.k2)) * F(k.h)  (eq. 4)
    E     = (nu (h.u)^2 + nv (h.v)^2) / (1 - (h.n)^2)
    F     = Rs + (1 - Rs)(1 - k.h)^5                                              (eq. 3)
    rho_d = 28 Rd / (23 pi) (1 - Rs) (1 - (1 - n.k1/2)^5) (1 - (1 - n.k2/2)^5)    (eq. 5)

``eval`` returns (rho_s + rho_d) cos(theta_o). The extensions change nothing at their
defaults: ``specular_scale`` s makes the specular term s rho_s, and ``diffuse_term =
lambert`` replaces rho_d by Rd / pi. Together they give the model Ngan, Durand and Matusik
fitted to the MERL measurements ("Experimental Analysis of BRDF Models", EGSR 2005; the
``ngan2005`` presets): a Lambertian albedo plus albedo (n+1)/(8 pi) (n.h)^n F(k.h) /
((k.h) max(n.k1, n.k2)) with Schlick's F0 = Rs. The model is reciprocal, so Mitsuba's wi/wo
and the paper's k1/k2 may be taken either way round.

Numerics: eq. 4's exponent is evaluated with no trigonometry and no 0/0 at h = n (see
``core.warp.aniso_phong_cos_power``); sampling (eq. 9, 10) works in log space, so
exponents from 0 to 1e6 and grazing directions stay finite in float32.

Sampling (sec. 3): a half vector h is drawn from p_h (eq. 6) by eq. 9-10 with the quadrant
mapping of xi_1, k2 is k1 reflected about h (eq. 7) with density p_h / (4 k.h) (eq. 8) and
zero weight below the horizon; the diffuse lobe is cosine-weighted. The lobe is chosen
with probability proportional to an estimate of each lobe's albedo at the incident
direction: F(cos theta_i) averaged over channels for the specular one, and the diffuse
term's exact albedo Rd (1 - Rs)(1 - (1 - cos theta_i / 2)^5) (eq. 5 integrates to it;
the 28/23 cancels), Rd for the ``lambert`` diffuse term; the specular estimate is scaled
by the mean of ``specular_scale``. The returned pdf is that weighted average of the two densities.

Lobes: a glossy anisotropic component (index 0), a diffuse one (index 1). A constant zero
Rd (or a constant Rs = 1, which zeroes eq. 5 through 1 - Rs) leaves the diffuse lobe out
of sampling and of the traced kernel (a metal; with ``diffuse_term = lambert`` only a
zero Rd does); the component stays declared, so an update
through ``mi.traverse`` (or differentiating a parameter) brings the lobe back, inside
wrappers too. Rs = 0 does *not* silence the specular lobe: by eq. 3 it still reflects
F = (1 - k.h)^5, which grows to 1 at grazing angles. The diffuse lobe alone is
``ctx.component = 1`` (or ``ctx.type_mask = Diffuse``).

Albedo AOV (``eval_diffuse_reflectance``, the ``aov`` integrator's ``albedo``): Rd,
the substrate's colour, as Mitsuba's ``roughplastic`` returns its ``diffuse_reflectance``
(not scaled by eq. 5's 1 - Rs, the share the specular layer leaves, like roughplastic's
1 - F); where Rd is black (a metal), Rs, the specular reflectance at normal incidence.
Never above 1.

XML::

    <bsdf type="ashikhmin_shirley">
        <rgb name="specular_reflectance" value="0.9, 0.8, 0.6"/>
        <float name="diffuse_reflectance" value="0"/>
        <float name="nu" value="10"/>
        <float name="nv" value="100"/>
    </bsdf>

Python::

    bsdf = mi.load_dict({'type': 'ashikhmin_shirley', 'nu': 10.0, 'nv': 100.0})
    rough = mi.load_dict({'type': 'ashikhmin_shirley', 'alpha_u': 0.4, 'alpha_v': 0.1})
"""
import drjit as dr
import mitsuba as mi

from ..core.facts import RED, Facts, rgb, white
from ..core.frame import cos_theta, half_vector, reflect
from ..core.fresnel import schlick
from ..core.lobes import Point, TwoLobeModel, lambert_f
from ..core.numerics import channel_mean, one_minus_pow5, safe_div
from ..core.registry import bsdf_plugin
from ..core.roughness import (beckmann_alpha, half_vector_exponent, read_roughness,
                              roughness_relations)
from ..core.warp import (MAX_EXPONENT, aniso_phong_cos_power, aniso_phong_half_vector_pdf,
                         aniso_phong_norm, reflection_jacobian,
                         square_to_aniso_phong_half_vector)

__all__ = ["AshikhminShirley"]


class _At(Point):
    """Parameter values at one shading point."""
    __slots__ = ("rs", "rd", "nu", "nv", "scale")


@bsdf_plugin("ashikhmin_shirley")
class AshikhminShirley(TwoLobeModel):
    GLOSSY_EXTRA_FLAGS = mi.BSDFFlags.Anisotropic
    OPTIONS = {"sampling": ("half_vector", "cosine"),
               "diffuse_term": ("ashikhmin_shirley", "lambert")}
    RELATIONS = roughness_relations(("nu", "nv"), anisotropic=True)

    def _read_parameters(self, r):
        self.rs = r.reflectance("specular_reflectance", 0.05)
        self.rd = r.reflectance("diffuse_reflectance", 0.5)
        # the exponents, or a Beckmann roughness that sets them (a load-time choice)
        self.alpha = read_roughness(r)
        if self.alpha is None:
            self.nu = r.scalar("nu", 100.0, hi=MAX_EXPONENT, what="a Phong exponent")
            self.nv = r.scalar("nv", 100.0, hi=MAX_EXPONENT, what="a Phong exponent")
        # extensions (see the docstring): defaults give the paper's model
        self.specular_scale = r.reflectance("specular_scale", 1.0)
        self.diffuse_term = r.enum("diffuse_term", "ashikhmin_shirley",
                                   self.OPTIONS["diffuse_term"])
        self._lambert = self.diffuse_term == "lambert"
        self.sampling = r.enum("sampling", "half_vector", self.OPTIONS["sampling"])
        self.cosine_only = self.sampling == "cosine"

    def _textures(self):
        textures = {"specular_reflectance": self.rs, "diffuse_reflectance": self.rd,
                    "specular_scale": self.specular_scale}
        if self.alpha is None:
            return {**textures, "nu": self.nu, "nv": self.nv}
        au, av = self.alpha
        return {**textures, **({"alpha": au} if au is av else {"alpha_u": au, "alpha_v": av})}

    def _options(self):
        return {"sampling": self.sampling, "diffuse_term": self.diffuse_term}

    def _lobes_present(self):
        # Schlick's F is never zero (F >= (1 - k.h)^5): the specular lobe is always present
        rs_one = self._is_constant(self.rs, 1.0) and not self._lambert
        return True, not (self._is_constant(self.rd, 0.0) or rs_one)

    def _at(self, si, active):
        if self.alpha is None:
            nu, nv = self.nu.eval_1(si, active), self.nv.eval_1(si, active)
        else:
            au, av = self.alpha
            nu = half_vector_exponent(au.eval_1(si, active))
            nv = nu if au is av else half_vector_exponent(av.eval_1(si, active))
        return _At(rs=self.rs.eval(si, active), rd=self.rd.eval(si, active), nu=nu, nv=nv,
                   scale=self.specular_scale.eval(si, active))

    # -- specular lobe, eq. 2-4, 6-10 ----------------------------------------------------

    def _glossy_f(self, p, wi, wo):
        h, k_h = half_vector(wi, wo)
        cos_i, cos_o = cos_theta(wi), cos_theta(wo)
        lobe = aniso_phong_norm(p.nu, p.nv) * (1 / (8 * dr.pi)) \
            * aniso_phong_cos_power(h, p.nu, p.nv)                              # eq. 4
        # (k.h) max(n.k1, n.k2) > 0 whenever both directions are above the surface; the
        # cosine ratio (<= 1) first, so that a tiny lobe times a grazing cos_o cannot underflow
        scale = lobe * safe_div(safe_div(cos_o, dr.maximum(cos_i, cos_o)), k_h)
        return p.scale * schlick(p.rs, k_h) * scale                            # eq. 3

    def _glossy_pdf(self, p, wi, wo):
        h, k_h = half_vector(wi, wo)
        pdf_h = aniso_phong_half_vector_pdf(h, p.nu, p.nv)                      # eq. 6
        return pdf_h * reflection_jacobian(k_h)                                 # eq. 8

    def _glossy_sample(self, p, wi, u):
        h = square_to_aniso_phong_half_vector(u, p.nu, p.nv)                    # eq. 9-10
        return reflect(wi, h)                                                   # eq. 7

    def _glossy_albedo(self, p, wi):
        return channel_mean(p.scale * schlick(p.rs, cos_theta(wi)))

    # -- diffuse lobe, eq. 5 -------------------------------------------------------------

    def _diffuse_f(self, p, wi, wo):
        if self._lambert:  # extension: Rd / pi (a load-time choice)
            return lambert_f(p.rd, wo)
        cos_i, cos_o = cos_theta(wi), cos_theta(wo)
        # 1 - (1 - x/2)^5 written out: exact where n.k ~ 1e-7 (1 - x/2 rounds to 1 there)
        shape = one_minus_pow5(0.5 * cos_i) * one_minus_pow5(0.5 * cos_o)
        return p.rd * (1 - p.rs) * (28 / (23 * dr.pi) * shape * cos_o)

    def _diffuse_albedo(self, p, wi):
        if self._lambert:
            return channel_mean(p.rd)
        return channel_mean(p.rd * (1 - p.rs)) * one_minus_pow5(0.5 * cos_theta(wi))

    # -- albedo AOV ----------------------------------------------------------------------

    def _diffuse_colour(self, p):
        return p.rd

    def _specular_colour(self, p):
        return p.scale * p.rs                                                   # F(1), eq. 3


def _metal(n, **kw):
    """A white metal of exponent ``n`` (other settings ``kw``)."""
    return {"nu": float(n), "nv": float(n), "specular_reflectance": 1.0,
            "diffuse_reflectance": 0.0, **kw}


#: what the generic tests, the property table, the catalog and the benchmarks run of this
#: model (``core.facts``)
FACTS = Facts(
    colour="diffuse_reflectance",
    differentiable=("specular_reflectance", "diffuse_reflectance", "nu", "nv"),
    non_default={"nu": 20.0, "nv": 200.0, "specular_reflectance": (0.3, 0.3, 0.2)},
    edges=(dict(nu=0.01, nv=0.01), dict(nu=1e6, nv=1e6, diffuse_reflectance=0.0),
           dict(nu=0.0, nv=1e6, specular_reflectance=1.0)),
    float64=((dict(nu=0.01, nv=0.01), 1e-4),
             (dict(nu=100.0, nv=100.0, diffuse_reflectance=0.2), 1e-4)),
    gradient_edges=(
        dict(nu=0.0, nv=0.0, specular_reflectance=0.0, diffuse_reflectance=0.5),
        dict(nu=0.0, nv=1e6, specular_reflectance=0.0, diffuse_reflectance=0.5),
        dict(nu=1e6, nv=1e6, specular_reflectance=0.3, diffuse_reflectance=0.5),
        dict(nu=1.0, nv=1e6, specular_reflectance=1.0, diffuse_reflectance=0.0),
    ),
    finite_difference=(dict(nu=20.0, nv=200.0, specular_reflectance=0.3, diffuse_reflectance=0.5),
                       ("nu", "nv", "specular_reflectance", "diffuse_reflectance")),
    zero_lobes=(("diffuse_reflectance", 0, 0.5, {}),),
    albedo=(({"diffuse_reflectance": 0.4, "specular_reflectance": 0.3, "nu": 20.0, "nv": 200.0},
             [0.4] * 3),
            ({"diffuse_reflectance": 0.0, "specular_reflectance": rgb(0.9, 0.8, 0.6),
              "nu": 1000.0, "nv": 1000.0}, [0.9, 0.8, 0.6])),
    on_request=({"alpha_u": 0.2, "alpha_v": 0.3},),
    traced_options=({"sampling": "cosine"},),
    properties=(
        ("metal n=100", _metal(100)),
        ("metal nu=10 nv=1000", {**_metal(10), "nv": 1000.0}),
        ("plastic Rs=0.05 Rd=1 n=100", {"nu": 100.0, "nv": 100.0, "specular_reflectance": 0.05,
                                        "diffuse_reflectance": 1.0}),
        # roughness instead of the exponents (the Beckmann-equivalent lobes of core.roughness)
        ("metal alpha_u=0.05 alpha_v=0.3", {"alpha_u": 0.05, "alpha_v": 0.3,
                                            "specular_reflectance": 1.0, "diffuse_reflectance": 0.0}),
    ),
    catalog=(
        ("n=100", {"diffuse_reflectance": RED, "specular_reflectance": white(0.05), "nu": 100.0,
                   "nv": 100.0}),
        ("nu=10 nv=1000", {"diffuse_reflectance": RED, "specular_reflectance": white(0.05),
                           "nu": 10.0, "nv": 1000.0}),
        ("metal n=300", {"diffuse_reflectance": 0.0, "specular_reflectance": rgb(0.95, 0.7, 0.35),
                         "nu": 300.0, "nv": 300.0}),
        # roughness instead of exponents: alpha = 0.1 is n = 198
        ("alpha_u=0.05 alpha_v=0.3", {"diffuse_reflectance": RED,
                                      "specular_reflectance": white(0.05), "alpha_u": 0.05,
                                      "alpha_v": 0.3}),
    ),
    cpp=(("metal", _metal(100),
          {"type": "roughconductor", "distribution": "beckmann",
           "alpha": round(beckmann_alpha(100), 4)},
          "comparable lobe: Beckmann alpha = sqrt(2 / (n + 2)), perfect conductor"),
         ("metal_vs_nonvisible", _metal(100),
          {"type": "roughconductor", "distribution": "beckmann",
           "alpha": round(beckmann_alpha(100), 4), "sample_visible": False},
          "as above, roughconductor sampling D cos (as AS samples its half vectors)"),
         ("plastic", {"nu": 100.0, "nv": 100.0, "specular_reflectance": 0.05,
                      "diffuse_reflectance": rgb(0.6, 0.08, 0.05)},
          {"type": "roughplastic", "distribution": "beckmann",
           "alpha": round(beckmann_alpha(100), 4), "diffuse_reflectance": rgb(0.6, 0.08, 0.05)},
          "two lobes each, comparable specular lobe")),
    dropped_lobes=(("rd0_vs_rd_tiny", _metal(100, specular_reflectance=0.9),
                    _metal(100, specular_reflectance=0.9, diffuse_reflectance=1e-6),
                    "Rd = 0 (diffuse lobe dropped) / Rd = 1e-6 (kept)"),
                   ("rs1_vs_rs_almost1", {"specular_reflectance": 1.0, "diffuse_reflectance": 0.5},
                    {"specular_reflectance": 1.0 - 1e-6, "diffuse_reflectance": 0.5},
                    "Rs = 1, Rd = 0.5 (eq. 5's 1 - Rs = 0: diffuse dropped) / Rs = 1 - 1e-6")),
    cases=tuple((dict(specular_reflectance=rs, diffuse_reflectance=rd, nu=nu, nv=nv, **kw), 5e-4)
                for rs, rd, nu, nv, kw in [
                    (0.05, 0.5, 100.0, 100.0, {}), (rgb(0.9, 0.6, 0.3), 0.0, 10.0, 1000.0, {}),
                    (rgb(0.2, 0.4, 0.1), rgb(0.7, 0.1, 0.3), 1.0, 1.0, {}),
                    (1.0, 0.3, 1e4, 10.0, {}), (0.0, 1.0, 5.0, 5.0, {}),
                    (0.05, 0.5, 100.0, 100.0, {"sampling": "cosine"})]),
    chi2=(("isotropic_mixed_normal", dict(specular_reflectance=0.05, nu=100.0, nv=100.0), 0, 16),
          ("isotropic_mixed_45", dict(specular_reflectance=0.3, nu=30.0, nv=30.0), 45, 16),
          ("anisotropic_metal_30", _metal(10, specular_reflectance=0.9, nv=1000.0), 30, 32),
          ("anisotropic_metal_grazing", _metal(10, specular_reflectance=0.9, nv=1000.0), 85, 64),
          ("anisotropic_mixed_grazing", dict(specular_reflectance=0.2, diffuse_reflectance=0.8,
                                             nu=1000.0, nv=10.0), 80, 64),
          ("metal_sharp", _metal(1000), 20, 32),
          ("metal_broad_grazing", _metal(1), 87, 16),
          ("rs_zero", dict(specular_reflectance=0.0, diffuse_reflectance=0.8, nu=5.0, nv=5.0),
           60, 8),
          ("pure_diffuse", dict(specular_reflectance=0.3, diffuse_reflectance=0.8, component=1),
           60, 8),
          ("cosine_sampling", dict(specular_reflectance=0.5, nu=10.0, nv=10.0,
                                   sampling="cosine"), 45, 8)),
    stability={"sampling": ("half_vector", "cosine"), "specular_reflectance": (0.0, 1.0),
               "diffuse_reflectance": (0.0, 1.0), "nu": (0.0, 1e-3, 1.0, 1e4, 1e6),
               "nv": (0.0, 1e-3, 1.0, 1e4, 1e6)},
    renders=(("mixed", dict(specular_reflectance=0.05, diffuse_reflectance=0.5)),
             ("metal_aniso", _metal(10, specular_reflectance=0.9, nv=1000.0)),
             ("sharp", _metal(1e6)),
             ("zero_exponent_cosine", dict(nu=0.0, nv=0.0, sampling="cosine"))),
)
