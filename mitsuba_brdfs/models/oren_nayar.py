"""Oren-Nayar rough diffuse reflection (``oren_nayar``).

References: the lecture "BRDF models" (Politecnico di Milano), section Oren-Nayar;
M. Oren, S. K. Nayar, "Generalization of Lambert's Reflectance Model", SIGGRAPH 1994
(the lecture's formulas are that paper's qualitative model); J. Portsmouth, P. Kutz,
S. Hill, "EON: A Practical Energy-Preserving Rough Diffuse BRDF", JCGT 14(1), 2025 (the
energy-preserving form and its sampling), which builds on Y. Fujii's improved Oren-Nayar
model (FON).

Parameters
----------
===================  ================  =================================================
``reflectance``      spectrum/texture  rho, the diffuse colour m_D, in [0, 1].
                                       Exposed, differentiable. (Default: 0.5)
``sigma``            float/texture     roughness: standard deviation of the facet slope
                                       angle, in radians, in [0, pi/2]. 0 is Lambert.
                                       Exposed, differentiable. (Default: 0.3)
``a``, ``b``         float/texture     the lecture's A and B directly, instead of
                                       sigma ("the material specifies A instead of
                                       sigma"), each in [0, 1]; both or neither, not with
                                       ``sigma``. Exposed, differentiable.
                                       (Default: unused)
``lut_resolution``   integer           0: evaluate f(p, q) = B sin(alpha) tan(beta)
                                       analytically; N in [2, 4096]: look it up in the
                                       lecture's precomputed N x N table with bilinear
                                       interpolation (see below). (Default: 0)
``form``             string            ``qualitative``: the lecture's model (all of the
                                       above); ``energy_preserving``: EON (below), which
                                       takes a roughness and a sampling choice instead.
                                       (Default: ``qualitative``)
``roughness``        float/texture     EON's roughness r in [0, 1] (OpenPBR's
                                       ``base_diffuse_roughness``); 0 is Lambert. Only
                                       with ``form = energy_preserving``. Exposed,
                                       differentiable. (Default: 0.25)
``sampling``         string            ``cltc``: EON's clipped linearly transformed
                                       cosines (EON's default); ``cosine``:
                                       cosine-weighted, the only choice of the
                                       qualitative form. (Default: ``cosine``)
===================  ================  =================================================

Values outside the ranges above (NaN included) are refused with an error naming the
plugin, the parameter and its range, at load and when ``params.update()`` sets them.

The lecture's model, with d the light direction (Mitsuba's ``wo``), omega_r the viewer
(``si.wi``), theta_i = angle(d, n), theta_r = angle(omega_r, n):

    alpha = max(theta_i, theta_r),  beta = min(theta_i, theta_r)
    A = 1 - 0.5 sigma^2 / (sigma^2 + 0.33),  B = 0.45 sigma^2 / (sigma^2 + 0.09)
    G = max(0, v_i . v_r)   (v_i, v_r: d and omega_r projected on the tangent plane, normalised)
    f = rho / pi (A + B G sin(alpha) tan(beta))

and ``eval`` returns f cos(theta_i). The lecture writes L = m_D clamp(d.n) times
(A + B G sin(alpha) tan(beta)), without 1/pi; the package normalises all diffuse terms to
rho / pi (a white Lambert surface reflects all light), so sigma = 0 (A = 1, B = 0) gives
``lambert`` exactly (the same float operations: tests compare bit for bit).

Analytic evaluation (``lut_resolution = 0``) uses no trigonometry. With
v_i . v_r = (d_x w_x + d_y w_y) / (sin(theta_i) sin(theta_r)) and
sin(alpha) tan(beta) = sin(theta_i) sin(theta_r) / cos(beta), cos(beta) = max(cos theta_i,
cos theta_r), the product is

    G sin(alpha) tan(beta) = max(0, d_x w_x + d_y w_y) / max(cos(theta_i), cos(theta_r)),

the same value, finite at normal incidence (where G alone is 0/0), with finite
derivatives in sigma, d and omega_r everywhere. Both directions grazing make it large (tan(beta) -> inf),
but times cos(theta_i) it stays below 1.

The lookup table (``lut_resolution = N``): the lecture precomputes f(p, q) =
B sin(alpha) tan(beta) as a function of p = d.n and q = omega_r.n and interpolates it.
Here the table holds T(p, q) = sin(alpha) tan(beta) (the lecture's f divided by B, which
depends on sigma only and is applied in the kernel): the table does not depend on sigma,
is built once at load time, and stays a constant Dr.Jit texture (``mi.Texture2f``), so
changing or differentiating sigma neither rebuilds it nor recompiles the kernel.
Parameterisation: texel (i, j) holds T at the cell centre p = (i + 1/2)/N,
q = (j + 1/2)/N (float64, rounded to float32), linear filtering, coordinates clamped
(beyond the outer centres the table is constant). G is computed as in the lecture, from
the normalised tangent projections. T is symmetric, so reciprocity is kept.
Accuracy: T is unbounded where both directions graze (T ~ 1/max(p, q)), has a kink on the
diagonal p = q and a square-root edge at p, q -> 1, so bilinear interpolation converges
only like 1/N there. Measured error of ``eval`` relative to rho/pi (so 1 = the whole
Lambert value), sigma = pi/2 (the largest B), directions uniform on the hemisphere
(``tests/test_oren_nayar.py::test_lut_error``):

    ====  =========  ==========  =====================  ===========================
    N     RMS error  mean error  max, both < 89 deg     max, both grazing included
    ====  =========  ==========  =====================  ===========================
    32    2.7e-3     3e-4        0.12                   0.32
    256   3.3e-4     1.3e-5      0.025                  0.13
    ====  =========  ==========  =====================  ===========================

The RMS error falls like 1/N; the largest errors sit next to the grazing corner and the
diagonal. (Moving the outer nodes onto the edge p = 1 was tried: the RMS changes by 5%.)

The table exists to reproduce the lecture's method and to measure what it costs in
accuracy: the analytic form above has no trigonometry either and is exact, so it is the
default.

The lecture's A and B (``a``, ``b``): "in most of the cases, the material specifies
directly parameters A instead of sigma", so ``a`` and ``b`` replace ``sigma`` (and are
exposed by ``traverse`` instead of it). A = 1, B = 0 is Lambert. The sigma curve only
reaches A in [0.56, 1], B in [0, 0.43]; other pairs are accepted. The albedo is
A + B R(theta_i), with R the albedo of the retro-reflection term, 0 at normal incidence,
0.12 at 30 deg, 0.30 at 60 deg, 0.44 at 80 deg and 1/2 at grazing incidence: A + B / 2 <= 1
keeps it at most 1.

Energy: the qualitative model does not conserve energy exactly. Its albedo is at most 1
for sigma >= 0.35 at every incidence and for every sigma up to 60 degrees of incidence,
but exceeds 1 slightly at grazing incidence for smaller sigma (at most 1.015, sigma ~ 0.2,
theta = 90 degrees). That is a property of the lecture's formula, not of this code: the
tests compare the albedo with a float64 quadrature of the formula.

Sampling: cosine-weighted (pdf cos(theta)/pi), weight eval / pdf. The model is reciprocal.

The energy-preserving form (``form = energy_preserving``, EON). With mu_i, mu_o the cosines
of the two directions, s = omega_i . omega_o - mu_i mu_o (the tangential dot product),
r the roughness and rho the reflectance, FON's single scattering term and its directional
albedo are

    f_ss = rho / pi A (1 + r s / t),   t = max(mu_i, mu_o) if s > 0, else 1
    A    = 1 / (1 + C1 r),   C1 = 1/2 - 2 / (3 pi),   C2 = 2/3 - 28 / (15 pi)
    E(mu) = A (1 + r G(mu) / pi),   E_avg = 2 int E(mu) mu dmu = A (1 + C2 r)
    G(mu) = S (theta - S mu) + 2/3 ((S / mu)(1 - S^3) - S),  S = sin(theta), mu = cos(theta)

and EON adds the multiple scattering lobe that restores the energy f_ss loses:

    f_ms = rho_ms / pi (1 - E(mu_o)) (1 - E(mu_i)) / (1 - E_avg)
    rho_ms = rho^2 E_avg / (1 - rho (1 - E_avg))
    f = f_ss + f_ms,   albedo = rho E(mu_i) + rho_ms (1 - E(mu_i))

so a white surface (rho = 1) has albedo exactly 1 at every roughness and incidence, and r = 0
is Lambert. ``eval`` returns f mu_o; the form is reciprocal. Checked numerically
(``tests/test_oren_nayar.py``): E(mu) and E_avg against a float64 quadrature of f_ss (to
1e-6), the plugin's eval integrated over the hemisphere (1 to 2e-5 for rho = 1), and Monte
Carlo furnace tests at r from 0 to 1 and incidences up to 89.5 deg. Numerics: 1 - E(mu) is
evaluated as A r (C1 - G(mu) / pi) and 1 - E_avg as A r (C1 - C2), with no cancellation
(so f_ms is exactly 0 at r = 0, where the paper's listing adds a 1e-7 guard), G(mu) with
(S / mu)(1 - S^3) = S mu (1 + S + S^2) / (1 + S) and theta = atan2(S, mu): finite, with
finite derivatives, from mu = 0 to 1.

EON's sampling (``sampling = cltc``): with probability P_u(mu_i, r) (the paper's fit,
at most 0.16) a uniform hemisphere direction, else the clipped linearly transformed cosine
(``core.warp.square_to_clipped_ltc``) whose matrix (a, b, c, d) is the paper's fit in mu_i
and r; the pdf is that mixture, weight = eval / pdf. Every sample lies above the surface.
Against cosine sampling (``sampling = cosine``, the baseline) it divides the variance of
the weights of a white surface by 7, 15 and 41 at 45, 80 and 89.5 deg for r = 1 (4.5, 11, 34
for r = 0.5); at normal incidence, where the lobe is nearly a cosine, both are alike (the
variance is small either way).

Lobes: one diffuse reflection component (index 0) in both forms; a constant black
reflectance does no work (nothing sampled or traced) until an update or a gradient brings
it back.

Albedo AOV (``eval_diffuse_reflectance``, the ``aov`` integrator's ``albedo``): rho, the
colour the roughness term modulates (as for ``lambert``).

XML::

    <bsdf type="oren_nayar">
        <rgb name="reflectance" value="0.7, 0.4, 0.3"/>
        <float name="sigma" value="0.5"/>
        <integer name="lut_resolution" value="0"/>
    </bsdf>

Python::

    bsdf = mi.load_dict({'type': 'oren_nayar', 'sigma': 0.5})
    lecture = mi.load_dict({'type': 'oren_nayar', 'a': 0.7, 'b': 0.4})
    eon = mi.load_dict({'type': 'oren_nayar', 'form': 'energy_preserving', 'roughness': 1.0})
"""
import math

