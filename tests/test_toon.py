"""The toon plugin: the lecture's band formula as read in the docstring, the smooth step,
brightness against Lambert, non-reciprocity, sampling, energy, lobes, parameters, renders."""
from functools import partial

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from checks import (working_lobes, CORNERS, check_chi2, check_eval_pdf_finite, check_finite_gradients,
                    check_glossy_and_diffuse_lobes, check_refused, check_render,
                    check_update_changes_render, param_key,
                    check_sample_weight_is_eval_over_pdf, check_samples_finite,
                    check_spectral_eval_and_render, check_xml_refused, context, corner_samples,
                    eval_both_ways, eval_left_right, eval_np, hard_directions, hard_pairs, load_bsdf, load_xml,
                    midpoint_hemisphere, random_pairs, unit_f32, write_halves)
from checks import interaction, random_upper, sample_bsdf, small_scene, sph, to_np, vec

from reference import TOON_DEFAULTS as DEFAULTS, toon as ref_toon, toon_step as ref_step

PLUGIN = "toon"
F = mi.BSDFFlags
load = partial(load_bsdf, PLUGIN)

CONFIGS = {
    "defaults": {},
    "hard_phong": dict(smoothing=0.0, diffuse_reflectance=[0.9, 0.3, 0.2], diffuse_shade=[0.3, 0.1, 0.05]),
    "hard_blinn": dict(smoothing=0.0, specular_model="blinn", specular_threshold=0.9, specular_shade=0.05),
    "soft_blinn": dict(smoothing=0.3, specular_model="blinn", diffuse_threshold=0.2, specular_threshold=0.7),
    "wide": dict(smoothing=1.0, diffuse_threshold=0.0, specular_threshold=1.0),
}


# -- the formula ---------------------------------------------------------------------------------

@pytest.mark.parametrize("name", list(CONFIGS))
def test_eval_matches_reference(name):
    kw = CONFIGS[name]
    rng = np.random.default_rng(7)
    wi, wo = random_upper(rng, 5000), random_upper(rng, 5000)
    wi = np.concatenate([wi, wi[:300], wi[:20]])  # mirror pairs (inside the highlight)
    wo = np.concatenate([wo, wi[:300] * [-1, -1, 1], wi[:20] * [1, 1, -1]])
    wi32, wo32 = unit_f32(wi), unit_f32(wo)
    diff, spec, c = ref_toon(wi32, wo32, **kw)
    got = eval_np(load(**kw), wi, wo)
    keep = np.ones(len(wi), bool)
    if kw.get("smoothing", 0.05) == 0:  # float32 and float64 may disagree right at a hard edge
        P = {**DEFAULTS, **kw}
        keep = (np.abs(wo32[:, 2] - P["diffuse_threshold"]) > 1e-5) & (np.abs(c - P["specular_threshold"]) > 1e-5)
    np.testing.assert_allclose(got[keep], (diff + spec)[keep], rtol=1e-5, atol=1e-6)
    assert (spec[:, 0] > 0.01).sum() > 100  # the highlight was hit


def test_lit_band_is_lambert_at_normal_incidence():
    """White lit band: eval = 1/pi, what a white Lambert gives with the light along n, for
    any light direction inside the band and any viewer."""
    toon = load(diffuse_reflectance=1.0, diffuse_shade=0.0, specular_reflectance=0.0, smoothing=0.0)
    lam = mi.load_dict({"type": "lambert", "reflectance": 1.0})
    rng = np.random.default_rng(1)
    view = random_upper(rng, 1000)
    light = sph(np.arccos(rng.uniform(0.5, 1, 1000)), rng.uniform(0, 2 * np.pi, 1000))
    np.testing.assert_allclose(eval_np(toon, view, light), 1 / np.pi, rtol=1e-6)
    np.testing.assert_allclose(eval_np(lam, view[:1], [[0, 0, 1]]), 1 / np.pi, rtol=1e-6)
    # below the threshold: the (black) shade
    dark = sph(np.arccos(rng.uniform(0.01, 0.49, 1000)), rng.uniform(0, 2 * np.pi, 1000))
    assert (eval_np(toon, view, dark) == 0).all()


