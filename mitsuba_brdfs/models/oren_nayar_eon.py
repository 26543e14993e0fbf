"""EON, the energy-preserving Oren-Nayar model: ``oren_nayar`` with ``form = energy_preserving``.

Reference: J. Portsmouth, P. Kutz, S. Hill, "EON: A Practical Energy-Preserving Rough
Diffuse BRDF", JCGT 14(1), 2025, which builds on Y. Fujii's improved Oren-Nayar model (FON).

One plugin, two models: the plugin ``oren_nayar`` builds ``OrenNayar`` (the lecture's
qualitative model, ``models/oren_nayar.py``) by default and this module's ``OrenNayarEON``
when the scene gives ``form = energy_preserving``. The parameters, equations, numerics and
measured accuracy of both forms are documented together in the plugin's docstring (the
manual's page of ``oren_nayar``); here are the model and its math: FON's single scattering
term and directional albedo (``fon_g``), EON's multiple scattering lobe (``eon_f``) and
its sampling, a clipped linearly transformed cosine mixed with uniform hemisphere samples
(``eon_sample``, ``eon_pdf``; the warp itself is ``core.warp.square_to_clipped_ltc``).
"""
import math

import drjit as dr
import mitsuba as mi

from ..core.frame import cos_theta
from ..core.lobes import Point, TwoLobeModel
from ..core.numerics import safe_div
from ..core.registry import bsdf_plugin
from ..core.warp import clipped_ltc_pdf, square_to_clipped_ltc
from .oren_nayar import FORMS, PARAMETER_RELATIONS, SAMPLING

__all__ = ["OrenNayarEON", "C1", "C2", "fon_g", "eon_f", "eon_sample", "eon_pdf"]

#: FON's A = 1 / (1 + C1 r) and its average albedo A (1 + C2 r)
C1 = 0.5 - 2 / (3 * math.pi)
C2 = 2 / 3 - 28 / (15 * math.pi)


def fon_g(mu):
    """G(mu) of FON's directional albedo E(mu) = A (1 + r G(mu) / pi):
    G = S (theta - S mu) + 2/3 (S mu (1 + S + S^2) / (1 + S) - S), S = sin(theta), mu =
    cos(theta): the paper's (S / mu)(1 - S^3) rewritten without cancellation (1 - S =
    mu^2 / (1 + S)), and theta = atan2(S, mu), whose derivative stays finite at mu = 1."""
    mu = dr.clip(mu, 0, 1)
    sn = dr.safe_sqrt(1 - mu * mu)
    return (sn * (dr.atan2(sn, mu) - sn * mu)
            + (2 / 3) * (sn * mu * (1 + sn + sn * sn) / (1 + sn) - sn))


def eon_f(rho, r, wi, wo):
    """EON's f cos(theta_o) (single scattering FON + multiple scattering lobe), see above."""
    mu_i, mu_o = cos_theta(wi), cos_theta(wo)
    s = wi.x * wo.x + wi.y * wo.y                    # omega_i . omega_o - mu_i mu_o
    s_over_t = dr.select(s > 0, safe_div(s, dr.maximum(mu_i, mu_o)), s)
    a = 1 / (1 + C1 * r)
    # 1 + r s >= 0 for unit directions (|s| <= 1); float32 directions are unit only to ~6e-8,
    # and nearly opposite grazing ones would take it a hair below 0
    single = a * dr.maximum(1 + r * s_over_t, 0)
    # 1 - E(mu) = A r (C1 - G / pi) and 1 - E_avg = A r (C1 - C2): no cancellation, exact 0 at r = 0
    # (E <= 1: the factors are >= 0, clamped where float32 rounding at grazing mu crosses 0)
    loss_o = dr.maximum(C1 - fon_g(mu_o) * dr.inv_pi, 0)
    loss_i = dr.maximum(C1 - fon_g(mu_i) * dr.inv_pi, 0)
    multi = a * r * loss_o * loss_i / (C1 - C2)
    rho_ms = rho * rho * (a * (1 + C2 * r)) / (1 - rho * (a * r * (C1 - C2)))
    return (rho * single + rho_ms * multi) * (dr.inv_pi * mu_o)


