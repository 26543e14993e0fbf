"""Gradients of the plugins: reverse mode against finite differences, forward against reverse,
and finite gradients at the hard cases of the stability grid.

The scene of the finite-difference check is a sphere lit by a single point light, with
nothing else to see or to hit. Its Monte Carlo estimate is then a smooth function of the
parameters for a fixed seed: the light is a delta (no sampled light position, MIS weight 1),
continuation rays drawn from the BSDF escape and add nothing, and the pixel positions depend
on the seed only. The adjoint pass of ``prb`` replays the primal path with ``seed_grad``, so a
central difference of two primal renders with that same seed differentiates exactly the
estimator that the adjoint pass differentiates. What remains between them is the central
difference's truncation error (O(h^2), ~1e-4 relative at h = 1% of the value) and float32
rounding in the renders (~1e-6 relative per pixel, amplified by 1/(2h) to ~1e-4); measured
agreement is 1e-4 to 1e-3. The tolerance of 1% leaves room for other machines and is still
far below the error of a wrong derivative (a missing factor or term is off by tens of %).
(With sampled lights or an environment the two estimators differ by Monte Carlo noise:
directions drawn from the BSDF move with the parameter in the primal renders, not in prb's
adjoint pass, which differentiates ``eval`` alone.)
"""
import itertools

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import mitsuba_brdfs

from checks import (FACTS, floats, hard_directions, interaction, one_scene_at_a_time,  # noqa: F401
                    point2, small_scene, to_np, vec)

PLUGINS = sorted(mitsuba_brdfs.plugin_models())
#: a render traces every live BSDF (prb's adjoint pass too): what earlier tests of the
#: process left is gone before each test renders
pytestmark = pytest.mark.usefixtures("one_scene_at_a_time")

#: plugin -> (settings, parameters whose gradient is checked against finite differences),
#: for the models that declare them (``FACTS.finite_difference``)
FD_CASES = {name: FACTS[name].finite_difference for name in PLUGINS
            if FACTS[name].finite_difference}
FD_PARAMS = [(name, p) for name, (_, ps) in FD_CASES.items() for p in ps]

RES, SPP, SEED, SEED_GRAD = 32, 4, 3, 4
#: relative step of the central difference
H_REL = 1e-2
#: relative tolerance of AD against FD (see the module docstring)
FD_RTOL = 1e-2
#: forward and reverse mode differentiate the same estimator with the same samples: they
#: differ only by the order of float32 accumulations
MODE_RTOL = 1e-3


def point_lit_scene(bsdf):
    """The sphere of BSDF ``mat`` under the point light alone (see the module docstring)."""
    return small_scene(bsdf, RES, {"type": "prb", "max_depth": 2}, spp=SPP, env=None, shared=True)


def key_of(params, name):
    for k in (f"mat.{name}.value", f"mat.{name}"):
        if k in params:
            return k
    raise KeyError(f"mat.{name}.value not in {list(params.keys())}")


def image_mean(img):
    return float(np.mean(np.array(img, dtype=np.float64)))


def grad_sum(x):
    """d(loss)/d(parameter) when every component of the parameter moves together."""
    return float(np.sum(np.array(dr.grad(x), dtype=np.float64)))


def set_value(params, key, array):
    """Assign a numpy value to a Float or a colour parameter."""
    a = np.asarray(array, dtype=np.float32)
    params[key] = type(params[key])(*a) if a.ndim > 1 else type(params[key])(a)


@pytest.fixture(scope="module")
def measured():
    """Collects (AD, forward, FD) per parameter for the summary printed at the end."""
    table = {}
    yield table
    if table:
        print("\nparameter                                 reverse        forward        FD")
        for k, (g, gf, fd) in table.items():
            print(f"{k:40s} {g:+.6e} {gf:+.6e} {fd:+.6e}")