def test_brightness_of_render_matches_lambert():
    """Swapping lambert for toon keeps the brightness of the lit part of a sphere: the
    brightest pixel under a distant light is the same, and the toon's lit band is flat."""
    def scene(bsdf):
        light = {"type": "directional", "direction": [0, 0, -1], "irradiance": {"type": "rgb", "value": 3}}
        return small_scene(bsdf, res=48, integrator="direct", light=light, env=None)
    lam = np.array(mi.render(scene({"type": "lambert", "reflectance": 0.8}), seed=1))[..., 0]
    toon = np.array(mi.render(scene({"type": PLUGIN, "diffuse_reflectance": 0.8, "diffuse_shade": 0.0,
                                     "specular_reflectance": 0.0, "smoothing": 0.0}), seed=1))[..., 0]
    assert abs(toon.max() / lam.max() - 1) < 0.01, (toon.max(), lam.max())
    lit = toon > 0.5 * toon.max()
    # flat: 0.8 / pi times the irradiance (pixels on the band's edge are partly covered)
    assert lit.sum() > 50 and (np.abs(toon[lit] / (3 * 0.8 / np.pi) - 1) < 1e-4).mean() > 0.9
    assert toon[lit].mean() > 1.05 * lam[lit].mean()  # Lambert dims away from the centre


def test_smoothing_band():
    """The gradient between bands: a smooth step of the given width around the threshold,
    exact colours outside it, a hard switch at width 0."""
    light_cos = np.linspace(0.01, 1, 400)
    light = np.stack([np.sqrt(1 - light_cos ** 2), 0 * light_cos, light_cos], 1)
    view = np.repeat([[0.0, 0.6, 0.8]], len(light), axis=0)  # far from the highlight
    for w in (0.0, 0.1, 0.4):
        b = load(diffuse_reflectance=0.8, diffuse_shade=0.2, specular_reflectance=0.0, smoothing=w,
                 diffuse_threshold=0.5)
        f = eval_np(b, view, light)[:, 0] * np.pi
        x = unit_f32(light)[:, 2]
        assert np.all(np.diff(f) >= -1e-7)  # monotone in the light's cosine
        np.testing.assert_allclose(f[x < 0.5 - w / 2 - 1e-4], 0.2, rtol=1e-6)
        np.testing.assert_allclose(f[x > 0.5 + w / 2 + 1e-4], 0.8, rtol=1e-6)
        inside = np.abs(x - 0.5) < w / 2
        if w > 0:
            assert ((f[inside] > 0.2) & (f[inside] < 0.8)).all() and inside.sum() > 5
            np.testing.assert_allclose(f[inside], 0.2 + 0.6 * ref_step(x[inside], 0.5, w), rtol=1e-5)


def test_not_reciprocal_and_importance_transport():
    """f = eval / cos(theta_light) is not symmetric (diffuse and specular bands alike), so
    RECIPROCAL is False and importance transport swaps the roles of wi and wo."""
    b = load(smoothing=0.2)
    assert not b.RECIPROCAL
    a, c = random_pairs(3, 3000)
    f_ac, f_ca = eval_both_ways(b, a, c)
    rel = np.abs(f_ac - f_ca) / np.maximum(f_ac, f_ca)
    assert np.median(rel) > 0.1
    for kw in (dict(specular_reflectance=0.0), dict(diffuse_reflectance=0.0, diffuse_shade=0.0,
                                                     specular_threshold=0.5)):
        g_ac, g_ca = eval_both_ways(load(**kw), a, c)
        assert np.abs(g_ac - g_ca).max() > 0.1 * g_ac.max(), kw
    imp = mi.BSDFContext(mi.TransportMode.Importance)
    want = eval_np(b, c, a) / a[:, 2:3].astype(np.float32) * c[:, 2:3].astype(np.float32)
    np.testing.assert_allclose(eval_np(b, a, c, imp), want, rtol=1e-4, atol=1e-7)


