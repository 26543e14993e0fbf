"""Every parameter of every registered plugin through ``mi.traverse``.

Generic over ``mitsuba_brdfs.plugin_models()``: for each plugin, loaded with its defaults
(every lobe present) as a top-level BSDF ``mat`` of a small scene,

- each texture the model declares (``_textures()``) is exposed, differentiable, as
  ``mat.<name>.value`` (constant) or ``mat.<name>.data`` (bitmap), and no texture held by
  the plugin is left out;
- the continuous parameters of the plugin contract, which each model declares, are all
  exposed;
- changing one value through ``params.update()`` changes the render, and gives exactly the
  render of a scene loaded afresh with that value (same seed): whatever the plugin
  precomputes from its parameters is recomputed in ``parameters_changed``.
"""
import gc

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import mitsuba_brdfs
from checks import FACTS, check_declared, small_scene

PLUGINS = sorted(mitsuba_brdfs.plugin_models())

#: continuous (differentiable) parameters of the package's models, as each model declares
#: them (``FACTS.differentiable``); enums, integers and load-time options are not
#: parameters of the render and are not listed
EXPECTED = {name: FACTS[name].differentiable for name in PLUGINS}

RES, SPP, SEED = 16, 2, 7


def materialize(bsdf):
    """A copy of ``bsdf`` whose bitmap data (numpy) become new tensors.

    The bitmap plugin takes over the tensor it is given, so each load gets its own.
    """
    return {k: ({**v, "data": mi.TensorXf(v["data"])} if isinstance(v, dict) and "data" in v else v)
            for k, v in bsdf.items()}


def scene_with(bsdf):
    """A sphere of BSDF ``mat`` under a point light (highlight) and a dim environment."""
    return small_scene(materialize(bsdf), RES, spp=SPP, env=0.3, shared=True)


def render(scene, params=None):
    return np.array(mi.render(scene, params, spp=SPP, seed=SEED))


def declared(scene):
    return list(scene.shapes()[0].bsdf()._textures())


def texture_key(params, name):
    for suffix in (".value", ".data"):
        if f"mat.{name}{suffix}" in params:
            return f"mat.{name}{suffix}"
    return None


def perturbed(value):
    """A clearly different value in the same range: [0, 1] stays in [0, 1], > 1 grows."""
    v = np.asarray(value, dtype=np.float64)
    return np.where(v < 0.5, v + 0.3, np.where(v <= 1.0, v - 0.3, v * 1.5))


def as_param(like, array):
    """``array`` (numpy) in the Dr.Jit type of the parameter ``like``."""
    if isinstance(like, mi.TensorXf):
        return mi.TensorXf(np.asarray(array, dtype=np.float32).reshape(like.shape))
    # from Python numbers, as a user writes ``mi.Float(0.5)``: a width-1 array built from
    # numpy is stored with another alignment, which Dr.Jit compiles as a different
    # (equally opaque) gather the first time it sees one
    values = [float(v) for v in np.asarray(array, dtype=np.float32).ravel()]
    return type(like)(*values) if dr.size_v(like) > 1 else type(like)(values)


def as_property(like, array):
    """``array`` as a load_dict property of the same kind as the parameter ``like``."""
    a = np.asarray(array, dtype=np.float32)
    if isinstance(like, mi.TensorXf):
        return {"type": "bitmap", "data": a.reshape(like.shape), "raw": True}
    if dr.size_v(like) > 1:
        return {"type": "rgb", "value": a.ravel().tolist()}
    return float(a.ravel()[0])


def bitmap_defaults(name):
    """The plugin's defaults, every texture replaced by a 2x2 bitmap varying around it."""
    scene = scene_with({"type": name})
    params = mi.traverse(scene)
    d = {"type": name}
    ramp = np.array([[1.0, 0.9], [0.8, 0.95]])
    for tex in declared(scene):
        v = np.asarray(params[texture_key(params, tex)], dtype=np.float64).ravel()
        data = ramp[..., None] * v[None, None, :]
        d[tex] = {"type": "bitmap", "data": data.astype(np.float32), "raw": True}
    return d


def test_some_plugins_are_registered():
    assert "ashikhmin_shirley" in PLUGINS


@pytest.mark.parametrize("name", PLUGINS)
def test_declared_textures_are_exposed(name):
    scene = scene_with({"type": name})
    params = mi.traverse(scene)
    bsdf = scene.shapes()[0].bsdf()
    names = declared(scene)
    for tex in names:
        key = f"mat.{tex}.value"
        assert key in params, (name, key, list(params.keys()))
        assert not params.flags(key) & mi.ParamFlags.NonDifferentiable.value, (name, key)
    # no texture held by the plugin is missing from _textures() (hence from traverse)
    held = {id(v) for v in vars(bsdf).values() if isinstance(v, mi.Texture)}
    assert held <= {id(t) for t in bsdf._textures().values()}, name
    # the parameters of the plugin contract are all there, as textures or as plain values
    check_declared(name, "differentiable")
    for p in EXPECTED[name]:
        assert texture_key(params, p) or f"mat.{p}" in params, (name, p, list(params.keys()))