@pytest.mark.parametrize("name,param", FD_PARAMS)
def test_gradient_matches_finite_difference(name, param, measured):
    settings, _ = FD_CASES[name]
    scene = point_lit_scene({"type": name, **settings})
    params = mi.traverse(scene)
    key = key_of(params, param)
    p0 = np.array(params[key], dtype=np.float64)

    # reverse mode: d mean(image) / d p
    dr.enable_grad(params[key])
    params.update()
    img = mi.render(scene, params, spp=SPP, seed=SEED, seed_grad=SEED_GRAD)
    dr.backward(dr.mean(img, axis=None))
    g = grad_sum(params[key])

    # forward mode, all components of the parameter moved by 1
    dr.disable_grad(params[key])
    params.update()
    dr.enable_grad(params[key])
    params.update()
    img = mi.render(scene, params, spp=SPP, seed=SEED, seed_grad=SEED_GRAD)
    dr.forward(params[key])
    gf = image_mean(dr.grad(img))
    dr.disable_grad(params[key])
    params.update()

    # central difference of primal renders with the adjoint pass's seed
    h = H_REL * float(np.abs(p0).max())
    vals = []
    for sign in (1, -1):
        set_value(params, key, p0 + sign * h)
        params.update()
        vals.append(image_mean(mi.render(scene, params, spp=SPP, seed=SEED_GRAD)))
    fd = (vals[0] - vals[1]) / (2 * h)
    measured[f"{name}.{param} = {p0.ravel()[0]:g}"] = (g, gf, fd)

    assert np.isfinite([g, gf, fd]).all(), (g, gf, fd)
    assert abs(fd) > 1e-7, f"{name}.{param}: the image does not depend on it (FD = {fd})"
    assert abs(g - fd) <= FD_RTOL * abs(fd), f"{name}.{param}: AD {g:.6e} vs FD {fd:.6e}"
    assert abs(gf - g) <= MODE_RTOL * abs(g), f"{name}.{param}: forward {gf:.6e} vs reverse {g:.6e}"


# -- hard cases: finite gradients ---------------------------------------------------------

def hard_cases():
    cases = []
    for name in PLUGINS:
        # settings at the edges of its parameter ranges, every lobe present or one dropped
        # (``FACTS.gradient_edges``; its defaults when it declares none)
        for s in FACTS[name].gradient_edges:
            cases.append(pytest.param(name, s, id=name + "-" + "-".join(f"{k}={v}" for k, v in s.items())))
    return cases


def _differentiate_everything(bsdf):
    """Enable gradients on every parameter and on the directions, call eval/pdf/sample at
    the hard directions with corner samples, backpropagate a gradient of 1 on every output
    (that of the sum of them all, without evaluating the outputs first); return the
    gradients as numpy arrays by name (evaluated together: one kernel per batch)."""
    params = mi.traverse(bsdf)
    keys = [k for k in params.keys()
            if not params.flags(k) & mi.ParamFlags.NonDifferentiable.value
            and dr.is_diff_v(params[k])]
    for k in keys:
        dr.enable_grad(params[k])
    params.update()
    d = hard_directions()
    pairs = np.array(list(itertools.product(range(len(d)), repeat=2)))
    ctx = mi.BSDFContext()
    si = interaction(d[pairs[:, 0]])
    wo = vec(d[pairs[:, 1]])
    dr.enable_grad(si.wi, wo)
    f, pdf = bsdf.eval_pdf(ctx, si, wo)
    outputs = [f, pdf, bsdf.eval(ctx, si, wo), bsdf.pdf(ctx, si, wo)]
    u = np.array([0, 1e-7, 0.25, 0.5, 0.75, 1 - 2**-24])
    g1, g2, g3, gi = np.meshgrid(u, u, u, np.arange(len(d)), indexing="ij")
    si_s = interaction(d[gi.ravel()])
    dr.enable_grad(si_s.wi)
    bs, w = bsdf.sample(ctx, si_s, floats(g1), point2(g2, g3))
    outputs += [w, bs.pdf, bs.wo]
    for x in outputs:
        dr.set_grad(x, 1.0)
    dr.enqueue(dr.ADMode.Backward, *outputs)
    dr.traverse(dr.ADMode.Backward)
    grads = {k: dr.grad(params[k]) for k in keys}
    grads.update(wi=dr.grad(si.wi), wo=dr.grad(wo), sampled_wi=dr.grad(si_s.wi))
    dr.eval(*grads.values())
    return {k: to_np(g) for k, g in grads.items()}


@pytest.mark.parametrize("name,settings", hard_cases())
def test_gradients_finite_at_hard_cases(name, settings):
    """Finite derivatives w.r.t. every parameter, and w.r.t. wi and wo (which
    reparameterising integrators differentiate), at the hard directions and samples."""
    grads = _differentiate_everything(mi.load_dict({"type": name, **settings}))
    assert len(grads) > 3, name
    bad = [k for k, g in grads.items() if not np.isfinite(g).all()]
    assert not bad, f"{name} {settings}: non-finite gradient w.r.t. {bad}"