# -- sampling and energy -------------------------------------------------------------------------

def ref_albedo(theta, n=300, **kw):
    """Midpoint quadrature of the reference eval over the light hemisphere (float64)."""
    light, dw = midpoint_hemisphere(n)
    view = np.repeat(sph(np.radians(theta), 0.0), len(light), axis=0)
    diff, spec, _ = ref_toon(view, light, **kw)
    return (diff[:, 0] * dw).sum(), (spec[:, 0] * dw).sum()


@pytest.mark.parametrize("name,kw", [
    ("lambert_like", dict(diffuse_reflectance=1.0, diffuse_shade=0.0, specular_reflectance=0.0)),
    ("defaults_no_shade", dict(diffuse_shade=0.0)),
    ("blinn_soft", dict(diffuse_shade=0.0, specular_model="blinn", smoothing=0.3, specular_threshold=0.8)),
    ("all_lit", dict(diffuse_reflectance=1.0, diffuse_threshold=0.0, smoothing=0.0, specular_reflectance=0.0)),
    ("defaults", {}),
])
def test_white_furnace(name, kw):
    """Albedo: Monte Carlo = quadrature of the formula; the diffuse part is
    2 (m_D1 (1 - t_D) + m_D2 t_D). Not energy conserving: t_D = 0 reflects twice the light."""
    P = {**DEFAULTS, **kw}
    b = load(**kw)
    want_d = 2 * (P["diffuse_reflectance"] * (1 - P["diffuse_threshold"]) + P["diffuse_shade"] * P["diffuse_threshold"])
    for theta in (0, 45, 85):
        _, (bs, w) = sample_bsdf(b, sph(np.radians(theta), 0.0)[0], 200_000, seed=int(theta))
        w = to_np(w)[:, 0]
        d, s = ref_albedo(theta, **kw)
        assert abs(d - want_d) < 2e-3, (d, want_d)
        # a flat shade band makes weights ~1/cos at grazing: a heavy tail, looser bound
        tol = 5 * w.std() / np.sqrt(len(w)) + (2e-2 if P["diffuse_shade"] > 0 else 2e-3)
        assert abs(w.mean() - (d + s)) < tol, (name, theta, w.mean(), d + s)
        if name == "lambert_like":
            assert abs(w.mean() - 1) < 3e-3  # same albedo as a white Lambert
        if name == "all_lit":
            assert abs(w.mean() - 2) < 1e-2


# -- flags, components, contexts -----------------------------------------------------------------

def test_flags_components_and_context():
    b = load(smoothing=0.1)
    check_glossy_and_diffuse_lobes(b)
    flat = load(specular_reflectance=0.0)
    assert working_lobes(flat) == 1 and flat.flags() == b.flags()
    assert working_lobes(load(specular_reflectance=0.0, specular_shade=0.2)) == 2
    spec = load(diffuse_reflectance=0.0, diffuse_shade=0.0)
    assert working_lobes(spec) == 1 and spec.flags() == b.flags()
    assert working_lobes(load(diffuse_reflectance=0.0, diffuse_shade=0.0, specular_reflectance=0.0)) == 0

    wi, wo = random_pairs(2, 500)
    wo[:100] = wi[:100] * [-1, -1, 1]
    diff, sp, _ = ref_toon(unit_f32(wi), unit_f32(wo), smoothing=0.1)
    cases = [({}, diff + sp, None), (dict(component=0), sp, 0), (dict(component=1), diff, 1),
             (dict(type_mask=+F.Glossy), sp, 0), (dict(type_mask=+F.Diffuse), diff, 1),
             (dict(type_mask=+F.Transmission), 0 * sp, -1)]
    for attrs, want, comp in cases:
        ctx = context(**attrs)
        np.testing.assert_allclose(eval_np(b, wi, wo, ctx), want, rtol=1e-5, atol=1e-6, err_msg=str(attrs))
        _, (bs, w) = sample_bsdf(b, wi[0], 2000, ctx=ctx)
        w = to_np(w)
        if comp == -1:
            assert (w == 0).all()
            continue
        assert (w > 0).any()
        if comp is not None:
            t = np.broadcast_to(to_np(bs.sampled_type), (2000,))[to_np(bs.pdf) > 0]
            assert (t == +b.flags(comp)).all(), attrs


