"""The tests the two Phong-family models (phong, blinn_phong) share: eval, pdf, sampling,
energy, reciprocity, lobes, parameters, renders, for every form.

A model's test class (``TestPhong`` in test_phong.py, ``TestBlinnPhong`` in
test_blinn_phong.py) derives from ``PhongFamilySuite``, sets ``PLUGIN`` and ``reference``
(its float64 transcription in reference.py) and adds the tests of its own. This module's
name does not start with ``test_`` and the suite's not with ``Test``: pytest collects the
suite only through those subclasses.
"""

import mitsuba as mi
import numpy as np
import pytest

from checks import (working_lobes, CORNERS, CORNERS_FINE, albedo, check_albedo_at_most_one, check_chi2,
                    check_context_selects_lobes, check_eval, check_eval_pdf_finite,
                    check_finite_gradients, pdf_np,
                    check_glossy_and_diffuse_lobes, check_render,
                    check_sample_weight_is_eval_over_pdf, check_samples_finite,
                    check_update_changes_lobes, check_update_changes_render, check_zero_below_horizon, corner_samples, eval_left_right,
                    eval_np, hard_directions, hard_pairs, load_bsdf, load_xml, mirror_pairs, param_key,
                    random_pairs, unit_f32, write_halves)
from checks import sample_bsdf, small_scene, sph, to_np
from checks import half_width_at_normal_incidence, roughconductor_half_width

FORMS = ["original", "modified", "normalized"]


