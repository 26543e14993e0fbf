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
from checks import (CORNERS, CORNERS_FINE, FACTS, blocks, check_chi2, check_declared,
                    check_eval_pdf_finite, check_sample_weight_is_eval_over_pdf,
                    corner_samples, eval_both_ways, eval_np, eval_pairs, hard_directions,
                    hard_pairs, one_scene_at_a_time, random_pairs, rendered, sph,  # noqa: F401
                    to_np)
from mitsuba_brdfs.validate.probe import call_sample
from mitsuba_brdfs import plugin_models

PLUGINS = sorted(plugin_models())
#: a render traces every live BSDF: each test's scenes are gone before the next renders
pytestmark = pytest.mark.usefixtures("one_scene_at_a_time")


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

@pytest.mark.parametrize("integrator", ["path", "direct"])
@pytest.mark.parametrize("plugin", PLUGINS)
def test_renders(plugin, integrator):
    """The model's renders (``FACTS.renders``), each setting a sphere of one grid scene (one
    kernel): every sphere finite and lit. (Every plugin in every other variant, scalar and
    spectral among them: tests/test_variants.py; every input form in the spectral
    variants: tests/test_inputs.py.)"""
    cells = {label: {"type": plugin, **settings} for label, settings in FACTS[plugin].renders}
    img = rendered(cells, integrator={"type": integrator, **(
        {"max_depth": 3} if integrator == "path" else {})})
    assert np.isfinite(img).all(), plugin
    for label, block in blocks(img, cells).items():
        assert block.mean() > 1e-3, (plugin, label, block.mean())