# -- textures and parameters ---------------------------------------------------------------------

def test_bitmap_textures(tmp_path):
    """Colours and thresholds from bitmaps, looked up at the shading point's uv."""
    L = dict(diffuse_reflectance=[0.9, 0.2, 0.1], diffuse_threshold=0.2, smoothing=0.0)
    R = dict(diffuse_reflectance=[0.1, 0.3, 0.8], diffuse_threshold=0.8, smoothing=0.3)
    b = mi.load_dict({"type": PLUGIN,
                      **{name: write_halves(tmp_path / f"{name}.exr", L[name], R[name]) for name in L}})
    assert b.flags() & F.SpatiallyVarying
    view, light = sph(np.radians(20), 0.0), sph(np.radians(60), 2.0)  # light cos 0.5
    f = eval_left_right(b, view, light)
    for k, P in enumerate((L, R)):
        np.testing.assert_allclose(f[k], eval_np(load(**P), view, light)[0], rtol=1e-5)
    assert np.abs(f[0] - f[1]).max() > 0.05


def test_parameters_from_xml():
    good = load_xml(PLUGIN, '<string name="specular_model" value="blinn"/><float name="smoothing" value="0"/>'
                            '<rgb name="diffuse_shade" value="0.2, 0.1, 0.1"/>')
    assert "specular_model = blinn" in str(good)


# -- hard cases ----------------------------------------------------------------------------------

def check_toon_stable(b, d, wi, wo):
    """eval finite, >= 0 and at most two lit bands (2 / pi) at the pairs; samples from the
    directions d finite in both transport modes; finite derivatives w.r.t. every parameter
    and both directions."""
    f, _ = check_eval_pdf_finite(b, mi.BSDFContext(), wi, wo)
    assert f.max() <= 2 / np.pi + 1e-6
    samples = corner_samples(d, CORNERS, CORNERS)
    for mode in (mi.TransportMode.Radiance, mi.TransportMode.Importance):
        check_samples_finite(b, mi.BSDFContext(mode), samples, tag=str(mode))
    check_finite_gradients(b, wi, wo)


@pytest.mark.parametrize("model", ["phong", "blinn"])
@pytest.mark.parametrize("w,t", [(0.0, 0.0), (0.0, 1.0), (1.0, 0.5), (0.1, 0.95)])
def test_stability_grid(model, w, t):
    d = hard_directions()
    wi, wo = hard_pairs(d)  # wi = -wo as well
    b = load(specular_model=model, smoothing=w, diffuse_threshold=t, specular_threshold=t,
             diffuse_reflectance=1.0, diffuse_shade=1.0, specular_reflectance=1.0, specular_shade=1.0)
    check_toon_stable(b, d, wi, wo)


# -- renders -------------------------------------------------------------------------------------

# -- colour ramps (the lecture's 1D textures f_mD, f_mS) ------------------------------------------

from mitsuba_brdfs.paths import SCENES  # noqa: E402
#: a 5-pixel ramp (float32 values, one row)
RAMP = np.array([[0.05, 0.02, 0.1], [0.2, 0.1, 0.3], [0.5, 0.3, 0.2], [0.8, 0.6, 0.4], [1.0, 0.95, 0.9]])


