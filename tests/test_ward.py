"""The ward plugin: eval, pdf, sampling, energy, anisotropy, lobes, parameters, renders."""
import itertools
from functools import partial

import mitsuba as mi
import numpy as np
import pytest

from checks import (working_lobes, albedo_at, check_albedo_at_most_one, check_context_selects_lobes, check_glossy_and_diffuse_lobes, check_update_changes_lobes, check_update_changes_render, check_zero_below_horizon, eval_left_right, eval_np,
                    load_bsdf, load_xml, param_key, random_pairs, unit, unit_f32,
                    write_halves)
from checks import sample_bsdf, small_scene, sph, to_np

from reference import ward as ward_reference

PLUGIN = "ward"
F = mi.BSDFFlags
load = partial(load_bsdf, PLUGIN)


FORMS = ["ward", "duer", "balanced"]


def bsdf_of(p, form="ward"):
    return load(specular_reflectance=p["rs"], diffuse_reflectance=p["rd"],
                alpha_u=p["au"], alpha_v=p["av"], form=form)


# -- eval against the float64 transcription ----------------------------------------------------

@pytest.mark.parametrize("form", FORMS)
def test_below_horizon_and_backfacing_is_zero(form):
    check_zero_below_horizon(load(alpha_u=1.0, alpha_v=1.0, form=form))


def test_forms_differ_as_their_denominators():
    """At one pair of directions the three forms differ by the ratios of their
    denominators (the exponential and rho_s are shared)."""
    wi, wo = sph(np.radians(70), 0.3), sph(np.radians(40), 0.3 + np.pi)
    f = {form: eval_np(load(diffuse_reflectance=0.0, form=form), wi, wo)[0, 0] for form in FORMS}
    ci, co = wi[0, 2], wo[0, 2]
    H = wi[0] + wo[0]
    np.testing.assert_allclose(f["duer"] / f["ward"], 1 / np.sqrt(ci * co), rtol=1e-5)
    np.testing.assert_allclose(f["balanced"] / f["ward"],
                               4 * np.sqrt(ci * co) * (H @ H) / H[2] ** 4, rtol=1e-5)


def test_anisotropy_follows_u_and_v():
    """alpha_u stretches the highlight along u (the shape's dP/du), alpha_v along v."""
    b = load(diffuse_reflectance=0.0, alpha_u=0.05, alpha_v=0.3)
    wi = sph(np.radians(30), 0.0)
    tilt = np.radians(12)  # h tilts by ~6 degrees: tan = 0.1 = 2 alpha_u = alpha_v / 3
    along_u = sph(np.radians(30) + tilt, np.pi)                   # in the u-n plane
    m = sph(np.radians(30), np.pi)[0]
    along_v = unit(np.cos(tilt) * m + np.sin(tilt) * np.array([0, 1, 0]))[None]
    fu = eval_np(b, wi, along_u)[0, 0]
    fv = eval_np(b, wi, along_v)[0, 0]
    assert fv > 10 * fu, (fu, fv)
    # the sampled directions spread along v
    _, (bs, _) = sample_bsdf(b, wi[0], 50_000)
    wo = to_np(bs.wo)
    assert np.std(wo[:, 1]) > 3 * np.std(wo[:, 0])
    # swapping the alphas turns the lobe by 90 degrees
    b2 = load(diffuse_reflectance=0.0, alpha_u=0.3, alpha_v=0.05)
    wi_v = sph(np.radians(30), np.pi / 2)
    along_u2 = sph(np.radians(30) + tilt, -np.pi / 2)              # in the v-n plane
    np.testing.assert_allclose(eval_np(b2, wi_v, along_u2)[0, 0], fu, rtol=1e-3)


# -- sampling --------------------------------------------------------------------------------

