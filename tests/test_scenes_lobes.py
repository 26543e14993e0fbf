"""The plugins' lobes in the scenes Mitsuba users build.

- A lobe that a zero colour removes comes back when ``params.update()`` raises the colour,
  inside every wrapper (none, twosided, blendbsdf, mask, normalmap, bumpmap): the render
  equals that of the scene loaded with the raised value, and the other way round.
- Absent lobes are not traced, measured: the IR of a metal (no diffuse lobe) and of a
  black ``lambert`` is smaller than with the lobe, and grows when the lobe is raised; every
  model's lobe of zero weight leaves its own kernels smaller; with a gradient enabled the
  lobe is traced, and the gradient at black is not zero (prb).

The scenes put several spheres on a grid seen face-on by a distant camera, so that each
sphere fills one block of pixels (``checks.blocks``) and one render covers many cases;
``test_scenes.py`` renders every plugin under the integrators and lights.
"""
import copy
import gc

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import mitsuba_brdfs
from checks import (FACTS, SEED, SPP, blocks, check_declared, grid_scene,  # noqa: F401
                    one_scene_at_a_time, render)
from mitsuba_brdfs.timing import bsdf_instructions, kernel_stats

PLUGINS = sorted(mitsuba_brdfs.plugin_models())

pytestmark = pytest.mark.usefixtures("one_scene_at_a_time")


# -- 1. a zero lobe raised through traverse, in every wrapper ------------------------------------

WRAPPERS = ("none", "twosided", "blendbsdf", "mask", "normalmap", "bumpmap")


@pytest.fixture(scope="module")
def flat_normalmap(tmp_path_factory):
    """A normal map of the unperturbed normal, (0.5, 0.5, 1) in the map's encoding."""
    path = tmp_path_factory.mktemp("normalmap") / "flat.exr"
    mi.Bitmap(np.tile(np.array([0.5, 0.5, 1.0], np.float32), (2, 2, 1))).write(str(path))
    return str(path)


def wrapped(kind, bsdf, normalmap):
    """``bsdf`` (a dict, copied) inside the wrapper ``kind``."""
    b = copy.deepcopy(bsdf)
    if kind == "none":
        return b
    if kind == "twosided":
        return {"type": "twosided", "bsdf": b}
    if kind == "blendbsdf":
        return {"type": "blendbsdf", "weight": 0.6, "bsdf_0": b,
                "bsdf_1": {"type": "diffuse", "reflectance": 0.2}}
    if kind == "mask":
        return {"type": "mask", "opacity": 0.7, "bsdf": b}
    if kind == "normalmap":
        return {"type": "normalmap", "bsdf": b,
                "normalmap": {"type": "bitmap", "filename": normalmap, "raw": True}}
    if kind == "bumpmap":
        return {"type": "bumpmap", "bsdf": b, "arbitrary": {"type": "uniform", "value": 0.3}}
    raise ValueError(kind)


def rgb(v):
    return {"type": "rgb", "value": [float(v)] * 3}


def value(param, v):
    """A colour as <rgb>, a weight (cook_torrance's k) as a float."""
    return float(v) if param == "k" else rgb(v)


#: (plugin, parameter, value that removes a lobe, value that gives it back, other parameters):
#: every model's ``FACTS.zero_lobes``
ZERO_LOBES = [(p, *case) for p in PLUGINS for case in FACTS[p].zero_lobes]


def case_id(case):
    return f"{case[0]}-{case[1]}-{case[2]}"


def wrapper_scene(state, normalmap):
    """Every case of ZERO_LOBES (a row) in every wrapper (a column), with each case's
    parameter at ``state`` ("zero" or "raised"); each sphere holds its own instance (the
    loader would otherwise merge identical BSDFs into one)."""
    cells = {}
    for case in ZERO_LOBES:
        plugin, param, zero, raised, extra = case
        bsdf = {"type": plugin, param: value(param, zero if state == "zero" else raised), **extra}
        for w in WRAPPERS:
            cells[f"{case_id(case)}_{w}"] = wrapped(w, bsdf, normalmap)
    return grid_scene(cells, cols=len(WRAPPERS), optimize=False)