def ramp_texture(path, colours=RAMP, filter_type="nearest", wrap_mode="repeat"):
    """A raw bitmap ramp, one pixel per colour."""
    mi.Bitmap(np.asarray(colours, np.float32)[None]).write(str(path))
    return {"type": "bitmap", "filename": str(path), "raw": True, "filter_type": filter_type,
            "wrap_mode": wrap_mode}


def ref_ramp(c, colours, filter_type):
    """The documented lookup, float64: u = clamp(c, 0, 1); nearest: pixel floor(u N);
    bilinear: linear between the pixel centres (k + 1/2) / N, flat beyond the end ones."""
    colours = np.asarray(colours, float)
    n = len(colours)
    u = np.clip(c, 0, 1)
    if filter_type == "nearest":
        return colours[np.minimum((u * n).astype(int), n - 1)]
    x = np.clip(u * n - 0.5, 0, n - 1)
    return np.stack([np.interp(x, np.arange(n), colours[:, k]) for k in range(colours.shape[1])], 1)


@pytest.mark.parametrize("filter_type", ["nearest", "bilinear"])
@pytest.mark.parametrize("lobe", ["diffuse", "specular"])
def test_ramp_matches_reference(tmp_path, lobe, filter_type):
    """eval = (ramp_D(d.n) + ramp_S(c_s)) / pi: a ramp replaces its lobe's bands, the other
    lobe keeps its bands."""
    rng = np.random.default_rng(5)
    wi, wo = random_upper(rng, 5000), random_upper(rng, 5000)
    wi = np.concatenate([wi, wi[:500]])
    wo = np.concatenate([wo, wi[:500] * [-1, -1, 1]])  # mirror pairs: the specular cosine near 1
    wi32, wo32 = unit_f32(wi), unit_f32(wo)
    b = load(**{f"{lobe}_ramp": ramp_texture(tmp_path / "r.exr", filter_type=filter_type)})
    diff, spec, c = ref_toon(wi32, wo32)
    x = wo32[:, 2] if lobe == "diffuse" else c
    ramp = ref_ramp(x, RAMP, filter_type) / np.pi
    want = (ramp + spec) if lobe == "diffuse" else (diff + ramp)
    keep = np.ones(len(wi), bool)
    if filter_type == "nearest":  # float32 and float64 may pick different pixels at an edge
        keep = np.abs(x * len(RAMP) - np.round(x * len(RAMP))) > 1e-4
    np.testing.assert_allclose(eval_np(b, wi, wo)[keep], want[keep], rtol=1e-5, atol=1e-6)
    assert f"{lobe}_ramp.data" in mi.traverse(b).keys()
    assert f"{lobe}_reflectance.value" not in mi.traverse(b).keys()


def test_nearest_ramp_gives_n_bands_and_ends_never_wrap(tmp_path):
    """A nearest ramp of N pixels gives N flat bands of width 1/N in the cosine, and the
    ends are the first and last pixel whatever the wrap mode (a repeating bitmap read at
    u = 1 would return its first pixel)."""
    light_cos = np.concatenate([np.linspace(1e-3, 1, 2000), [1.0]])
    light = np.stack([np.sqrt(1 - light_cos ** 2), 0 * light_cos, light_cos], 1)
    view = np.repeat([[0.0, 0.6, 0.8]], len(light), axis=0)
    for wrap in ("repeat", "mirror", "clamp"):
        for filter_type in ("nearest", "bilinear"):
            b = load(diffuse_ramp=ramp_texture(tmp_path / f"{wrap}.exr", filter_type=filter_type,
                                               wrap_mode=wrap), specular_reflectance=0.0)
            f = eval_np(b, view, light) * np.pi
            np.testing.assert_allclose(f[-1], RAMP[-1], rtol=1e-6)   # the light along n
            np.testing.assert_allclose(f[0], RAMP[0], rtol=1e-3)     # grazing light
            if filter_type == "nearest":
                assert len(np.unique(f[:, 0])) == len(RAMP)
            else:  # a gradient: monotone, as many values as samples inside
                assert np.all(np.diff(f[:, 0]) >= -1e-7) and len(np.unique(f[:, 0])) > 1000