@pytest.mark.parametrize("form", FORMS)
def test_sample_weight_is_walters(form):
    """Walter 2005: the specular sample weight is rho_s (v.h) cos^3(theta_h)
    sqrt(cos(theta_l) / cos(theta_v)) (a metal: every sample is specular); the same sampler
    gives rho_s (v.h) cos^3(theta_h) / cos(theta_v) for Duer's form and the bounded
    rho_s cos(theta_l) / ((v.h) cos(theta_h)) for the balanced one."""
    wi = sph(np.radians(40), 0.5)[0]
    _, (bs, w) = sample_bsdf(load(diffuse_reflectance=0.0, specular_reflectance=0.7,
                                  alpha_u=0.2, alpha_v=0.4, form=form), wi, 20000)
    wo, w = to_np(bs.wo).astype(float), to_np(w)[:, 0]
    ok = to_np(bs.pdf) > 0
    h = unit(wo + wi)
    vh, cos_l = np.sum(h * wi, axis=1), np.clip(wo[:, 2], 0, None)
    want = 0.7 * {"ward": vh * h[:, 2] ** 3 * np.sqrt(cos_l / wi[2]),
                  "duer": vh * h[:, 2] ** 3 / wi[2],
                  "balanced": cos_l / (vh * h[:, 2])}[form]
    np.testing.assert_allclose(w[ok], want[ok], rtol=2e-4, atol=1e-7)
    if form == "balanced":
        assert w.max() <= 2 * 0.7 * (1 + 1e-5)


# -- energy ----------------------------------------------------------------------------------

#: incidences (as cos(theta)) down to the documented limit of bounded albedo, cos = 0.01
COS_BOUNDED = [1.0, 0.866, 0.5, 0.17, 0.087, 0.0105]
ALPHAS = [(1e-4, 1e-4), (0.05, 0.05), (0.2, 0.2), (0.5, 0.5), (1.0, 1.0), (0.05, 0.3), (1e-4, 1.0)]


@pytest.mark.parametrize("cos_t", COS_BOUNDED)
def test_white_furnace(cos_t):
    """Albedo <= 1 (rho_s = 1, and rho_s + rho_d = 1) for every alpha down to cos = 0.01."""
    for (au, av), phi in itertools.product(ALPHAS, [0.0, np.pi / 2]):
        wi = sph(np.arccos(cos_t), phi)[0]
        for rs, rd in [(1.0, 0.0), (0.3, 0.7)]:
            b = load(specular_reflectance=rs, diffuse_reflectance=rd, alpha_u=au, alpha_v=av)
            a, err = albedo_at(b, wi, n=100_000)
            check_albedo_at_most_one(a, err, (au, av, phi, rs, rd))


@pytest.mark.parametrize("form", FORMS)
def test_albedo_of_a_smooth_surface(form):
    """In the limit of small slopes Ward's normalisation makes the albedo rho_s at normal
    incidence and rho_s cos(theta_v) elsewhere: near the mirror direction l and v have the
    same elevation, and f cos(theta_l) / p(l) = rho_s (v.h) cos^3(theta_h) -> rho_s cos(theta_v).
    Duer's and the balanced denominators make it rho_s at every incidence."""
    rs = np.array([0.9, 0.5, 0.2])
    b = load(specular_reflectance=rs.tolist(), diffuse_reflectance=0.0, alpha_u=1e-3, alpha_v=1e-3,
             form=form)
    for theta in (0, 40, 70):
        a, err = albedo_at(b, sph(np.radians(theta), 0.3)[0], n=50_000)
        want = rs * np.cos(np.radians(theta)) if form == "ward" else rs
        np.testing.assert_allclose(a, want, rtol=2e-3 + 4 * err.max())


#: incidences (as cos(theta)) down to float32's limit for the balanced form, and the
#: documented albedo table (rows alpha 0.05, 0.2, 0.5, 1; columns cos 1, 0.5, 0.1, 0.01, 1e-4)
COS_ALL = [1.0, 0.5, 0.1, 0.01, 1e-3, 1e-4]
BALANCED_TABLE = [[1.00, 0.99, 0.89, 0.85, 0.99], [0.96, 0.90, 0.80, 0.93, 1.00],
                  [0.75, 0.71, 0.81, 0.95, 1.00], [0.37, 0.54, 0.80, 0.96, 1.00]]