def _eon_ltc(mu, r):
    """Matrix (a, b, c, d) of EON's clipped LTC at mu = cos(theta_i) (the paper's fit)."""
    a = 1 + r * (0.303392 + (-0.518982 + 0.111709 * mu) * mu + (-0.276266 + 0.335918 * mu) * r)
    b = r * (-1.16407 + 1.15859 * mu + (0.150815 - 0.150105 * mu) * r) / (mu * mu * mu - 1.43545)
    c = 1 + (0.20013 + (-0.506373 + 0.261777 * mu) * mu) * r
    d = ((0.540852 + (-1.01625 + 0.475392 * mu) * mu) * r) / (-1.0743 + mu * (0.0725628 + mu))
    return a, b, c, d


def _eon_uniform_share(mu, r):
    """Share of uniform hemisphere samples in EON's sampling mixture (the paper's fit);
    r^0.1 as exp(0.1 log r), 0 at r = 0 with a finite derivative."""
    rp = dr.select(r > 0, dr.exp(0.1 * dr.log(dr.maximum(r, 1e-30))), 0)
    return dr.clip(rp * (0.162925 + mu * (-0.372058 + (0.538233 - 0.290822 * mu) * mu)), 0, 1)


def eon_sample(wi, r, u):
    """EON's sampling: the clipped LTC, mixed with a uniform share for the flat tail."""
    mu = dr.clip(cos_theta(wi), 0, 1)
    pu = _eon_uniform_share(mu, r)
    uniform = u.x < pu
    # u.x rescaled inside the chosen branch keeps the sample stratified
    ux = dr.select(uniform, safe_div(u.x, pu), safe_div(u.x - pu, 1 - pu))
    u2 = mi.Point2f(dr.minimum(ux, 1 - 2.0 ** -24), u.y)
    return dr.select(uniform, mi.warp.square_to_uniform_hemisphere(u2),
                     square_to_clipped_ltc(u2, wi, *_eon_ltc(mu, r)))


def eon_pdf(wi, wo, r):
    mu = dr.clip(cos_theta(wi), 0, 1)
    pu = _eon_uniform_share(mu, r)
    return (pu * mi.warp.square_to_uniform_hemisphere_pdf(wo)
            + (1 - pu) * clipped_ltc_pdf(wo, wi, *_eon_ltc(mu, r)))


class _At(Point):
    """Parameter values at one shading point: rho and EON's roughness r."""
    __slots__ = ("rho", "r")


@bsdf_plugin("oren_nayar", form=("form", "energy_preserving"))
class OrenNayarEON(TwoLobeModel):
    """``oren_nayar`` with ``form = energy_preserving``: EON (see the module docstring)."""
    LOBES = (False, True)
    OPTIONS = {"form": FORMS, "sampling": SAMPLING}
    RELATIONS = PARAMETER_RELATIONS

    def _read_parameters(self, r):
        self.rho = r.reflectance("reflectance", 0.5)
        self.form = r.enum("form", "energy_preserving", FORMS)
        self.sampling = r.enum("sampling", "cltc", SAMPLING)
        self.roughness = r.scalar("roughness", 0.25, 0.0, 1.0, what="an EON roughness")
        self.cosine_only = self.sampling == "cosine"

    def _textures(self):
        return {"reflectance": self.rho, "roughness": self.roughness}

    def _options(self):
        return {"form": self.form, "sampling": self.sampling}

    def _lobes_present(self):
        return False, not self._is_constant(self.rho, 0.0)

    def _at(self, si, active):
        return _At(rho=self.rho.eval(si, active), r=self.roughness.eval_1(si, active))

    # -- the diffuse lobe ----------------------------------------------------------------------

    def _diffuse_f(self, p, wi, wo):
        return eon_f(p.rho, p.r, wi, wo)

    # EON's own sampler (reached only with sampling = cltc: cosine is ``cosine_only``)

    def _diffuse_sample(self, p, wi, u):
        return eon_sample(wi, p.r, u)

    def _diffuse_pdf(self, p, wi, wo):
        return eon_pdf(wi, wo, p.r)

    # -- albedo AOV --------------------------------------------------------------------------

    def _diffuse_colour(self, p):
        return p.rho