def test_ramp_albedo(tmp_path):
    """The diffuse albedo of a ramp is 2 int ramp(mu) dmu (eval is flat in the cosine), for
    any viewer: twice the mean pixel of a nearest ramp (Monte Carlo and chi-square)."""
    b = load(diffuse_ramp=ramp_texture(tmp_path / "r.exr"), specular_reflectance=0.0)
    want = 2 * RAMP.mean(axis=0)
    for theta in (0, 45, 85):
        _, (bs, w) = sample_bsdf(b, sph(np.radians(theta), 0.0)[0], 200_000, seed=int(theta))
        w = to_np(w)
        np.testing.assert_allclose(w.mean(axis=0), want, atol=4 * w.std(axis=0).max() / np.sqrt(len(w)) + 1e-3)
    check_chi2(PLUGIN, {"diffuse_ramp": ramp_texture(tmp_path / "c.exr", filter_type="bilinear"),
                        "specular_ramp": ramp_texture(tmp_path / "s.exr")}, 50, res=101, ires=8)
    check_sample_weight_is_eval_over_pdf(b, sph(np.radians(60), 1.0)[0], min_valid=0.99,
                                         pdf_rtol=1e-6, weight_rtol=1e-5)


def test_png_ramps_of_the_example_scene():
    """The 8-bit sRGB PNG ramps of scenes/toon_ramp.xml load (as fractions of 255, decoded to
    linear colours) and the white pixel of the specular ramp gives eval = 1/pi at the mirror
    direction."""
    png = lambda name, f: {"type": "bitmap", "filename": f"{SCENES}/{name}", "filter_type": f}  # noqa: E731
    b = load(diffuse_ramp=png("toon_ramp_diffuse.png", "nearest"),
             specular_ramp=png("toon_ramp_specular.png", "nearest"))
    assert b.component_count() == 2
    wi = sph(np.radians(30), 0.0)
    spec = eval_np(b, wi, wi * [-1, -1, 1], context(component=0))
    np.testing.assert_allclose(spec, 1 / np.pi, rtol=1e-5)
    diff = eval_np(b, wi, [[0, 0, 1]], context(component=1))[0] * np.pi
    np.testing.assert_allclose(diff, (np.array([255, 200, 150]) / 255) ** 2.2, rtol=0.05)  # ~sRGB


def test_ramp_lobes_and_errors(tmp_path):
    black = {"type": "rgb", "value": [0, 0, 0]}
    assert working_lobes(load(specular_ramp=black)) == 1
    assert working_lobes(load(specular_ramp=black, diffuse_ramp=black)) == 0
    assert load(diffuse_ramp=ramp_texture(tmp_path / "r.exr")).flags() & F.SpatiallyVarying
    for band in ("diffuse_reflectance", "diffuse_shade", "diffuse_threshold"):
        check_refused(PLUGIN, {"diffuse_ramp": black, band: 0.5},
                      rf"toon: parameter '{band}' must be absent when 'diffuse_ramp' is given "
                      r"\(the ramp replaces the lobe's two bands\)")
    check_refused(PLUGIN, {"specular_ramp": black, "specular_threshold": 0.5},
                  r"parameter 'specular_threshold' must be absent when 'specular_ramp' is given")
    check_refused(PLUGIN, {"specular_ramp": black, "diffuse_ramp": black, "smoothing": 0.1},
                  r"toon: parameter 'smoothing' must be absent when 'diffuse_ramp' and "
                  r"'specular_ramp' are given")
    check_refused(PLUGIN, {"diffuse_ramp": ramp_texture(tmp_path / "bad.exr", colours=[[0.2] * 3, [1.5] * 3])},
                  r"toon: parameter 'diffuse_ramp' must be a reflectance in \[0, 1\]")
    check_xml_refused(PLUGIN, '<rgb name="specular_ramp" value="0.5, 2, 0.5"/>',
                      r"toon: parameter 'specular_ramp' must be a reflectance in \[0, 1\]")


