"""Calling a BSDF on NumPy directions: interactions, eval, pdf and samples as arrays."""
import drjit as dr
import mitsuba as mi
import numpy as np

__all__ = ["expect", "vec", "interaction", "to_np", "sample_bsdf", "load_bsdf", "context",
           "eval_np", "pdf_np"]


def expect(condition, message=None):
    """Raise ``AssertionError(message)`` unless ``condition`` (an ``assert`` that ``python -O``
    keeps)."""
    if not condition:
        raise AssertionError() if message is None else AssertionError(message)


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
    """n samples of ``bsdf`` at a fixed wi: (si, (bs, weight)) with arrays of width n."""
    ctx = ctx or mi.BSDFContext()
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(seed, n)
    si = interaction(np.repeat(np.asarray(wi, float).reshape(1, 3), n, axis=0))
    s1, s2 = sampler.next_1d(), sampler.next_2d()
    return si, bsdf.sample(ctx, si, s1, s2)


def load_bsdf(plugin, **kw):
    """The plugin with the given parameters; lists and tuples become RGB colours."""
    d = {"type": plugin}
    for k, v in kw.items():
        d[k] = {"type": "rgb", "value": v} if isinstance(v, (list, tuple)) else v
    return mi.load_dict(d)


def context(**attrs):
    """A BSDFContext with the given attributes set (component, type_mask, ...)."""
    ctx = mi.BSDFContext()
    for k, v in attrs.items():
        setattr(ctx, k, v)
    return ctx


def eval_np(bsdf, wi, wo, ctx=None):
    return to_np(bsdf.eval(ctx or mi.BSDFContext(), interaction(wi), vec(wo)))


def pdf_np(bsdf, wi, wo, ctx=None):
    return to_np(bsdf.pdf(ctx or mi.BSDFContext(), interaction(wi), vec(wo)))
