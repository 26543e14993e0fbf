"""The phong plugin (and, through ``PhongFamilySuite``, blinn_phong): eval, pdf, sampling,
energy, reciprocity, lobes, parameters, renders, for every form.

``PhongFamilySuite`` holds the tests both models share; a model's test class sets
``PLUGIN`` and ``reference`` (an independent float64 NumPy transcription of the seed) and
adds the tests of its own. The suite's name does not start with ``Test``, so pytest collects
it only through those subclasses.
"""
import itertools

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

from conftest import interaction, random_upper, sample_bsdf, small_scene, sph, to_np, vec

FORMS = ["original", "modified", "normalized"]
F = mi.BSDFFlags


def unit(a):
    a = np.asarray(a, float)
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


def as_f32_unit(a):
    """The float32 directions the plugin sees, back in float64 (and renormalised)."""
    return unit(np.asarray(a, np.float32).astype(float))


def colour(c):
    return np.atleast_1d(np.asarray(c, float))[None, :]


def clamped_power(c, p):
    """clamp(c)^p, zero where c <= 0 (also for p = 0: the lobe ends at 90 degrees)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(c > 0, np.abs(c) ** p, 0.0)


def phong_reference(wi, wo, kd, ks, p, form):
    """Akyuz eq. 2, 3, 5 with l = wo (light), v = wi (viewer): (specular f, diffuse f).

    The diffuse term is kd / pi in every form (documented in the plugin)."""
    l, v = np.asarray(wo, float), np.asarray(wi, float)
    r = 2 * l[:, 2:3] * np.array([0, 0, 1.0]) - l             # mirror of l about n
    lobe = clamped_power(np.sum(r * v, axis=1), p)             # cos^p(alpha_r)
    scale = {"original": 1 / l[:, 2], "modified": np.ones(len(l)),
             "normalized": np.full(len(l), (p + 2) / (2 * np.pi))}[form]
    spec = colour(ks) * (lobe * scale)[:, None]
    diff = colour(kd) / np.pi * np.ones((len(l), 1))
    return spec, diff


def load(plugin, **kw):
    d = {"type": plugin}
    for k, v in kw.items():
        d[k] = {"type": "rgb", "value": v} if isinstance(v, (list, tuple)) else v
    return mi.load_dict(d)


def eval_np(bsdf, wi, wo, ctx=None):
    return to_np(bsdf.eval(ctx or mi.BSDFContext(), interaction(wi), vec(wo)))


def pdf_np(bsdf, wi, wo, ctx=None):
    return to_np(bsdf.pdf(ctx or mi.BSDFContext(), interaction(wi), vec(wo)))


def albedo(bsdf, theta, n=300_000, seed=0, ctx=None):
    """Monte Carlo directional albedo (mean sample weight) and its standard error."""
    wi = sph(np.radians(theta), 0.7)[0]
    _, (_, weight) = sample_bsdf(bsdf, wi, n, seed=seed, ctx=ctx)
    w = to_np(weight)
    return w.mean(axis=0), w.std(axis=0) / np.sqrt(n)


def hard_directions():
    eps = 1e-7
    g = np.sqrt(1 - eps * eps)
    d = np.array([
        [0, 0, 1],                                  # the normal (h = n with itself)
        [g, 0, eps], [0, g, eps], [-g, 0, eps],     # grazing, cos = 1e-7
        [1, 0, 0], [0, -1, 0],                      # exactly at the horizon
        [0.6, 0, 0.8], [-0.6, 0, 0.8],              # a mirror pair
        [0, 0.6, 0.8], [0, -0.6, 0.8],
        [0.3, 0.4, -np.sqrt(0.75)], [0, 0, -1],     # below the horizon
        [0.577, 0.577, 0.578],
    ], float)
    return unit(d)


def write_bitmap(path, value, res=4):
    arr = np.full((res, res, np.size(value)), value, dtype=np.float32)
    mi.Bitmap(arr).write(str(path))
    return str(path)


def bitmap(f):
    return {"type": "bitmap", "filename": f, "raw": True, "filter_type": "nearest"}


PARAMS = [
    dict(kd=[0.5, 0.5, 0.5], ks=[0.2, 0.2, 0.2], p=30.0),
    dict(kd=[0.7, 0.1, 0.3], ks=[0.2, 0.4, 0.1], p=1.0),
    dict(kd=[0.0, 0.0, 0.0], ks=[0.9, 0.6, 0.3], p=1000.0),
    dict(kd=[0.3, 0.3, 0.3], ks=[1.0, 1.0, 1.0], p=0.0),
    dict(kd=[1.0, 1.0, 1.0], ks=[0.0, 0.0, 0.0], p=5.0),
]

#: (name, settings, theta_i in degrees, ires); each runs for every form
CHI2 = [
    ("mixed_0", dict(specular_reflectance=0.5, diffuse_reflectance=0.5, exponent=30.0), 0, 16),
    ("mixed_45", dict(specular_reflectance=0.5, diffuse_reflectance=0.3, exponent=10.0), 45, 16),
    ("glossy_80", dict(specular_reflectance=0.8, diffuse_reflectance=0.0, exponent=100.0), 80, 32),
    ("mixed_89", dict(specular_reflectance=0.5, diffuse_reflectance=0.5, exponent=20.0), 89, 32),
    ("sharp_30", dict(specular_reflectance=1.0, diffuse_reflectance=0.0, exponent=1000.0), 30, 64),
    ("flat_60", dict(specular_reflectance=0.6, diffuse_reflectance=0.2, exponent=0.0), 60, 8),
]

RENDERS = {
    "mixed": dict(specular_reflectance=0.3, diffuse_reflectance=0.5, exponent=60.0),
    "sharp": dict(specular_reflectance=1.0, diffuse_reflectance=0.2, exponent=1e6),
    "flat": dict(specular_reflectance=0.2, diffuse_reflectance=0.3, exponent=0.0),
}

BAD = [
    ({"exponent": -1.0}, r"parameter 'exponent' must be a Phong exponent in \[0, inf\] \(got -1"),
    ({"exponent": float("nan")}, r"parameter 'exponent' .*\[0, inf\] \(got nan"),
    ({"exponent": float("inf")}, r"parameter 'exponent'"),
    ({"exponent": "abc"}, r"parameter 'exponent'"),
    ({"specular_reflectance": 1.5}, r"parameter 'specular_reflectance' must be a reflectance in \[0, 1\]"),
    ({"diffuse_reflectance": -0.1}, r"parameter 'diffuse_reflectance' must be a reflectance in \[0, 1\]"),
    ({"diffuse_reflectance": {"type": "rgb", "value": [0.2, 1.2, 0.3]}},
     r"parameter 'diffuse_reflectance' must be a reflectance in \[0, 1\]"),
    ({"specular_reflectance": float("nan")}, r"parameter 'specular_reflectance'"),
    ({"form": "blinn"}, r"parameter 'form' must be one of 'original', 'modified', 'normalized' "
                        r"\(got 'blinn'\)"),
    ({"form": 3.0}, r"parameter 'form' must be one of"),
]


class PhongFamilySuite:
    PLUGIN = None
    #: (wi, wo, kd, ks, p, form) -> (specular f, diffuse f), float64, without the cosine
    reference = None

    def ref(self, wi, wo, kd, ks, p, form):
        return type(self).reference(wi, wo, kd, ks, p, form)

    def load(self, **kw):
        return load(self.PLUGIN, **kw)

    def bsdf_of(self, prm, form, **extra):
        return self.load(diffuse_reflectance=prm["kd"], specular_reflectance=prm["ks"],
                         exponent=prm["p"], form=form, **extra)

    # -- eval against the float64 transcription ----------------------------------------------

    @pytest.mark.parametrize("form", FORMS)
    @pytest.mark.parametrize("prm", PARAMS, ids=[f"p={p['p']:g}" for p in PARAMS])
    def test_eval_matches_reference(self, prm, form):
        rng = np.random.default_rng(7)
        wi, wo = random_upper(rng, 4000), random_upper(rng, 4000)
        # exact mirror pairs (the Phong peak, h = n) and the normal
        wi = np.concatenate([wi, wi[:200], [[0, 0, 1]]])
        wo = np.concatenate([wo, wi[:200] * [-1, -1, 1], [[0, 0, 1]]])
        wi32, wo32 = as_f32_unit(wi), as_f32_unit(wo)
        spec, diff = self.ref(wi32, wo32, prm["kd"], prm["ks"], prm["p"], form)
        want = (spec + diff) * wo32[:, 2:3]
        got = eval_np(self.bsdf_of(prm, form), wi, wo)
        np.testing.assert_allclose(got, want, rtol=5e-4, atol=1e-6 * want.max())

    @pytest.mark.parametrize("form", FORMS)
    def test_below_horizon_and_backfacing_is_zero(self, form):
        b = self.load(form=form, exponent=0.0)
        wi = np.array([[0, 0, 1], [0.6, 0, -0.8], [0.6, 0, 0.8], [0, 0, 1], [1, 0, 0]])
        wo = np.array([[0.6, 0, -0.8], [0, 0, 1], [-0.6, 0, -0.8], [0, 0, -1], [-1, 0, 0]])
        assert (eval_np(b, wi, wo) == 0).all()
        assert (pdf_np(b, wi, wo) == 0).all()

    # -- reciprocity -------------------------------------------------------------------------

    @pytest.mark.parametrize("form", FORMS)
    def test_reciprocity(self, form):
        """f(a, b) = f(b, a) for the modified and normalized forms; the original form is
        not reciprocal (its 1 / cos(theta_l) singles out the light), and says so."""
        rng = np.random.default_rng(3)
        a, b = random_upper(rng, 3000), random_upper(rng, 3000)
        bsdf = self.load(form=form, exponent=10.0, diffuse_reflectance=0.3,
                         specular_reflectance=0.7)
        f_ab = eval_np(bsdf, a, b) / b[:, 2:3].astype(np.float32)
        f_ba = eval_np(bsdf, b, a) / a[:, 2:3].astype(np.float32)
        rel = np.abs(f_ab - f_ba) / np.maximum(np.abs(f_ab) + np.abs(f_ba), 1e-30)
        if form == "original":
            assert bsdf.RECIPROCAL is False
            assert rel.max() > 0.1, "the original form unexpectedly passes reciprocity"
            with pytest.raises(AssertionError):
                np.testing.assert_allclose(f_ab, f_ba, rtol=1e-3, atol=1e-6 * f_ab.max())
        else:
            assert bsdf.RECIPROCAL is True
            np.testing.assert_allclose(f_ab, f_ba, rtol=1e-3, atol=1e-6 * f_ab.max())

    @pytest.mark.parametrize("form", FORMS)
    def test_importance_transport_swaps_roles(self, form):
        """Under TransportMode.Importance wi is the light side: eval returns
        f(l = wi, v = wo) cos(theta_o); for the reciprocal forms that is the radiance value."""
        rng = np.random.default_rng(13)
        a, b = random_upper(rng, 2000), random_upper(rng, 2000)
        kd, ks = [0.3, 0.2, 0.1], [0.7, 0.6, 0.5]
        bsdf = self.load(form=form, exponent=10.0, diffuse_reflectance=kd, specular_reflectance=ks)
        ctx = mi.BSDFContext(mi.TransportMode.Importance)
        got = eval_np(bsdf, a, b, ctx)
        a32, b32 = as_f32_unit(a), as_f32_unit(b)
        spec, diff = self.ref(b32, a32, kd, ks, 10.0, form)  # viewer b, light a
        want = (spec + diff) * b32[:, 2:3]
        np.testing.assert_allclose(got, want, rtol=2e-3, atol=1e-6 * want.max())
        if form != "original":
            np.testing.assert_allclose(got, eval_np(bsdf, a, b), rtol=1e-5, atol=1e-7)

    # -- sampling ----------------------------------------------------------------------------

    @pytest.mark.parametrize("form", FORMS)
    @pytest.mark.parametrize("name,params,theta,ires", CHI2, ids=[c[0] for c in CHI2])
    def test_chi2(self, name, params, theta, ires, form):
        wi = sph(np.radians(theta), 0.3)[0]
        sample_func, pdf_func = BSDFAdapter(self.PLUGIN, {"type": self.PLUGIN, "form": form, **params},
                                            wi=mi.Vector3f(*map(float, wi)))
        test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func,
                             pdf_func=pdf_func, sample_dim=3, res=161, ires=ires)
        assert test.run(), test.messages

    def test_chi2_diffuse_component(self):
        ctx = mi.BSDFContext()
        ctx.component = 1
        sample_func, pdf_func = BSDFAdapter(
            self.PLUGIN, {"type": self.PLUGIN, "specular_reflectance": 0.5, "exponent": 10.0},
            wi=mi.Vector3f(*map(float, sph(np.radians(60), 0.3)[0])), ctx=ctx)
        test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func,
                             pdf_func=pdf_func, sample_dim=3, res=161, ires=8)
        assert test.run(), test.messages

    @pytest.mark.parametrize("form", FORMS)
    @pytest.mark.parametrize("theta", [0, 45, 80, 89])
    def test_sample_weight_is_eval_over_pdf(self, theta, form):
        wi = sph(np.radians(theta), 1.0)[0]
        n = 20000
        for prm in PARAMS[:4]:
            bsdf = self.bsdf_of(prm, form)
            si, (bs, weight) = sample_bsdf(bsdf, wi, n)
            ctx = mi.BSDFContext()
            f, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
            w, f, pdf, bpdf = to_np(weight), to_np(f), to_np(pdf), to_np(bs.pdf)
            ok = bpdf > 0
            assert ok.mean() > 0.2, prm
            np.testing.assert_allclose(bpdf[ok], pdf[ok], rtol=1e-5)
            np.testing.assert_allclose(w[ok], f[ok] / pdf[ok, None], rtol=1e-4, atol=1e-7)
            assert (w[~ok] == 0).all()
            np.testing.assert_allclose(np.linalg.norm(to_np(bs.wo), axis=1), 1, atol=1e-5)
            # eval_pdf == (eval, pdf)
            np.testing.assert_array_equal(f, to_np(bsdf.eval(ctx, si, bs.wo)))
            np.testing.assert_array_equal(pdf, to_np(bsdf.pdf(ctx, si, bs.wo)))

    # -- energy --------------------------------------------------------------------------------

    @pytest.mark.parametrize("theta", [0, 30, 60, 80, 89])
    def test_white_furnace_normalized(self, theta):
        """The normalized form conserves energy: albedo <= 1 when kd + ks <= 1."""
        for kd, ks, p in [(0.0, 1.0, 0.0), (0.0, 1.0, 1.0), (0.0, 1.0, 10.0), (0.0, 1.0, 30.0),
                          (0.0, 1.0, 1e4), (0.5, 0.5, 3.0), (0.9, 0.1, 100.0), (1.0, 0.0, 1.0)]:
            b = self.load(form="normalized", diffuse_reflectance=kd, specular_reflectance=ks,
                          exponent=p)
            a, err = albedo(b, theta)
            assert np.isfinite(a).all()
            assert (a <= 1 + 4 * err + 1e-3).all(), (kd, ks, p, a, err)
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
        assert b.component_count() == 2
        assert b.flags(0) == F.GlossyReflection | F.FrontSide
        assert b.flags(1) == F.DiffuseReflection | F.FrontSide
        assert b.flags() == b.flags(0) | b.flags(1)
        metal = self.load(form=form, diffuse_reflectance=0.0)
        assert metal.component_count() == 1 and metal.flags() == b.flags(0)
        matte = self.load(form=form, specular_reflectance=0.0)
        assert matte.component_count() == 1 and matte.flags() == b.flags(1)
        black = self.load(form=form, specular_reflectance=0.0, diffuse_reflectance=0.0)
        assert black.component_count() == 0 and black.flags() == F.Empty
        _, (bs, w) = sample_bsdf(black, [0, 0, 1], 100)
        assert (to_np(w) == 0).all()
        assert self.load(form=form, diffuse_reflectance=1e-6).component_count() == 2
        # a matte surface never samples the (absent) glossy lobe, a metal never the diffuse
        _, (bs, _) = sample_bsdf(matte, [0.3, 0, 0.954], 2000)
        assert (to_np(bs.sampled_type) == +b.flags(1)).all()
        assert (to_np(bs.sampled_component) == 0).all()
        _, (bs, _) = sample_bsdf(metal, [0.3, 0, 0.954], 2000)
        assert (to_np(bs.sampled_type) == +b.flags(0)).all()
        assert f"form = {form}" in str(b) and "exponent" in str(b)

    @pytest.mark.parametrize("form", FORMS)
    def test_context_selects_lobes(self, form):
        kd, ks, p = [0.6, 0.5, 0.4], [0.3, 0.3, 0.3], 20.0
        b = self.load(form=form, diffuse_reflectance=kd, specular_reflectance=ks, exponent=p)
        rng = np.random.default_rng(5)
        wi, wo = random_upper(rng, 500), random_upper(rng, 500)
        spec, diff = self.ref(as_f32_unit(wi), as_f32_unit(wo), kd, ks, p, form)
        cases = {
            "component0": (dict(component=0), spec),
            "component1": (dict(component=1), diff),
            "glossy_mask": (dict(type_mask=+F.Glossy), spec),
            "diffuse_mask": (dict(type_mask=+F.Diffuse), diff),
            "nothing": (dict(type_mask=+F.Transmission), 0 * spec),
        }
        for name, (attrs, want) in cases.items():
            ctx = mi.BSDFContext()
            for k, v in attrs.items():
                setattr(ctx, k, v)
            got = eval_np(b, wi, wo, ctx)
            np.testing.assert_allclose(got, want * wo[:, 2:3], rtol=2e-3, atol=1e-6, err_msg=name)
            si, (bs, weight) = sample_bsdf(b, wi[7], 5000, ctx=ctx)
            pdf = to_np(bs.pdf)
            if name == "nothing":
                assert (to_np(weight) == 0).all() and (pdf == 0).all()
                continue
            t = np.broadcast_to(to_np(bs.sampled_type), (5000,))[pdf > 0]
            glossy = name in ("component0", "glossy_mask")
            assert (t == +b.flags(0 if glossy else 1)).all(), name
            # the pdf is that lobe's alone
            f_ctx, pdf_ctx = b.eval_pdf(ctx, si, bs.wo)
            np.testing.assert_allclose(pdf, to_np(pdf_ctx), rtol=1e-6)
            if not glossy:
                np.testing.assert_allclose(pdf[pdf > 0], to_np(bs.wo)[pdf > 0, 2] / np.pi, rtol=1e-5)

    # -- textures and parameters ---------------------------------------------------------------

    @pytest.mark.parametrize("form", FORMS)
    def test_texture_parameters(self, tmp_path, form):
        kd = write_bitmap(tmp_path / "kd.exr", [0.5, 0.3, 0.1])
        ks = write_bitmap(tmp_path / "ks.exr", [0.2, 0.4, 0.6])
        p = write_bitmap(tmp_path / "p.exr", 40.0)
        textured = mi.load_dict({"type": self.PLUGIN, "form": form, "diffuse_reflectance": bitmap(kd),
                                 "specular_reflectance": bitmap(ks), "exponent": bitmap(p)})
        const = self.load(form=form, diffuse_reflectance=[0.5, 0.3, 0.1],
                          specular_reflectance=[0.2, 0.4, 0.6], exponent=40.0)
        assert textured.flags() & F.SpatiallyVarying
        assert not const.flags() & F.SpatiallyVarying
        rng = np.random.default_rng(11)
        wi, wo = random_upper(rng, 1000), random_upper(rng, 1000)
        np.testing.assert_allclose(eval_np(textured, wi, wo), eval_np(const, wi, wo), rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(pdf_np(textured, wi, wo), pdf_np(const, wi, wo), rtol=1e-5, atol=1e-7)
        bad = write_bitmap(tmp_path / "bad.exr", [0.2, 1.5, 0.6])
        with pytest.raises(RuntimeError, match=self.PLUGIN + r": parameter 'diffuse_reflectance'.*\[0, 1\]"):
            mi.load_dict({"type": self.PLUGIN, "diffuse_reflectance": bitmap(bad)})
        neg = write_bitmap(tmp_path / "neg.exr", -3.0)
        with pytest.raises(RuntimeError, match=r"parameter 'exponent'.*\[0, inf\]"):
            mi.load_dict({"type": self.PLUGIN, "exponent": bitmap(neg)})

    def test_spatially_varying_exponent(self, tmp_path):
        """A bitmap exponent is looked up at the shading point's uv."""
        arr = np.zeros((2, 2, 1), np.float32)
        arr[:, 0], arr[:, 1] = 10.0, 1000.0
        mi.Bitmap(arr).write(str(tmp_path / "p.exr"))
        b = mi.load_dict({"type": self.PLUGIN, "diffuse_reflectance": 0.0,
                          "exponent": bitmap(str(tmp_path / "p.exr"))})
        wi = sph(np.radians(20), 0.0)
        wo = sph(np.radians(22), np.pi)
        si = interaction(np.repeat(wi, 2, axis=0))
        si.uv = mi.Point2f([0.25, 0.75], [0.5, 0.5])
        f = to_np(b.eval(mi.BSDFContext(), si, vec(np.repeat(wo, 2, axis=0))))
        for i, p in enumerate((10.0, 1000.0)):
            ref = eval_np(self.load(diffuse_reflectance=0.0, exponent=p), wi, wo)
            np.testing.assert_allclose(f[i], ref[0], rtol=1e-5)
        assert abs(f[0, 0] - f[1, 0]) > 0.1 * f.max()  # the two halves differ

    @pytest.mark.parametrize("params,msg", BAD)
    def test_bad_parameters_raise_at_load(self, params, msg):
        with pytest.raises(RuntimeError, match=self.PLUGIN + ": " + msg):
            mi.load_dict({"type": self.PLUGIN, **params})

    def test_bad_parameters_from_xml(self):
        head = f'<bsdf version="3.0.0" type="{self.PLUGIN}">'
        cases = [
            ('<rgb name="specular_reflectance" value="0.5, 2, 0.5"/>',
             r"parameter 'specular_reflectance'.*\[0, 1\]"),
            ('<float name="exponent" value="-2"/>', r"parameter 'exponent'.*\[0, inf\]"),
            ('<string name="form" value="energy"/>', r"parameter 'form' must be one of"),
        ]
        for body, msg in cases:
            with pytest.raises(RuntimeError, match=self.PLUGIN + ": " + msg):
                mi.load_string(head + body + "</bsdf>")
        b = mi.load_string(head + '<string name="form" value="original"/>'
                           '<float name="exponent" value="12"/></bsdf>')
        assert b.RECIPROCAL is False and "original" in str(b)

    # -- hard cases stay finite -----------------------------------------------------------------

    @pytest.mark.parametrize("form", FORMS)
    def test_stability_grid(self, form):
        d = hard_directions()
        pairs = np.array(list(itertools.product(range(len(d)), repeat=2)))
        wi, wo = d[pairs[:, 0]], d[pairs[:, 1]]
        wi = np.concatenate([wi, -wo[:10]])  # wi = -wo as well
        wo = np.concatenate([wo, wo[:10]])
        u1 = np.array([0, 1e-7, 0.25, 0.5, 0.75, 1 - 2**-24])
        u2 = np.array([0, 1e-7, 0.5, 1 - 2**-24])
        g1, g2, g3, gi = np.meshgrid(u1, u1, u2, np.arange(len(d)), indexing="ij")
        for (ks, kd), p in itertools.product([(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)],
                                             [0.0, 1e-3, 1.0, 1e4, 1e6]):
            b = self.load(form=form, specular_reflectance=ks, diffuse_reflectance=kd, exponent=p)
            tag = f"{form} p={p} ks={ks} kd={kd}"
            for mode in (mi.TransportMode.Radiance, mi.TransportMode.Importance):
                ctx = mi.BSDFContext(mode)
                f, pdf = b.eval_pdf(ctx, interaction(wi), vec(wo))
                f, pdf = to_np(f), to_np(pdf)
                assert np.isfinite(f).all() and (f >= 0).all(), tag
                assert np.isfinite(pdf).all() and (pdf >= 0).all(), tag
                si = interaction(d[gi.ravel()])
                bs, w = b.sample(ctx, si, mi.Float(g1.ravel()), mi.Point2f(g2.ravel(), g3.ravel()))
                w, wo_s, bpdf = to_np(w), to_np(bs.wo), to_np(bs.pdf)
                assert np.isfinite(w).all() and (w >= 0).all(), tag
                assert np.isfinite(bpdf).all() and (bpdf >= 0).all(), tag
                assert np.isfinite(wo_s).all(), tag
                if ks or kd:
                    np.testing.assert_allclose(np.linalg.norm(wo_s, axis=1), 1, atol=1e-5, err_msg=tag)

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

    # -- parameters through mi.traverse, renders -------------------------------------------

    def test_traverse_and_update(self):
        scene = small_scene({"type": self.PLUGIN, "id": "mat", "diffuse_reflectance": 0.0,
                             "form": "modified"}, res=16)
        params = mi.traverse(scene)
        key = next(k for k in params.keys() if k.endswith("exponent.value"))
        img0 = np.array(mi.render(scene, spp=4, seed=0))
        params[key] = 5.0
        params.update()
        img1 = np.array(mi.render(scene, spp=4, seed=0))
        assert np.abs(img0 - img1).max() > 1e-3
        kd_key = next(k for k in params.keys() if k.endswith("diffuse_reflectance.value"))
        bsdf = scene.shapes()[0].bsdf()
        assert bsdf.component_count() == 1
        params[kd_key] = 0.5
        params.update()
        assert bsdf.component_count() == 2

    @pytest.mark.parametrize("integrator", ["path", "direct"])
    @pytest.mark.parametrize("form", FORMS)
    def test_render_llvm(self, form, integrator):
        for name, cfg in RENDERS.items():
            scene = small_scene({"type": self.PLUGIN, "form": form, **cfg}, integrator=integrator)
            img = np.array(mi.render(scene, spp=4))
            assert np.isfinite(img).all(), name
            assert img.mean() > 1e-3, name

    def test_render_scalar_rgb(self):
        mi.set_variant("scalar_rgb")
        for form in FORMS:
            scene = small_scene({"type": self.PLUGIN, "form": form, "exponent": 20.0}, res=6)
            img = np.array(mi.render(scene, spp=2))
            assert np.isfinite(img).all() and img.mean() > 1e-3, form

    @pytest.mark.parametrize("variant", ["llvm_ad_spectral", "scalar_spectral"])
    def test_spectral_variants(self, variant):
        mi.set_variant(variant)
        b = mi.load_dict({"type": self.PLUGIN, "form": "original",
                          "specular_reflectance": {"type": "rgb", "value": [0.9, 0.5, 0.2]}})
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(0, 0, 1)
        si.wavelengths = mi.Spectrum(450, 500, 600, 650)
        v = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(0.1, 0, 0.995)))
        assert np.isfinite(v).all() and (v > 0).all()
        if variant.startswith("llvm"):
            img = np.array(mi.render(small_scene({"type": self.PLUGIN}, res=8), spp=2))
            assert np.isfinite(img).all() and img.mean() > 1e-3


# -- phong ------------------------------------------------------------------------------------

class TestPhong(PhongFamilySuite):
    PLUGIN = "phong"
    reference = staticmethod(phong_reference)

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
