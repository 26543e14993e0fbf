"""The generic tests of every model, written once and driven by what each model module
declares (``FACTS``, ``mitsuba_brdfs.core.facts``): eval against the model's float64
formula (``tests/reference.py``), sample weights = eval / pdf, reciprocity, Mitsuba's
chi-square test, the stability grid, and renders in ``llvm_ad_rgb``, ``scalar_rgb`` and the
spectral variants.

A new model is checked here without being listed: its module's ``FACTS`` fill ``cases``,
``chi2``, ``stability`` and ``renders`` (``test_every_model_declares_its_generic_cases``
says which is missing), and ``tests/reference.py`` holds its float64 formula. A model's own
test file holds only what is its own.
"""
import itertools

import mitsuba as mi
import numpy as np
import pytest

import reference as R
from checks import (CORNERS, CORNERS_FINE, FACTS, check_chi2, check_declared,
                    check_eval_pdf_finite, check_render, check_sample_weight_is_eval_over_pdf,
                    corner_samples, eval_both_ways, eval_np, eval_pairs, hard_directions,
                    hard_pairs, interaction, random_pairs, sph, to_np, vec)
from mitsuba_brdfs.validate.probe import call_sample
from mitsuba_brdfs import plugin_models

PLUGINS = sorted(plugin_models())


def _ids(plugin, settings):
    return plugin + "".join(f"-{k}={v}" for k, v in settings.items()
                            if not isinstance(v, dict))


def _cases():
    return [(p, s, rtol) for p in PLUGINS for s, rtol in FACTS[p].cases]


def _load(plugin, settings):
    return mi.load_dict({"type": plugin, **settings})


def _plain(settings):
    """The settings as the float64 formulas take them: an ``rgb`` colour as its values."""
    return {k: v["value"] if isinstance(v, dict) and v.get("type") == "rgb" else v
            for k, v in settings.items()}


@pytest.mark.parametrize("plugin", PLUGINS)
def test_every_model_declares_its_generic_cases(plugin):
    """The settings of this file come from the models' own declarations: a new model is
    not silently left out of them."""
    check_declared(plugin, "cases", "chi2", "stability", "renders")


# -- eval against the float64 formula -----------------------------------------------------------

@pytest.mark.parametrize("plugin,settings,rtol", _cases(),
                         ids=[_ids(p, s) for p, s, _ in _cases()])
def test_eval_matches_float64(plugin, settings, rtol):
    """eval = f cos(theta_o) of the float64 formula at random pairs, exact mirror pairs
    (h = n) and the normal, for the float32 directions the plugin sees."""
    wi, wo = eval_pairs()
    want = R.f(plugin, wi, wo, **_plain(settings)) * wo[:, 2:3]
    got = eval_np(_load(plugin, settings), wi, wo)
    np.testing.assert_allclose(got, np.broadcast_to(want, got.shape), rtol=rtol,
                               atol=1e-6 * want.max(), err_msg=_ids(plugin, settings))


# -- sampling ------------------------------------------------------------------------------------

@pytest.mark.parametrize("plugin,settings,rtol", _cases(),
                         ids=[_ids(p, s) for p, s, _ in _cases()])
def test_sample_weight_is_eval_over_pdf(plugin, settings, rtol):
    """From theta_i = 0, 40, 80 and 89 deg (one batch): most samples succeed, each one's
    pdf is pdf(wo) and its weight eval(wo) / pdf(wo), failed samples weigh 0, eval_pdf is
    eval and pdf, directions are unit vectors."""
    wi = np.concatenate([sph(np.radians(t), 1.0) for t in (0, 40, 80, 89)])
    check_sample_weight_is_eval_over_pdf(_load(plugin, settings), wi, min_valid=0.3,
                                         pdf_rtol=1e-5, weight_rtol=1e-4, weight_atol=1e-7,
                                         unit_wo=True, n=10000, tag=_ids(plugin, settings))


def _chi2():
    return [(p, label, s, theta, ires) for p in PLUGINS for label, s, theta, ires in
            FACTS[p].chi2]


@pytest.mark.parametrize("plugin,label,settings,theta,ires", _chi2(),
                         ids=[f"{c[0]}-{c[1]}" for c in _chi2()])
def test_chi2(plugin, label, settings, theta, ires):
    """Mitsuba's chi-square test of the sampled directions against pdf() (a ``component``
    entry selects that lobe alone, the way a context does)."""
    check_chi2(plugin, settings, theta, res=161, ires=ires)


# -- reciprocity -----------------------------------------------------------------------------------

def _reciprocal(plugin, settings):
    """False where the model declares these settings not reciprocal."""
    return not any(all(settings.get(k) == v for k, v in part.items())
                   for part in FACTS[plugin].not_reciprocal)


@pytest.mark.parametrize("plugin,settings,rtol", _cases(),
                         ids=[_ids(p, s) for p, s, _ in _cases()])
