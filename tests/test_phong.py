"""The phong plugin: the Phong-family suite (phong_family.py) with its own reference, plus
the tests of its mirror-direction lobe."""
import numpy as np

import reference
from checks import (eval_np, half_width_at_normal_incidence, roughconductor_half_width, sph,
                    unit)
from phong_family import PhongFamilySuite


# -- phong ------------------------------------------------------------------------------------

class TestPhong(PhongFamilySuite):
    PLUGIN = "phong"
    reference = staticmethod(reference.phong)

    @staticmethod
    def exponent_of(alpha):
        """The mirror lobe's Beckmann-equivalent exponent: a quarter of the half-vector one."""
        return (2 / alpha ** 2 - 2) / 4

    def test_half_vector_mapping_would_halve_the_highlight(self):
        """Why Phong takes a quarter of 2 / alpha^2 - 2: with the half-vector exponent its
        highlight is half as wide as roughconductor's."""
        w = half_width_at_normal_incidence(self.load(exponent=2 / 0.1 ** 2 - 2, diffuse_reflectance=0.0))
        np.testing.assert_allclose(w / roughconductor_half_width(0.1), 0.5, rtol=0.03)

    @staticmethod
    def specular_albedo_at_normal(form, p):
        """Integral of cos^p(alpha) (original), of cos^p(alpha) cos(theta_l) (modified), and
        1 (normalized) over the hemisphere, the lobe around n."""
        return {"original": 2 * np.pi / (p + 1), "modified": 2 * np.pi / (p + 2),
                "normalized": 1.0}[form]

    @staticmethod
    def sharp_albedo(theta):
        return np.cos(theta)  # a narrow lobe around the mirror direction, times cos(theta_l)

    def test_lobe_follows_the_mirror_direction(self):
        """The highlight is centred on the mirror direction of wi and rotationally symmetric
        around it (not around n)."""
        b = self.load(diffuse_reflectance=0.0, exponent=200.0)
        wi = sph(np.radians(50), 0.0)
        m = sph(np.radians(50), np.pi)[0]
        a = unit(np.cross(m, [0, 0, 1]))
        c = np.cross(m, a)
        phi = np.linspace(0, 2 * np.pi, 8, endpoint=False)[:, None]
        off = np.radians(3)
        ring = np.cos(off) * m + np.sin(off) * (np.cos(phi) * a + np.sin(phi) * c)
        f = eval_np(b, np.repeat(wi, len(ring), axis=0), ring)[:, 0] / ring[:, 2]
        peak = eval_np(b, wi, m)[0, 0] / m[2]
        np.testing.assert_allclose(f, f.mean(), rtol=1e-3)  # symmetric around the mirror axis
        np.testing.assert_allclose(f / peak, np.cos(off) ** 200, rtol=2e-3)