def case_keys(params, case):
    """The traverse keys of a case's parameter, one per wrapper (not the blend's partner)."""
    return [k for k in params.keys() if k.startswith(f"{case_id(case)}_")
            and k.endswith(f".{case[1]}.value") and ".bsdf_1." not in k]


def set_cases(params, state):
    for case in ZERO_LOBES:
        v = case[2] if state == "zero" else case[3]
        for k in case_keys(params, case):
            params[k] = type(params[k])(float(v))
    params.update()


def lobes_present(scene, case):
    bsdf = next(s.bsdf() for s in scene.shapes() if s.id() == f"{case_id(case)}_none")
    return sum(bsdf._present)


def compare_blocks(got, want, names, what):
    """One line per block where ``got`` differs from ``want``."""
    got, want = blocks(got, names, len(WRAPPERS)), blocks(want, names, len(WRAPPERS))
    return [f"{n}: {what}: mean {got[n].mean():.5f} vs {want[n].mean():.5f}" for n in names
            if not np.allclose(got[n], want[n], rtol=1e-5, atol=1e-6)]


def load_render_update_render(state, other, normalmap):
    """Load the wrapper scene at ``state``, render, set every case to ``other`` through
    mi.traverse, render again: (scene facts, image before, image after).

    One scene is alive at a time: a render traces the methods of every live BSDF.
    """
    scene = wrapper_scene(state, normalmap)
    present = {case_id(c): lobes_present(scene, c) for c in ZERO_LOBES}
    before = render(scene)
    params = mi.traverse(scene)
    keys = {case_id(c): len(case_keys(params, c)) for c in ZERO_LOBES}
    set_cases(params, other)
    after = render(scene)
    del scene, params
    gc.collect()
    return {"present": present, "keys": keys}, before, after


def test_zero_lobe_raised_through_traverse(flat_normalmap):
    """Every case of ZERO_LOBES in every wrapper, loaded with the lobe removed, then raised
    through mi.traverse: the render equals the scene loaded with the raised values; and
    the scene loaded raised, lowered through mi.traverse, renders as the one loaded with
    the lobes removed (same seed). Before the flags were fixed at build time, lambert in
    twosided rendered black after the update."""
    for p in PLUGINS:
        check_declared(p, "zero_lobes")
    names = [f"{case_id(c)}_{w}" for c in ZERO_LOBES for w in WRAPPERS]
    facts_low, img_low, img_raised = load_render_update_render("zero", "raised", flat_normalmap)
    facts_high, img_high, img_lowered = load_render_update_render("raised", "zero", flat_normalmap)
    for c in map(case_id, ZERO_LOBES):
        assert facts_low["present"][c] == facts_high["present"][c] - 1, \
            f"{c}: the value does not remove a lobe"
        # the keys reach through every wrapper
        assert facts_low["keys"][c] == len(WRAPPERS), (c, facts_low["keys"][c])
    assert np.isfinite(img_low).all() and np.isfinite(img_high).all()
    b_low, b_high = blocks(img_low, names, len(WRAPPERS)), blocks(img_high, names, len(WRAPPERS))
    dark = [n for n in names if not np.abs(b_low[n] - b_high[n]).max() > 1e-3]
    assert not dark, f"the lobe does not show in {dark}"
    failures = compare_blocks(img_raised, img_high, names, "raised")
    failures += compare_blocks(img_lowered, img_low, names, "lowered")
    assert not failures, "\n".join(failures)


# -- 2. absent lobes are not traced, and measured ------------------------------------------------

def bsdf_sizes(plugin, param, v, raise_to=None):
    """IR instructions of the BSDF's own sample and eval_pdf (``bsdf_instructions``), loaded
    with ``param = v``; with ``raise_to``, after setting it to that value through traverse."""
    gc.collect()
    bsdf = mi.load_dict({"type": plugin, param: v})
    params = mi.traverse(bsdf)
    if raise_to is not None:
        params[f"{param}.value"] = mi.Float(raise_to)
        params.update()
    sizes = bsdf_instructions(bsdf)
    del bsdf, params
    gc.collect()
    return sizes