DUER_TABLE = [[1.00, 1.00, 0.97, 1.94, 140], [0.93, 0.92, 1.07, 5.5, 505],
              [0.69, 0.66, 1.21, 8.7, 836], [0.35, 0.39, 0.98, 7.9, 772]]


@pytest.mark.parametrize("cos_t", COS_ALL)
def test_white_furnace_balanced(cos_t):
    """The balanced form's albedo is bounded: <= 1 for every alpha and incidence (rho_s = 1,
    and rho_s + rho_d = 1), here down to cos(theta_v) = 1e-4."""
    for (au, av), phi in itertools.product(ALPHAS, [0.0, 0.7, np.pi / 2]):
        wi = sph(np.arccos(cos_t), phi)[0]
        for rs, rd in [(1.0, 0.0), (0.3, 0.7)]:
            b = load(specular_reflectance=rs, diffuse_reflectance=rd, alpha_u=au, alpha_v=av,
                     form="balanced")
            a, err = albedo_at(b, wi, n=100_000)
            check_albedo_at_most_one(a, err, (au, av, phi, rs, rd))


@pytest.mark.parametrize("form,table", [("balanced", BALANCED_TABLE), ("duer", DUER_TABLE)])
def test_albedo_tables_of_the_docstring(form, table):
    """The tables in the docstring (rounded Monte Carlo values): each entry within 0.02
    (2% for the large Duer values)."""
    for (k, a), (j, c) in itertools.product(enumerate((0.05, 0.2, 0.5, 1.0)),
                                            enumerate((1.0, 0.5, 0.1, 0.01, 1e-4))):
        b = load(specular_reflectance=1.0, diffuse_reflectance=0.0, alpha_u=a, alpha_v=a, form=form)
        got, err = albedo_at(b, sph(np.arccos(c), 0.0)[0], n=200_000)
        want = table[k][j]
        assert abs(got[0] - want) < max(0.02, 0.02 * want) + 4 * err[0], (form, a, c, got[0], want)


def test_duer_albedo_grows_like_one_over_cos():
    """Duer's documented excess: at grazing incidence the albedo grows like 1 / cos(theta_v)
    (Ward's like its square root)."""
    b = load(specular_reflectance=1.0, diffuse_reflectance=0.0, alpha_u=0.5, alpha_v=0.5, form="duer")
    a1, _ = albedo_at(b, sph(np.arccos(1e-3), 0.0)[0])
    a2, _ = albedo_at(b, sph(np.arccos(1e-4), 0.0)[0])
    assert a1[0] > 50
    np.testing.assert_allclose(a2 / a1, 10, rtol=0.1)


def test_albedo_is_unbounded_at_grazing_incidence():
    """The documented defect of the original normalisation: below cos(theta_v) ~ 0.01 the
    albedo grows like 1 / sqrt(cos(theta_v)) (about 6 at cos = 1e-4 for alpha = 0.5)."""
    b = load(specular_reflectance=1.0, diffuse_reflectance=0.0, alpha_u=0.5, alpha_v=0.5)
    a1, _ = albedo_at(b, sph(np.arccos(1e-4), 0.0)[0])
    a2, _ = albedo_at(b, sph(np.arccos(1e-6), 0.0)[0])
    assert 5 < a1[0] < 7.5, a1
    np.testing.assert_allclose(a2 / a1, 10, rtol=0.1)


# -- flags, components, contexts --------------------------------------------------------------

