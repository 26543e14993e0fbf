"""Test setup: the llvm_ad_rgb variant on 2 threads, plugins registered, shared helpers."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

mi.set_variant("llvm_ad_rgb")
dr.set_thread_count(2)
import mitsuba_brdfs  # noqa: E402,F401  (registers the plugins)


@pytest.fixture(autouse=True)
def _llvm_rgb():
    """Every test starts in llvm_ad_rgb, whatever the previous one switched to."""
    if mi.variant() != "llvm_ad_rgb":
        mi.set_variant("llvm_ad_rgb")
    yield
    if mi.variant() != "llvm_ad_rgb":
        mi.set_variant("llvm_ad_rgb")


def sph(theta, phi):
    """Unit vectors from spherical angles (numpy, shape (N, 3))."""
    theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                     np.cos(theta)], axis=-1).reshape(-1, 3)


def random_upper(rng, n):
    """Directions spread over the upper hemisphere, grazing ones included."""
    return sph(np.arccos(rng.uniform(0.001, 1, n)), rng.uniform(0, 2 * np.pi, n))


def vec(a):
    a = np.asarray(a, dtype=np.float32).reshape(-1, 3)
    return mi.Vector3f(a[:, 0], a[:, 1], a[:, 2])


def interaction(wi):
    """A SurfaceInteraction3f with the given local wi (uv at the centre)."""
    wi = vec(wi)
    si = dr.zeros(mi.SurfaceInteraction3f, dr.width(wi))
    si.wi = wi
    si.uv = mi.Point2f(0.5, 0.5)
    return si


def to_np(x):
    """A Dr.Jit array (Float or Color3f) as numpy, shape (N,) or (N, C)."""
    a = np.array(x)
    return a.T if a.ndim == 2 else a


def sample_bsdf(bsdf, wi, n, seed=0, ctx=None):
    """n samples of ``bsdf`` at a fixed wi: (bs, weight) with arrays of width n."""
    ctx = ctx or mi.BSDFContext()
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(seed, n)
    si = interaction(np.repeat(np.asarray(wi, float).reshape(1, 3), n, axis=0))
    s1, s2 = sampler.next_1d(), sampler.next_2d()
    return si, bsdf.sample(ctx, si, s1, s2)


def small_scene(bsdf, res=24, integrator="path", max_depth=3):
    """A sphere lit by a point light and a dim environment, seen by a perspective camera."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": integrator, **({"max_depth": max_depth} if integrator == "path" else {})},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 4}},
        "ball": {"type": "sphere", "bsdf": bsdf},
        "light": {"type": "point", "position": [2, 2, 4], "intensity": {"type": "rgb", "value": 30}},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.2}},
    })
