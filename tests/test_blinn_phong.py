"""The blinn_phong plugin: the Phong-family suite (see test_phong.py) with its own reference,
plus its normalisation."""
import functools

import numpy as np
import pytest
from scipy.integrate import quad

from checks import colour, eval_np, unit_f32
from conftest import random_upper, sph
from test_phong import FORMS, PhongFamilySuite


@functools.lru_cache(maxsize=None)
def lobe_integral(p, with_cos):
    """Integral over l of cos^p(alpha_h) [cos(theta_l)] at v = n, by quadrature: there
    alpha_h = theta_l / 2."""
    def integrand(t):
        return np.cos(t / 2) ** p * (np.cos(t) if with_cos else 1.0) * 2 * np.pi * np.sin(t)
    return quad(integrand, 0, np.pi / 2, epsabs=0, epsrel=1e-12, limit=200)[0]


def normalization(p):
    """Eq. 4 at normal incidence: the factor that makes the specular albedo 1 there."""
    return 1 / lobe_integral(float(p), True)


def blinn_phong_reference(wi, wo, kd, ks, p, form):
    """Akyuz eq. 6-9 with l = wo (light), v = wi (viewer): (specular f, diffuse f).

    The normalized form's factor is the exact normalisation (by quadrature), not eq. 9's
    approximation (p + 8) / (8 pi) (documented in the plugin)."""
    l, v = np.asarray(wo, float), np.asarray(wi, float)
    h = l + v
    h /= np.linalg.norm(h, axis=1, keepdims=True)                        # eq. 6
    lobe = np.clip(h[:, 2], 0, None) ** p                                 # cos^p(alpha_h)
    scale = {"original": 1 / l[:, 2], "modified": np.ones(len(l)),
             "normalized": np.full(len(l), normalization(p))}[form]
    spec = colour(ks) * (lobe * scale)[:, None]
    diff = colour(kd) / np.pi * np.ones((len(l), 1))
    return spec, diff


class TestBlinnPhong(PhongFamilySuite):
    PLUGIN = "blinn_phong"
    reference = staticmethod(blinn_phong_reference)

    @staticmethod
    def specular_albedo_at_normal(form, p):
        return {"original": lobe_integral(p, False), "modified": lobe_integral(p, True),
                "normalized": 1.0}[form]

    @staticmethod
    def sharp_albedo(theta):
        # a narrow half-vector lobe: N(p) * 4 cos(theta) * 2 pi / (p + 1) * cos(theta) -> cos^2
        return np.cos(theta) ** 2

    @pytest.mark.parametrize("p", [0.0, 0.5, 1.0, 4.0, 10.0, 30.0, 100.0, 1e3, 1e4])
    def test_normalization_is_exact_and_close_to_akyuz(self, p):
        """The normalized peak (h = n) is ks N(p) cos(theta_l) with N(p) from eq. 4; Akyuz's
        (p + 8) / (8 pi) would exceed it by up to 8% (an albedo above 1)."""
        b = self.load(form="normalized", diffuse_reflectance=0.0, specular_reflectance=1.0,
                      exponent=p)
        wi = sph(np.radians(35), 0.4)
        wo = wi * [-1, -1, 1]
        n_plugin = eval_np(b, wi, wo)[0, 0] / wo[0, 2]
        np.testing.assert_allclose(n_plugin, normalization(p), rtol=2e-5)
        ratio = (p + 8) / (8 * np.pi) / n_plugin
        assert 1 - 1e-6 <= ratio < 1.08, ratio
        if 0.5 <= p <= 1e3:
            assert ratio > 1.001  # the approximation overshoots, hence the exact factor

    @pytest.mark.parametrize("form", FORMS)
    def test_lobe_depends_on_the_half_vector_only(self, form):
        """f cos(theta_l) / factor is cos^p of the angle between h and n: pairs of
        directions with the same half vector give the same lobe value."""
        b = self.load(form=form, diffuse_reflectance=0.0, exponent=40.0)
        rng = np.random.default_rng(21)
        h = unit_f32(sph(np.radians(10), rng.uniform(0, 2 * np.pi, 200)))
        v = random_upper(rng, 200)
        v = v[np.sum(v * h, axis=1) > 0.3]
        h = h[: len(v)]
        l = 2 * np.sum(v * h, axis=1, keepdims=True) * h - v
        keep = l[:, 2] > 0.05
        v, l = v[keep], l[keep]
        f = eval_np(b, v, l)[:, 0]
        lobe = {"original": f, "modified": f / l[:, 2],
                "normalized": f / l[:, 2] / normalization(40.0)}[form] / 0.2
        np.testing.assert_allclose(lobe, np.cos(np.radians(10)) ** 40, rtol=2e-3)