import drjit as dr
import mitsuba as mi

from ..core.facts import RED, Facts, rgb
from ..core.frame import cos_theta
from ..core.lobes import Point, TwoLobeModel, lambert_f
from ..core.numerics import safe_div
from ..core.params import ParameterError, float32
from ..core.registry import bsdf_plugin
from ..core.relations import Excludes, Only, Together

__all__ = ["OrenNayar", "FORMS", "SAMPLING", "oren_nayar_ab", "sin_alpha_tan_beta_table"]

#: the plugin's forms: the lecture's model (this module) and EON (``oren_nayar_eon``)
FORMS = ("qualitative", "energy_preserving")
#: the plugin's samplers: EON's own (its form only) and cosine-weighted
SAMPLING = ("cltc", "cosine")
#: largest table side (4096^2 float32 = 64 MiB)
MAX_LUT = 4096
#: upper bound of sigma: pi/2 rounded up to float32 (a texture stores float32(pi/2), which
#: is slightly above the float64 pi/2)
SIGMA_MAX = float32(math.pi / 2)


def oren_nayar_ab(sigma):
    """The lecture's A and B from the roughness sigma (radians)."""
    s2 = sigma * sigma
    return 1 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09)


def sin_alpha_tan_beta_table(n):
    """T(p, q) = sin(alpha) tan(beta) at the cell centres (i + 1/2)/n of [0, 1]^2, computed
    in float64, as a float32 ``mi.TensorXf`` of shape (n, n, 1): rows follow q, columns p
    (the table is symmetric)."""
    flat = mi.TensorXf().array
    f64, u32 = dr.float64_array_t(flat), dr.uint32_array_t(flat)
    theta = f64([math.acos((k + 0.5) / n) for k in range(n)])  # at the cell centres
    i = dr.arange(u32, n * n)
    c_p, c_q = dr.gather(f64, theta, i % n), dr.gather(f64, theta, i // n)
    t = dr.sin(dr.maximum(c_p, c_q)) * dr.tan(dr.minimum(c_p, c_q))
    return mi.TensorXf(type(flat)(t), shape=(n, n, 1))


class _At(Point):
    """Parameter values at one shading point: rho and the lecture's A and B."""
    __slots__ = ("rho", "a", "b")


#: the relations of the plugin's parameters (``core.relations``), in both forms
PARAMETER_RELATIONS = (
    Only(("roughness",), "form", "energy_preserving", default="qualitative",
         why="the qualitative form takes 'sigma', or 'a' and 'b'"),
    Only(("sigma", "a", "b", "lut_resolution"), "form", "qualitative", default="qualitative",
         why="form 'energy_preserving' takes 'roughness' in [0, 1]"),
    Excludes(("sigma",), ("a", "b"), why="the lecture's A and B replace sigma"),
    Together("a", "b", why="A and B come together"),
)


@bsdf_plugin("oren_nayar")
class OrenNayar(TwoLobeModel):
    """The lecture's model (``form = qualitative``, the default); the plugin builds
    ``oren_nayar_eon.OrenNayarEON`` instead for ``form = energy_preserving``."""
    LOBES = (False, True)
    #: (sampling = cltc goes with form = energy_preserving only)
    OPTIONS = {"form": FORMS, "sampling": SAMPLING}
    RELATIONS = PARAMETER_RELATIONS
    cosine_only = True

    def _read_parameters(self, r):
        self.rho = r.reflectance("reflectance", 0.5)
        # (the plugin builds OrenNayarEON for 'energy_preserving': only 'qualitative' is left)
        self.form = r.enum("form", "qualitative", FORMS)
        self.sigma = self.a = self.b = self.lut = None
        self.sampling = r.enum("sampling", "cosine", SAMPLING)
        if self.sampling != "cosine":
            raise r.error("sampling", "'cosine' with form 'qualitative' ('cltc' samples the "
                          "energy-preserving form)", repr(self.sampling))
        self._read_qualitative(r)

    def _read_qualitative(self, r):
        """sigma, or the lecture's A and B directly; the optional lookup table."""
        if "a" in r.props:  # (with "b": ``RELATIONS``)
            self.a = r.scalar("a", 1.0, 0.0, 1.0, what="the lecture's A")
            self.b = r.scalar("b", 0.0, 0.0, 1.0, what="the lecture's B")
        else:
            self.sigma = r.scalar("sigma", 0.3, 0.0, SIGMA_MAX,
                                  what="a roughness angle in radians (pi/2 = 1.5708)")
        expected = f"0 (analytic) or a table size in [2, {MAX_LUT}]"
        try:
            n = r.integer("lut_resolution", 0, 0, MAX_LUT)
        except ParameterError:
            n = None
        if n is None or n == 1:
            raise r.error("lut_resolution", expected, repr(r.props.get("lut_resolution")))
        self.lut_resolution = n
        if n > 0:
            self.lut = mi.Texture2f(sin_alpha_tan_beta_table(n), use_accel=False,
                                    filter_mode=dr.FilterMode.Linear,
                                    wrap_mode=dr.WrapMode.Clamp)

    def _textures(self):
        if self.sigma is None:
            return {"reflectance": self.rho, "a": self.a, "b": self.b}
        return {"reflectance": self.rho, "sigma": self.sigma}

    def _options(self):
        return {"form": self.form, "lut_resolution": self.lut_resolution}

    def _lobes_present(self):
        return False, not self._is_constant(self.rho, 0.0)

    def _at(self, si, active):
        rho = self.rho.eval(si, active)
        if self.sigma is None:  # the lecture's A and B given directly
            a, b = self.a.eval_1(si, active), self.b.eval_1(si, active)
        else:
            a, b = oren_nayar_ab(self.sigma.eval_1(si, active))
        return _At(rho=rho, a=a, b=b)

    # -- the term G sin(alpha) tan(beta) ---------------------------------------------------

    @staticmethod
    def _retro_analytic(wi, wo):
        """G sin(alpha) tan(beta) = max(0, tangential dot) / max(cos theta_i, cos theta_r)."""
        tangential = dr.maximum(wi.x * wo.x + wi.y * wo.y, 0)
        return safe_div(tangential, dr.maximum(cos_theta(wi), cos_theta(wo)))

    def _retro_lut(self, wi, wo):
        """G from the normalised tangent projections, sin(alpha) tan(beta) from the table."""
        # 1 / |projection|, floored: within 1e-6 rad of the normal, G fades to 0 with the
        # projection (beta -> 0 there) instead of becoming 0/0, and its derivative stays finite
        inv_si = dr.rsqrt(dr.maximum(wi.x * wi.x + wi.y * wi.y, 1e-12))
        inv_so = dr.rsqrt(dr.maximum(wo.x * wo.x + wo.y * wo.y, 1e-12))
        g = dr.minimum(dr.maximum(wi.x * wo.x + wi.y * wo.y, 0) * inv_si * inv_so, 1)
        t = self.lut.eval(mi.Point2f(cos_theta(wo), cos_theta(wi)))[0]
        return g * t

    # -- the diffuse lobe ----------------------------------------------------------------------

    def _diffuse_f(self, p, wi, wo):
        # a load-time choice: the table or the closed form
        retro = self._retro_analytic(wi, wo) if self.lut is None else self._retro_lut(wi, wo)
        return lambert_f(p.rho, wo) * (p.a + p.b * retro)

    # -- albedo AOV --------------------------------------------------------------------------

    def _diffuse_colour(self, p):
        return p.rho


#: what the generic tests, the property table, the catalog and the benchmarks run of this
#: plugin, EON's form included (``core.facts``)
FACTS = Facts(
    colour="reflectance",
    differentiable=("reflectance", "sigma"),
    non_default={"sigma": 0.4, "lut_resolution": 16},
    edges=(dict(sigma=1.5707963), dict(sigma=1.0, lut_resolution=16),
           dict(form="energy_preserving", roughness=1.0, reflectance=1.0),
           dict(form="energy_preserving", roughness=0.0, sampling="cosine")),
    float64=((dict(sigma=0.5), 1e-4), (dict(form="energy_preserving", roughness=0.5), 1e-4)),
    gradient_edges=(dict(sigma=0.0), dict(sigma=math.pi / 2),
                    dict(sigma=math.pi / 2, lut_resolution=16)),
    finite_difference=(dict(sigma=0.3), ("sigma",)),
    zero_lobes=(("reflectance", 0, 0.5, {}),),
    albedo=(({"reflectance": rgb(0.2, 0.5, 0.7), "sigma": 0.5}, [0.2, 0.5, 0.7]),),
    on_request=({"a": 0.8, "b": 0.2}, {"form": "energy_preserving"}),
    traced_options=({"lut_resolution": 16},),
    # (a rule on values, not on which parameters are given: sampling = cltc needs this form)
    companions={"sampling": {"form": "energy_preserving"}},
    properties=(
        ("sigma=0.3", {"reflectance": 1.0, "sigma": 0.3}),
        ("sigma=1.2", {"reflectance": 1.0, "sigma": 1.2}),
        ("sigma=1.2 lut=32", {"reflectance": 1.0, "sigma": 1.2, "lut_resolution": 32}),
        # the lecture's A and B given directly, off the sigma curve (A + B / 2 = 1: the
        # albedo reaches 1 at grazing incidence)
        ("a=0.7 b=0.6", {"reflectance": 1.0, "a": 0.7, "b": 0.6}),
        # EON: albedo 1 at every roughness; its own sampler and the cosine baseline
        ("energy_preserving r=0.5", {"reflectance": 1.0, "form": "energy_preserving",
                                     "roughness": 0.5}),
        ("energy_preserving r=1", {"reflectance": 1.0, "form": "energy_preserving",
                                   "roughness": 1.0}),
        ("energy_preserving r=1 cosine", {"reflectance": 1.0, "form": "energy_preserving",
                                          "roughness": 1.0, "sampling": "cosine"}),
    ),
    catalog=(
        ("sigma=0.5", {"reflectance": RED, "sigma": 0.5}),
        ("a=0.6 b=0.4", {"reflectance": RED, "a": 0.6, "b": 0.4}),
        ("energy_preserving r=1", {"form": "energy_preserving", "reflectance": RED,
                                   "roughness": 1.0}),
    ),
    cpp=(("", {"reflectance": 0.5, "sigma": 0.3}, {"type": "diffuse", "reflectance": 0.5},
          "Mitsuba 3 has no Oren-Nayar plugin; `diffuse` has the same (cosine) sampling and "
          "a simpler eval"),),
    cases=tuple((dict(reflectance=rgb(0.9, 0.5, 0.2), sigma=s), 2e-5)
                for s in (0.0, 0.1, 0.3, 1.0, SIGMA_MAX))
    + ((dict(reflectance=rgb(0.3, 0.6, 0.9), a=0.7, b=0.4), 2e-5),)
    + tuple((dict(reflectance=rgb(0.9, 0.5, 0.2), form="energy_preserving", roughness=r,
                  sampling=s), 5e-5)
            for r, s in ((0.0, "cltc"), (0.1, "cosine"), (0.5, "cltc"), (1.0, "cltc"))),
    chi2=tuple((f"sigma={s:.2f}-lut={n}", {"sigma": s, "lut_resolution": n}, t, 8)
               for s, t, n in ((0.3, 0, 0), (1.0, 45, 0), (SIGMA_MAX, 80, 0),
                               (SIGMA_MAX, 89.5, 0), (1.0, 70, 32)))
    + tuple((f"eon-r={r}-{s}", {"form": "energy_preserving", "roughness": r, "sampling": s}, t, 8)
            for r, t, s in ((0.1, 0, "cltc"), (0.5, 45, "cltc"), (1.0, 70, "cltc"),
                            (1.0, 89.5, "cltc"), (0.25, 85, "cltc"), (1.0, 60, "cosine"))),
    stability=({"reflectance": (1.0,), "sigma": (0.0, SIGMA_MAX), "lut_resolution": (0, 2, 16)},
               {"reflectance": (1.0,), "form": ("energy_preserving",),
                "roughness": (0.0, 1e-4, 0.5, 1.0), "sampling": ("cltc", "cosine")}),
    renders=(("sigma=1", {"sigma": 1.0}), ("sigma=1 lut=32", {"sigma": 1.0, "lut_resolution": 32}),
             ("eon r=1 cltc", {"form": "energy_preserving", "roughness": 1.0}),
             ("eon r=1 cosine", {"form": "energy_preserving", "roughness": 1.0,
                                 "sampling": "cosine"})),
)