@pytest.mark.parametrize("filter_type", ["nearest", "bilinear"])
def test_ramp_stability_and_gradients(tmp_path, filter_type):
    d = hard_directions()
    wi, wo = hard_pairs(d)
    b = load(diffuse_ramp=ramp_texture(tmp_path / "d.exr", filter_type=filter_type),
             specular_ramp=ramp_texture(tmp_path / "s.exr", filter_type=filter_type))
    check_toon_stable(b, d, wi, wo)


def test_ramp_traverse_and_renders(tmp_path):
    scene = small_scene({"type": PLUGIN, "id": "mat",
                         "diffuse_ramp": ramp_texture(tmp_path / "d.exr", filter_type="bilinear")}, res=16)
    params = mi.traverse(scene)
    key = param_key(params, "diffuse_ramp.data")
    check_update_changes_render(scene, params, key, dr.full(mi.TensorXf, 0.9, params[key].shape))
    for integrator in ("path", "direct"):
        check_render({"type": PLUGIN, "diffuse_ramp": ramp_texture(tmp_path / "n.exr"),
                      "specular_ramp": ramp_texture(tmp_path / "s.exr")}, integrator=integrator)
    mi.set_variant("scalar_rgb")
    check_render({"type": PLUGIN, "diffuse_ramp": ramp_texture(tmp_path / "n.exr")}, res=6, spp=2)
    check_spectral_eval_and_render(
        "llvm_ad_spectral", {"type": PLUGIN, "diffuse_ramp": {"type": "bitmap", "filter_type": "nearest",
                                                              "filename": f"{SCENES}/toon_ramp_diffuse.png"}},
        scene_bsdf={"type": PLUGIN, "specular_ramp": {"type": "rgb", "value": [0.2, 0.2, 0.2]}})


def test_ramp_albedo_aov_and_width_after_update(tmp_path):
    """With ramps the albedo AOV is each ramp's lit end (cosine 1); a ramp whose data is
    replaced through traverse by a wider one is looked up over its new pixel centres."""
    ramp = ramp_texture(tmp_path / "d.exr", filter_type="nearest")
    b = load(diffuse_ramp=ramp, specular_ramp=ramp)
    si = interaction(np.array([[0, 0, 1.0]]))
    lit_end = np.array(mi.traverse(b)["diffuse_ramp.data"])[0, -1]
    np.testing.assert_allclose(to_np(b.eval_diffuse_reflectance(si)), lit_end[None, :], rtol=1e-6)
    scene = small_scene({"type": "toon", "specular_reflectance": 0.0,
                         "diffuse_ramp": ramp_texture(tmp_path / "e.exr", filter_type="nearest")})
    params = mi.traverse(scene)
    wide = np.repeat(np.linspace(0.05, 0.95, 8, dtype=np.float32)[None, :, None], 3, axis=2)
    params["ball.bsdf.diffuse_ramp.data"] = mi.TensorXf(wide)
    params.update()
    bsdf = scene.shapes()[0].bsdf()
    ctx = mi.BSDFContext()
    ctx.component = 1
    wo = np.array([[np.sqrt(1 - 0.01 ** 2), 0, 0.01], [0, 0, 1.0]])
    f = to_np(bsdf.eval(ctx, interaction(np.repeat([[0, 0, 1.0]], 2, axis=0)), vec(wo)))
    # the first and the last of the 8 pixels (eval = ramp / pi: the bands hold the cosine)
    np.testing.assert_allclose(f[:, 0] * np.pi, [0.05, 0.95], rtol=1e-5)