def render_ops(plugin, param, v, raise_to=None):
    """IR operations of the render kernel of a sphere of the plugin with ``param = v``;
    with ``raise_to``, of the same scene after setting it to that value through traverse.
    Nothing else is alive meanwhile (a render traces every live BSDF)."""
    gc.collect()
    scene = grid_scene({"ball": {"type": plugin, param: v}}, cols=1)
    params = mi.traverse(scene)
    if raise_to is not None:
        kernel_stats(scene, spp=2)
        params[f"ball.bsdf.{param}.value"] = mi.Float(raise_to)
        params.update()
    ops = kernel_stats(scene, spp=2)["ops_max"]
    del scene, params
    gc.collect()
    return ops


METALS = [("ashikhmin_shirley", "diffuse_reflectance"), ("lambert", "reflectance")]


@pytest.mark.parametrize("plugin,param", METALS)
def test_absent_lobe_is_not_traced(plugin, param):
    """The BSDF's own sample and eval_pdf kernels, and the render kernel: smaller without
    the lobe, the size of the two-lobe BSDF once the lobe is raised through traverse."""
    metal, full = bsdf_sizes(plugin, param, 0.0), bsdf_sizes(plugin, param, 0.5)
    raised = bsdf_sizes(plugin, param, 0.0, raise_to=0.5)
    for what in ("sample", "eval_pdf"):
        assert metal[what] < full[what], (what, metal, full)
        assert raised[what] == full[what], (what, raised, full)
    if plugin == "lambert":  # no lobe at all: nothing of the BSDF is traced
        assert metal == {"sample": 0, "eval_pdf": 0}

    ops_metal, ops_full = render_ops(plugin, param, 0.0), render_ops(plugin, param, 0.5)
    ops_raised = render_ops(plugin, param, 0.0, raise_to=0.5)
    assert ops_metal < ops_full, (ops_metal, ops_full)
    assert ops_raised == ops_full, (ops_raised, ops_full)


def _dropped_lobe_pairs():
    from mitsuba_brdfs.bench.speed import drops_a_lobe, effect_pairs
    return [pytest.param(a, b, id=key) for key, a, b, what in effect_pairs()
            if drops_a_lobe(what)]


@pytest.mark.parametrize("a,b", _dropped_lobe_pairs())
def test_every_dropped_lobe_is_not_traced(a, b):
    """Every model's lobes of constant zero weight (``dropped_lobes`` of its facts, the
    pairs the study times): the BSDF's own sample and eval_pdf kernels are smaller than
    with the lobe weighted 1e-6."""
    without, kept = (bsdf_instructions(mi.load_dict(d)) for d in (a, b))
    for what in ("sample", "eval_pdf"):
        assert 0 < without[what] < kept[what], (what, without, kept)


def test_gradient_at_black_is_not_zero():
    """prb: with the gradient of a zero colour enabled, the removed lobe is traced and the
    gradient of the image w.r.t. that colour is positive in every channel (an
    optimisation may start from black), also inside a wrapper."""
    cells = {"metal": {"type": "ashikhmin_shirley", "diffuse_reflectance": rgb(0)},
             "black": {"type": "lambert", "reflectance": rgb(0)},
             "wrapped": {"type": "twosided", "bsdf": {"type": "lambert",
                                                      "reflectance": rgb(0)}}}
    scene = grid_scene(cells, integrator={"type": "prb", "max_depth": 3}, optimize=False)
    params = mi.traverse(scene)
    keys = {"metal": "metal.bsdf.diffuse_reflectance.value",
            "black": "black.bsdf.reflectance.value",
            "wrapped": next(k for k in params.keys() if k.startswith("wrapped.") and k.endswith("reflectance.value"))}
    for k in keys.values():
        dr.enable_grad(params[k])
    params.update()
    img = mi.render(scene, params, spp=SPP, seed=SEED)
    dr.backward(dr.mean(img, axis=None))
    grads = {n: np.array(dr.grad(params[k]), dtype=np.float64) for n, k in keys.items()}
    for n, g in grads.items():
        assert np.isfinite(g).all() and (g > 0).all(), (n, g)
