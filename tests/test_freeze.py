"""Frozen functions (``@dr.freeze``) with the plugins: a replayed render is the traced one,
and an update that adds or removes a lobe makes the frozen function record anew."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mitsuba_brdfs.sphere import sphere_scene


def _render(scene, seed):
    return mi.render(scene, seed=seed)


# each starts without a lobe: a replay of that recording would miss it once it is back
@pytest.mark.parametrize("bsdf,key,values", [
    # no diffuse lobe (0), then one (0.5), none again, one again
    ({"type": "lambert", "reflectance": 0.0}, "reflectance", [0.0, 0.0, 0.5, 0.5, 0.0, 0.3]),
    # Rd = 0: a metal, no diffuse lobe; Rd > 0: two lobes
    ({"type": "ashikhmin_shirley", "diffuse_reflectance": 0.0, "nu": 50.0, "nv": 50.0},
     "diffuse_reflectance", [0.0, 0.0, 0.5, 0.0, 0.2]),
    # Rs = 1 leaves no light to the diffuse layer (eq. 5's 1 - Rs): no diffuse lobe
    ({"type": "ashikhmin_shirley", "diffuse_reflectance": 0.5, "specular_reflectance": 1.0},
     "specular_reflectance", [1.0, 1.0, 0.5, 0.9, 1.0]),
])
def test_replayed_render_follows_the_lobes(bsdf, key, values):
    scene = sphere_scene(bsdf, res=16, spp=2)
    params = mi.traverse(scene)
    frozen = dr.freeze(_render)
    for v in values:
        params[f"ball.bsdf.{key}.value"] = v
        params.update()
        replayed = np.array(frozen(scene, mi.UInt32(3)))
        traced = np.array(_render(scene, mi.UInt32(3)))
        np.testing.assert_allclose(replayed, traced, rtol=1e-5, atol=1e-6, err_msg=f"{key} = {v}")
    # one recording per set of lobes (two sets each here), and Dr.Jit's second one for the
    # first set (which makes its literals opaque): back to a set seen before replays
    assert frozen.n_recordings <= 3


def test_frozen_gradient_is_the_traced_one():
    """Backpropagating through a replayed render gives the traced render's gradient."""
    scene = sphere_scene({"type": "ashikhmin_shirley", "nu": 30.0, "nv": 30.0}, res=16, spp=2,
                         integrator="prb")
    params = mi.traverse(scene)
    key = "ball.bsdf.nu.value"

    def grad_of_mean(scene, seed):
        img = mi.render(scene, mi.traverse(scene), seed=seed)
        dr.backward(dr.mean(img, axis=None))

    frozen = dr.freeze(grad_of_mean)
    for nu in (30.0, 40.0, 50.0):
        grads = []
        for f in (frozen, grad_of_mean):
            params[key] = mi.Float(nu)
            dr.enable_grad(params[key])
            params.update()
            f(scene, mi.UInt32(5))
            grads.append(dr.grad(params[key]).array[0])
        assert grads[0] != 0 and np.isclose(grads[0], grads[1], rtol=1e-4), (nu, grads)
    assert frozen.n_recordings <= 2