def test_reciprocity(plugin, settings, rtol):
    """f(a, b) = f(b, a) (radiance and importance transport give the same values); a model
    declared not reciprocal at these settings shows it, and swaps its directions under
    importance transport."""
    a, b = random_pairs(3, 3000)
    bsdf = _load(plugin, settings)
    f_ab, f_ba = eval_both_ways(bsdf, a, b)
    scale = max(np.abs(f_ab).max(), np.abs(f_ba).max(), 1e-30)
    off = np.abs(f_ab - f_ba) / scale
    importance = eval_np(bsdf, a, b, mi.BSDFContext(mi.TransportMode.Importance))
    radiance = eval_np(bsdf, a, b)
    if _reciprocal(plugin, settings):
        assert off.max() < 1e-3, (_ids(plugin, settings), off.max())
        np.testing.assert_allclose(importance, radiance, rtol=1e-6, atol=1e-7 * scale)
    else:
        assert off.max() > 1e-2, (_ids(plugin, settings), "reciprocal after all")
        assert np.abs(importance - radiance).max() > 1e-3 * scale


# -- the stability grid ----------------------------------------------------------------------------

def _grid(plugin):
    """Every combination of each of the model's grids (one, or a tuple of them)."""
    grids = FACTS[plugin].stability
    grids = (grids,) if isinstance(grids, dict) else grids
    return [dict(zip(g, values)) for g in grids for values in itertools.product(*g.values())]


@pytest.mark.parametrize("plugin", PLUGINS)
def test_stability_grid(plugin):
    """Every combination of the model's extreme settings (``FACTS.stability``) at every pair
    of hard directions (h = n, grazing at 1e-7, on the horizon, wi = -wo, below the horizon)
    and at corner samples: eval, pdf, weights finite and >= 0, sampled directions finite
    and unit where their pdf is not 0."""
    d = hard_directions()
    wi, wo = hard_pairs(d, mirrored=10)  # wi = -wo as well
    samples = corner_samples(d, CORNERS_FINE, CORNERS)
    # a model that is not reciprocal swaps its directions under importance transport
    modes = [mi.TransportMode.Radiance] + [mi.TransportMode.Importance] * bool(
        FACTS[plugin].not_reciprocal)
    for settings, mode in itertools.product(_grid(plugin), modes):
        tag = f"{_ids(plugin, settings)} {mode}"
        b, ctx = _load(plugin, settings), mi.BSDFContext(mode)
        check_eval_pdf_finite(b, ctx, wi, wo, tag)
        bs, w = call_sample(b, ctx, *samples)
        w, pdf, swo = to_np(w), to_np(bs.pdf), to_np(bs.wo)
        assert np.isfinite(w).all() and (w >= 0).all(), tag
        assert np.isfinite(pdf).all() and (pdf >= 0).all(), tag
        assert np.isfinite(swo).all(), tag
        up = pdf > 0
        np.testing.assert_allclose(np.linalg.norm(swo[up], axis=1), 1, atol=1e-5, err_msg=tag)


# -- renders ---------------------------------------------------------------------------------------

def _renders():
    return [(p, label, s) for p in PLUGINS for label, s in FACTS[p].renders]


@pytest.mark.parametrize("integrator", ["path", "direct"])
@pytest.mark.parametrize("plugin,label,settings", _renders(),
                         ids=[f"{r[0]}-{r[1]}" for r in _renders()])
def test_render_llvm(plugin, label, settings, integrator):
    check_render({"type": plugin, **settings}, integrator=integrator, msg=label)


@pytest.mark.parametrize("plugin", PLUGINS)
def test_scalar_and_spectral_variants(plugin):
    """The first of the model's renders in scalar_rgb; in the spectral variants its colour
    given as an RGB colour evaluates to finite positive values at four wavelengths, and
    renders in llvm_ad_spectral."""
    label, settings = FACTS[plugin].renders[0]
    mi.set_variant("scalar_rgb")
    check_render({"type": plugin, **settings}, res=6, spp=2, msg=label)
    colour = {FACTS[plugin].colour: {"type": "rgb", "value": [0.9, 0.5, 0.2]}}
    for variant in ("scalar_spectral", "llvm_ad_spectral"):
        mi.set_variant(variant)
        b = mi.load_dict({"type": plugin, **colour})
        v = to_np(b.eval(mi.BSDFContext(), interaction(np.array([[0.0, 0.0, 1.0]])),
                         vec([[0.6, 0.0, 0.8]]))) if variant.startswith("llvm") else \
            np.array(b.eval(mi.BSDFContext(), _scalar_si(), mi.ScalarVector3f(0.6, 0, 0.8)))
        assert np.isfinite(v).all() and (v > 0).all(), (variant, v)
    check_render({"type": plugin, **colour}, res=8, spp=2)


def _scalar_si():
    import drjit as dr
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(0, 0, 1)
    si.wavelengths = mi.Spectrum(450, 500, 600, 650)
    return si