@pytest.mark.parametrize("name", PLUGINS)
def test_bitmap_textures_expose_their_data(name):
    scene = scene_with(bitmap_defaults(name))
    params = mi.traverse(scene)
    for tex in declared(scene):
        key = f"mat.{tex}.data"
        assert key in params, (name, key, list(params.keys()))
        assert not params.flags(key) & mi.ParamFlags.NonDifferentiable.value, (name, key)


def check_updates(name, base):
    """Perturb each parameter in turn: the render changes and equals a fresh load's.

    The updates first, then the fresh loads, each one gone before the next is made: a
    render traces every live BSDF, and a scene loaded where the last one was freed reuses
    its objects' ids, so every fresh load runs the kernel the first one compiled."""
    scene = scene_with(base)
    params = mi.traverse(scene)
    img0 = render(scene)
    assert np.isfinite(img0).all() and img0.max() > 0, name
    keys = [texture_key(params, t) for t in declared(scene)]
    keys += [f"mat.{p}" for p in EXPECTED[name] if f"mat.{p}" in params]
    updated = {}
    for key in keys:
        old = params[key]
        old_np = np.array(old, dtype=np.float64)
        new_np = perturbed(old_np)
        params[key] = as_param(old, new_np)
        params.update()
        tex = key[len("mat."):].rsplit(".", 1)[0] if key.count(".") > 1 else key[len("mat."):]
        updated[key] = (render(scene), tex, as_property(old, new_np), old_np, new_np)
        params[key] = as_param(old, old_np)
        params.update()
    # back at the original values, the original render
    np.testing.assert_allclose(render(scene), img0, rtol=1e-4, atol=1e-5, err_msg=name)
    del scene, params
    gc.collect()
    failures = []
    for key, (img1, tex, prop, old_np, new_np) in updated.items():
        fresh = scene_with({**base, tex: prop})
        img_fresh = render(fresh)
        del fresh
        gc.collect()
        if not np.abs(img1 - img0).max() > 1e-4:
            failures.append(f"{key}: {old_np.ravel()[:3]} -> {new_np.ravel()[:3]} leaves the render unchanged")
        elif not np.allclose(img1, img_fresh, rtol=1e-4, atol=1e-5):
            failures.append(f"{key}: after update the render differs from a fresh load "
                            f"(max diff {np.abs(img1 - img_fresh).max():.3g})")
    assert not failures, f"{name}:\n" + "\n".join(failures)


@pytest.mark.parametrize("name", PLUGINS)
def test_update_changes_render_constant(name):
    check_updates(name, {"type": name})


@pytest.mark.parametrize("name", PLUGINS)
def test_update_changes_render_bitmap(name):
    check_updates(name, bitmap_defaults(name))


@pytest.mark.parametrize("name", PLUGINS)
def test_update_reuses_kernel(name):
    """A new value of a parameter traces the same kernel (values are opaque, not literals).

    Kernels are compared by the hash of their IR: a baked-in constant changes the hash.
    (Comparing hashes rather than cache hits keeps the test immune to the kernel cache
    being flushed by other tests in the same process.) The first ``update()`` after a load
    may lay out the call data of the scene's BSDFs differently (Dr.Jit), a one-time
    recompile that does not depend on the values: the check starts after one.
    """
    scene = scene_with({"type": name})
    params = mi.traverse(scene)
    keys = [texture_key(params, t) for t in declared(scene)]
    for key in keys:
        params.set_dirty(key)
    params.update()

    def jit_hashes():
        return {h["hash"] for h in dr.kernel_history() if h["type"] == dr.KernelType.JIT}

    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()  # clear
        dr.eval(mi.render(scene, spp=SPP, seed=SEED))
        before = jit_hashes()
        after, changed = set(), []
        for key in keys:
            old = params[key]
            old_np = np.array(old, dtype=np.float64)
            if not old_np.any():
                continue  # from 0 a lobe may appear: a new kernel by design
            params[key] = as_param(old, old_np * 0.9)
            params.update()
            dr.eval(mi.render(scene, spp=SPP, seed=SEED))
            new = jit_hashes()
            after |= new
            if new - before:
                changed.append(key)
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert before and after, name
    assert not changed, f"{name}: a new value of {changed} compiled a different kernel"