def test_flags_and_components():
    b = load()
    check_glossy_and_diffuse_lobes(b, F.GlossyReflection | F.Anisotropic | F.FrontSide)
    metal = load(diffuse_reflectance=0.0)
    assert working_lobes(metal) == 1 and metal.flags() == b.flags()
    matte = load(specular_reflectance=0.0)
    assert working_lobes(matte) == 1 and matte.flags() == b.flags()
    black = load(specular_reflectance=0.0, diffuse_reflectance=0.0)
    assert working_lobes(black) == 0 and black.flags() == b.flags()
    assert working_lobes(load(specular_reflectance=1e-6)) == 2
    _, (bs, _) = sample_bsdf(metal, [0.3, 0, 0.954], 5000)
    assert (to_np(bs.sampled_type) == +b.flags(0)).all()
    assert (to_np(bs.sampled_component) == 0).all()
    _, (bs, _) = sample_bsdf(matte, [0.3, 0, 0.954], 5000)
    assert (to_np(bs.sampled_type) == +b.flags(1)).all()
    s = str(b)
    assert all(k in s for k in ("alpha_u", "alpha_v", "specular_reflectance", "diffuse_reflectance"))


@pytest.mark.parametrize("form", FORMS)
def test_context_selects_lobes(form):
    p = dict(rs=[0.3, 0.3, 0.3], rd=[0.6, 0.5, 0.4], au=0.1, av=0.3)
    b = bsdf_of(p, form)
    wi, wo = random_pairs(5, 500)
    spec, diff = ward_reference(unit_f32(wi), unit_f32(wo), p["rs"], p["rd"], p["au"], p["av"], form)
    check_context_selects_lobes(b, wi, wo, spec, diff, rtol=2e-3, atol=1e-6, lobe_pdf=True)
    assert f"form = {form}" in str(b)


# -- textures and parameters ------------------------------------------------------------------

def test_spatially_varying_alpha(tmp_path):
    b = mi.load_dict({"type": PLUGIN, "diffuse_reflectance": 0.0,
                      "alpha_u": write_halves(tmp_path / "a.exr", 0.05, 0.4), "alpha_v": 0.1})
    wi = sph(np.radians(20), 0.0)
    wo = sph(np.radians(26), np.pi)
    f = eval_left_right(b, wi, wo)
    for i, a in enumerate((0.05, 0.4)):
        ref = eval_np(load(diffuse_reflectance=0.0, alpha_u=a, alpha_v=0.1), wi, wo)
        np.testing.assert_allclose(f[i], ref[0], rtol=1e-5)
    assert abs(f[0, 0] - f[1, 0]) > 0.1 * f.max()


def test_parameters_from_xml():
    b = load_xml(PLUGIN, '<float name="alpha_u" value="0.0001"/><float name="alpha_v" value="1"/>')
    assert b.component_count() == 2
    assert "form = balanced" in str(load_xml(PLUGIN, '<string name="form" value="balanced"/>'))


# -- hard cases stay finite --------------------------------------------------------------------

def test_smooth_lobe_is_not_lost_to_rounding():
    """At alpha = 1e-4 the albedo is cos(theta) (see above) and the samples spread around
    the mirror direction by ~1e-4 rad."""
    b = load(specular_reflectance=1.0, diffuse_reflectance=0.0, alpha_u=1e-4, alpha_v=1e-4)
    wi = sph(np.radians(30), 0.0)[0]
    _, (bs, w) = sample_bsdf(b, wi, 100_000)
    np.testing.assert_allclose(to_np(w).mean(axis=0), np.cos(np.radians(30)), rtol=2e-3)
    m = sph(np.radians(30), np.pi)[0]
    wo = to_np(bs.wo).astype(float)
    angle = np.linalg.norm(np.cross(wo, m), axis=1)
    # the angle of h to n is Rayleigh(alpha / sqrt 2)-like; wo moves twice as far
    assert 0.5e-4 < np.median(angle) < 4e-4, np.median(angle)


# -- parameters through mi.traverse, renders ---------------------------------------------------

def test_traverse_and_update():
    scene = small_scene({"type": PLUGIN, "id": "mat", "diffuse_reflectance": 0.0}, res=16)
    params = mi.traverse(scene)
    check_update_changes_render(scene, params, param_key(params, "alpha_v.value"), 0.4)
    check_update_changes_lobes(scene, params, param_key(params, "diffuse_reflectance.value"), 0.5,
                               before=1, after=2)


