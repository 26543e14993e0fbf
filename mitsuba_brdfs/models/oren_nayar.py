"""Oren-Nayar rough diffuse reflection (``oren_nayar``).

References: the lecture "BRDF models" (Politecnico di Milano), section Oren-Nayar;
M. Oren, S. K. Nayar, "Generalization of Lambert's Reflectance Model", SIGGRAPH 1994
(the lecture's formulas are that paper's qualitative model).

Parameters
----------
===================  ================  =================================================
``reflectance``      spectrum/texture  rho, the diffuse colour m_D, in [0, 1].
                                       Exposed, differentiable. (Default: 0.5)
``sigma``            float/texture     roughness: standard deviation of the facet slope
                                       angle, in radians, in [0, pi/2]. 0 is Lambert.
                                       Exposed, differentiable. (Default: 0.3)
``lut_resolution``   integer           0: evaluate f(p, q) = B sin(alpha) tan(beta)
                                       analytically; N in [2, 4096]: look it up in the
                                       lecture's precomputed N x N table with bilinear
                                       interpolation (see below). (Default: 0)
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
(A + B G sin(alpha) tan(beta)), without 1/pi; MODELS.md normalises all diffuse terms to
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

Energy: the qualitative model does not conserve energy exactly. Its albedo is at most 1
for sigma >= 0.35 at every incidence and for every sigma up to 60 degrees of incidence,
but exceeds 1 slightly at grazing incidence for smaller sigma (at most 1.015, sigma ~ 0.2,
theta = 90 degrees). That is a property of the lecture's formula, not of this code: the
tests compare the albedo with a float64 quadrature of the formula.

Sampling: cosine-weighted (pdf cos(theta)/pi), weight eval / pdf. The model is reciprocal.

Lobes: one diffuse reflection component (index 0); a constant black reflectance does no
work (nothing sampled or traced) until an update or a gradient brings it back.

Albedo AOV (``eval_diffuse_reflectance``, the ``aov`` integrator's ``albedo``): rho, the
colour the roughness term modulates (as for ``lambert``).

XML::

    <bsdf type="oren_nayar">
        <rgb name="reflectance" value="0.7, 0.4, 0.3"/>
        <float name="sigma" value="0.5"/>
        <integer name="lut_resolution" value="0"/>
    </bsdf>

Python: ``mi.load_dict({'type': 'oren_nayar', 'sigma': 0.5})``
"""
import math

import drjit as dr
import mitsuba as mi

from ..core.frame import cos_theta
from ..core.lobes import TwoLobeModel, lambert_f
from ..core.numerics import safe_div
from ..core.params import ParameterError, float32, is_constant_zero
from ..core.plugin import bsdf_plugin

__all__ = ["OrenNayar", "oren_nayar_ab", "sin_alpha_tan_beta_table"]

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


class _At:
    """Parameter values at one shading point."""
    __slots__ = ("rho", "a", "b")


@bsdf_plugin("oren_nayar")
class OrenNayar(TwoLobeModel):
    LOBES = (False, True)

    def _read_parameters(self, r):
        self.rho = r.reflectance("reflectance", 0.5)
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
        self.lut = None
        if n > 0:
            self.lut = mi.Texture2f(sin_alpha_tan_beta_table(n), use_accel=False,
                                    filter_mode=dr.FilterMode.Linear,
                                    wrap_mode=dr.WrapMode.Clamp)

    def _textures(self):
        return {"reflectance": self.rho, "sigma": self.sigma}

    def _options(self):
        return {"lut_resolution": self.lut_resolution}

    def _lobes_present(self):
        return False, not is_constant_zero(self.rho)

    def _at(self, si, active):
        p = _At()
        p.rho = self.rho.eval(si, active)
        p.a, p.b = oren_nayar_ab(self.sigma.eval_1(si, active))
        return p

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
        # a load-time choice (a Python branch): the kernel holds one of the two forms
        retro = self._retro_analytic(wi, wo) if self.lut is None else self._retro_lut(wi, wo)
        return lambert_f(p.rho, wo) * (p.a + p.b * retro)

    # -- albedo AOV --------------------------------------------------------------------------

    def _diffuse_colour(self, p):
        return p.rho