class PhongFamilySuite:
    PLUGIN = None
    #: (wi, wo, kd, ks, p, form) -> (specular f, diffuse f), float64, without the cosine
    reference = None

    def ref(self, wi, wo, kd, ks, p, form):
        return type(self).reference(wi, wo, kd, ks, p, form)

    def load(self, **kw):
        return load_bsdf(self.PLUGIN, **kw)

    def bsdf_of(self, prm, form, **extra):
        return self.load(diffuse_reflectance=prm["kd"], specular_reflectance=prm["ks"],
                         exponent=prm["p"], form=form, **extra)

    # -- eval against the float64 transcription ----------------------------------------------

    @pytest.mark.parametrize("form", FORMS)
    def test_below_horizon_and_backfacing_is_zero(self, form):
        check_zero_below_horizon(self.load(form=form, exponent=0.0))

    # -- reciprocity -------------------------------------------------------------------------

    @pytest.mark.parametrize("form", FORMS)
    def test_importance_transport_swaps_roles(self, form):
        """Under TransportMode.Importance wi is the light side: eval returns
        f(l = wi, v = wo) cos(theta_o); for the reciprocal forms that is the radiance value."""
        a, b = random_pairs(13, 2000)
        kd, ks = [0.3, 0.2, 0.1], [0.7, 0.6, 0.5]
        bsdf = self.load(form=form, exponent=10.0, diffuse_reflectance=kd, specular_reflectance=ks)
        ctx = mi.BSDFContext(mi.TransportMode.Importance)
        got = eval_np(bsdf, a, b, ctx)
        a32, b32 = unit_f32(a), unit_f32(b)
        spec, diff = self.ref(b32, a32, kd, ks, 10.0, form)  # viewer b, light a
        want = (spec + diff) * b32[:, 2:3]
        np.testing.assert_allclose(got, want, rtol=2e-3, atol=1e-6 * want.max())
        if form != "original":
            np.testing.assert_allclose(got, eval_np(bsdf, a, b), rtol=1e-5, atol=1e-7)

    # -- sampling ----------------------------------------------------------------------------

    # -- energy --------------------------------------------------------------------------------

    @pytest.mark.parametrize("theta", [0, 30, 60, 80, 89])
    def test_white_furnace_normalized(self, theta):
        """The normalized form conserves energy: albedo <= 1 when kd + ks <= 1."""
        for kd, ks, p in [(0.0, 1.0, 0.0), (0.0, 1.0, 1.0), (0.0, 1.0, 10.0), (0.0, 1.0, 30.0),
                          (0.0, 1.0, 1e4), (0.5, 0.5, 3.0), (0.9, 0.1, 100.0), (1.0, 0.0, 1.0)]:
            b = self.load(form="normalized", diffuse_reflectance=kd, specular_reflectance=ks,
                          exponent=p)
            a, err = albedo(b, theta)
            check_albedo_at_most_one(a, err, (kd, ks, p))
            if theta == 0 and kd == 0.0:  # the normalisation is exact at normal incidence
                np.testing.assert_allclose(a, 1, atol=4 * err.max() + 2e-3)

    @pytest.mark.parametrize("form", FORMS)
    @pytest.mark.parametrize("p", [0.0, 1.0, 10.0, 100.0])
    def test_specular_albedo_at_normal_incidence(self, form, p):
        """The documented lobe integrals: ks times them is the specular albedo at theta = 0;
        the original and modified forms exceed 1 for broad lobes (not energy conserving)."""
        b = self.load(form=form, diffuse_reflectance=0.0, specular_reflectance=1.0, exponent=p)
        a, err = albedo(b, 0)
        want = self.specular_albedo_at_normal(form, p)
        np.testing.assert_allclose(a, want, rtol=4 * err.max() / want + 2e-3)
        if form != "normalized" and p <= 1:
            assert a.min() > 1.5

    @staticmethod
    def specular_albedo_at_normal(form, p):
        raise NotImplementedError

    # -- flags, components, contexts ---------------------------------------------------------

    @pytest.mark.parametrize("form", FORMS)
    def test_flags_and_components(self, form):
        b = self.load(form=form)
        check_glossy_and_diffuse_lobes(b)
        metal = self.load(form=form, diffuse_reflectance=0.0)
        assert working_lobes(metal) == 1 and metal.flags() == b.flags()
        matte = self.load(form=form, specular_reflectance=0.0)
        assert working_lobes(matte) == 1 and matte.flags() == b.flags()
        black = self.load(form=form, specular_reflectance=0.0, diffuse_reflectance=0.0)
        assert working_lobes(black) == 0 and black.flags() == b.flags()
        _, (bs, w) = sample_bsdf(black, [0, 0, 1], 100)
        assert (to_np(w) == 0).all()
        assert working_lobes(self.load(form=form, diffuse_reflectance=1e-6)) == 2
        # a matte surface never samples the (absent) glossy lobe, a metal never the diffuse
        _, (bs, _) = sample_bsdf(matte, [0.3, 0, 0.954], 2000)
        assert (to_np(bs.sampled_type) == +b.flags(1)).all()
        assert (to_np(bs.sampled_component) == 1).all()  # indices stay: glossy 0, diffuse 1
        _, (bs, _) = sample_bsdf(metal, [0.3, 0, 0.954], 2000)
        assert (to_np(bs.sampled_type) == +b.flags(0)).all()
        assert f"form = {form}" in str(b) and "exponent" in str(b)

    @pytest.mark.parametrize("form", FORMS)
    def test_context_selects_lobes(self, form):
        kd, ks, p = [0.6, 0.5, 0.4], [0.3, 0.3, 0.3], 20.0
        b = self.load(form=form, diffuse_reflectance=kd, specular_reflectance=ks, exponent=p)
        wi, wo = random_pairs(5, 500)
        spec, diff = self.ref(unit_f32(wi), unit_f32(wo), kd, ks, p, form)
        # with lobe_pdf, a sample's pdf is the selected lobe's alone
        check_context_selects_lobes(b, wi, wo, spec, diff, rtol=2e-3, atol=1e-6, lobe_pdf=True)

    # -- textures and parameters ---------------------------------------------------------------

    def test_spatially_varying_exponent(self, tmp_path):
        """A bitmap exponent is looked up at the shading point's uv."""
        b = mi.load_dict({"type": self.PLUGIN, "diffuse_reflectance": 0.0,
                          "exponent": write_halves(tmp_path / "p.exr", 10.0, 1000.0)})
        wi = sph(np.radians(20), 0.0)
        wo = sph(np.radians(22), np.pi)
        f = eval_left_right(b, wi, wo)
        for i, p in enumerate((10.0, 1000.0)):
            ref = eval_np(self.load(diffuse_reflectance=0.0, exponent=p), wi, wo)
            np.testing.assert_allclose(f[i], ref[0], rtol=1e-5)
        assert abs(f[0, 0] - f[1, 0]) > 0.1 * f.max()  # the two halves differ

    def test_parameters_from_xml(self):
        b = load_xml(self.PLUGIN, '<string name="form" value="original"/><float name="exponent" value="12"/>')
        assert b.RECIPROCAL is False and "original" in str(b)

    # -- hard cases stay finite -----------------------------------------------------------------

    def test_sharp_lobe_is_not_lost_to_rounding(self):
        """At p = 1e6 (lobe ~1e-3 rad wide) the normalized lobe keeps its albedo and the
        samples spread around the mirror direction instead of collapsing onto it."""
        b = self.load(form="normalized", specular_reflectance=1.0, diffuse_reflectance=0.0,
                      exponent=1e6)
        a, err = albedo(b, 30, n=100_000)
        np.testing.assert_allclose(a, self.sharp_albedo(np.radians(30)), rtol=0.01)
        _, (bs, _) = sample_bsdf(b, sph(np.radians(30), 0.0)[0], 100_000)
        spread = np.degrees(np.arccos(np.clip(to_np(bs.wo) @ sph(np.radians(30), np.pi)[0], -1, 1)))
        assert 0 < np.median(spread) < 0.2

    # -- roughness instead of the exponent ------------------------------------------------------

    @pytest.mark.parametrize("form", FORMS)
    def test_alpha_sets_the_exponent(self, form):
        """alpha gives exactly the lobe of the exponent it maps to (float64 mapping)."""
        wi, wo = mirror_pairs(2000, seed=9, mirrors=100)
        wi32, wo32 = unit_f32(wi), unit_f32(wo)
        for alpha in (1e-2, 0.1, 0.5, 1.0):
            p = self.exponent_of(alpha)
            kd, ks = [0.3, 0.2, 0.1], [0.5, 0.4, 0.3]
            spec, diff = self.ref(wi32, wo32, kd, ks, p, form)
            b = self.load(form=form, alpha=alpha, diffuse_reflectance=kd, specular_reflectance=ks)
            check_eval(b, wi, wo, (spec + diff) * wo32[:, 2:3], rtol=5e-4)
            np.testing.assert_allclose(pdf_np(b, wi, wo), pdf_np(self.bsdf_of(
                dict(kd=kd, ks=ks, p=p), form), wi, wo), rtol=1e-4, atol=1e-6)

    @pytest.mark.parametrize("alpha,rtol", [(0.02, 2e-3), (0.05, 6e-3), (0.1, 0.02), (0.2, 0.07)])
    def test_alpha_highlight_as_wide_as_roughconductor(self, alpha, rtol):
        """The point of the mapping: the same highlight width as Mitsuba's Beckmann
        roughconductor of that alpha (at normal incidence; a leading-order match, so a
        little narrower for rough lobes, as documented in core.roughness)."""
        w = half_width_at_normal_incidence(self.load(alpha=alpha, diffuse_reflectance=0.0))
        np.testing.assert_allclose(w, roughconductor_half_width(alpha), rtol=rtol)

    @pytest.mark.parametrize("theta", [0, 60, 89])
    def test_alpha_sampling_and_furnace(self, theta):
        check_chi2(self.PLUGIN, dict(alpha=0.2, specular_reflectance=0.6, diffuse_reflectance=0.3),
                   theta, res=161, ires=16)
        for alpha in (1.5e-3, 0.1, 1.0):
            b = self.load(alpha=alpha, diffuse_reflectance=0.0, specular_reflectance=1.0)
            check_sample_weight_is_eval_over_pdf(b, sph(np.radians(theta), 1.0)[0], min_valid=0.2,
                                                 pdf_rtol=1e-5, weight_rtol=1e-4, weight_atol=1e-7)
            a, err = albedo(b, theta, n=100_000)
            check_albedo_at_most_one(a, err, alpha)
            if theta == 0:  # the normalized form: 1 at normal incidence
                np.testing.assert_allclose(a, 1, atol=4 * err.max() + 2e-3)

    def test_alpha_stability_and_gradients(self):
        d = hard_directions()
        wi, wo = hard_pairs(d, mirrored=10)
        samples = corner_samples(d, CORNERS_FINE, CORNERS)
        for alpha in (1.5e-3, 1e-2, 0.5, 1.0):
            for form in FORMS:
                b = self.load(form=form, alpha=alpha, diffuse_reflectance=1.0, specular_reflectance=1.0)
                tag = f"{form} alpha={alpha}"
                check_eval_pdf_finite(b, mi.BSDFContext(), wi, wo, tag)
                check_samples_finite(b, mi.BSDFContext(), samples, tag)
            check_finite_gradients(b, wi, wo, keys=["alpha.value"])

    def test_alpha_traverse(self):
        b = self.load(alpha=0.3)
        keys = set(mi.traverse(b).keys())
        assert "alpha.value" in keys and "exponent.value" not in keys and "alpha" in str(b)
        scene = small_scene({"type": self.PLUGIN, "id": "mat", "alpha": 0.3}, res=16)
        params = mi.traverse(scene)
        check_update_changes_render(scene, params, param_key(params, "alpha.value"), 0.05)
        check_render({"type": self.PLUGIN, "alpha": 0.1})

    # -- parameters through mi.traverse, renders -------------------------------------------

    def test_traverse_and_update(self):
        scene = small_scene({"type": self.PLUGIN, "id": "mat", "diffuse_reflectance": 0.0,
                             "form": "modified"}, res=16)
        params = mi.traverse(scene)
        check_update_changes_render(scene, params, param_key(params, "exponent.value"), 5.0)
        check_update_changes_lobes(scene, params, param_key(params, "diffuse_reflectance.value"), 0.5,
                                   before=1, after=2)

