"""The blinn_phong plugin: the Phong-family suite (phong_family.py) with its own reference,
plus its normalisation."""
import mitsuba as mi
import numpy as np
import pytest

from checks import (CORNERS, CORNERS_FINE, albedo, check_chi2, check_eval, check_eval_pdf_finite,
                    check_refused, check_sample_weight_is_eval_over_pdf, check_samples_finite,
                    check_xml_refused, corner_samples, eval_np, hard_directions, hard_pairs,
                    load_xml, mirror_pairs, unit_f32)
from checks import random_upper, sph
from phong_family import FORMS, PhongFamilySuite
from reference import akyuz_normalization, lobe_integral, normalization
from reference import blinn_phong as blinn_phong_reference


class TestBlinnPhong(PhongFamilySuite):
    PLUGIN = "blinn_phong"
    reference = staticmethod(blinn_phong_reference)

    @staticmethod
    def exponent_of(alpha):
        """Walter et al. 2007: the half-vector lobe of Beckmann roughness alpha."""
        return 2 / alpha ** 2 - 2

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

    # -- normalization = approximate: Akyuz's (p + 8) / (8 pi) --------------------------------

    def load_approx(self, **kw):
        return self.load(form="normalized", normalization="approximate", **kw)

    @pytest.mark.parametrize("p", [0.0, 1.0, 30.0, 1000.0])
    def test_approximate_matches_akyuz(self, p):
        wi, wo = mirror_pairs(3000, seed=8, mirrors=100)
        wi32, wo32 = unit_f32(wi), unit_f32(wo)
        kd, ks = [0.5, 0.3, 0.1], [0.2, 0.4, 0.3]
        spec, diff = blinn_phong_reference(wi32, wo32, kd, ks, p, "normalized", approximate=True)
        b = self.load_approx(diffuse_reflectance=kd, specular_reflectance=ks, exponent=p)
        check_eval(b, wi, wo, (spec + diff) * wo32[:, 2:3], rtol=5e-4)
        assert "normalization = approximate" in str(b)

    @pytest.mark.parametrize("p", [1.0, 10.0, 100.0])
    def test_approximate_albedo_exceeds_one_as_documented(self, p):
        """White furnace at normal incidence: the specular albedo is the ratio of the two
        factors, 1.024 / 1.075 / 1.018 at p = 1 / 10 / 100 (above 1: not energy
        conserving), while the exact factor gives 1."""
        a, err = albedo(self.load_approx(diffuse_reflectance=0.0, specular_reflectance=1.0,
                                         exponent=p), 0)
        want = akyuz_normalization(p) / normalization(p)
        np.testing.assert_allclose(a, want, rtol=4 * err.max() + 2e-3)
        assert want > 1.015
        exact, err = albedo(self.load(diffuse_reflectance=0.0, specular_reflectance=1.0,
                                      exponent=p), 0)
        np.testing.assert_allclose(exact, 1, atol=4 * err.max() + 2e-3)

    @pytest.mark.parametrize("theta", [0, 60, 89])
    def test_approximate_sampling(self, theta):
        """Same sampler; the lobe choice follows the approximate factor's albedo estimate."""
        check_chi2(self.PLUGIN, dict(form="normalized", normalization="approximate",
                                     specular_reflectance=0.5, diffuse_reflectance=0.5,
                                     exponent=20.0), theta, res=161, ires=16)
        b = self.load_approx(diffuse_reflectance=0.4, specular_reflectance=0.6, exponent=10.0)
        check_sample_weight_is_eval_over_pdf(b, sph(np.radians(theta), 1.0)[0], min_valid=0.2,
                                             pdf_rtol=1e-5, weight_rtol=1e-4, weight_atol=1e-7,
                                             unit_wo=True)

    def test_approximate_stability_grid(self):
        d = hard_directions()
        wi, wo = hard_pairs(d, mirrored=10)
        samples = corner_samples(d, CORNERS_FINE, CORNERS)
        for ks, kd in [(1.0, 0.0), (1.0, 1.0)]:
            for p in [0.0, 1e-3, 1.0, 1e4, 1e6]:
                b = self.load_approx(specular_reflectance=ks, diffuse_reflectance=kd, exponent=p)
                tag = f"p={p} ks={ks} kd={kd}"
                check_eval_pdf_finite(b, mi.BSDFContext(), wi, wo, tag)
                check_samples_finite(b, mi.BSDFContext(), samples, tag)

    def test_bad_normalization(self):
        check_refused(self.PLUGIN, {"normalization": "approx"},
                      r"blinn_phong: parameter 'normalization' must be one of 'exact', "
                      r"'approximate' \(got 'approx'\)")
        for form in ("original", "modified"):
            check_refused(self.PLUGIN, {"form": form, "normalization": "exact"},
                          r"blinn_phong: parameter 'normalization' must be given only with form "
                          r"'normalized' \(the other forms have no normalisation factor\) "
                          rf"\(got form '{form}'\)")
        check_xml_refused(self.PLUGIN, '<string name="normalization" value="akyuz"/>',
                          r"parameter 'normalization' must be one of")
        b = load_xml(self.PLUGIN, '<string name="normalization" value="approximate"/>')
        assert "normalization = approximate" in str(b)
