"""Calling a BSDF on NumPy directions: interactions, eval, pdf and samples as arrays."""
import drjit as dr
import mitsuba as mi
import numpy as np

__all__ = ["expect", "close", "aligned", "floats", "vec", "point2", "interaction", "unpolarized", "to_np", "rows",
           "call_eval", "call_pdf", "call_eval_pdf", "call_sample", "sample_bsdf", "short",
           "load_bsdf", "context", "eval_np", "pdf_np"]

#: wavelengths (nm) a spectral variant evaluates at
WAVELENGTHS = (450.0, 520.0, 590.0, 660.0)


def expect(condition, message=None):
    """Raise ``AssertionError(message)`` unless ``condition`` (an ``assert`` that ``python -O``
    keeps)."""
    if not condition:
        raise AssertionError() if message is None else AssertionError(message)


def close(actual, desired, rtol, atol=0.0):
    """How far ``actual`` is from ``desired`` in the sense of ``np.testing.assert_allclose``:
    ``ok`` when |actual - desired| <= atol + rtol |desired| everywhere, the largest relative
    error |actual - desired| / |desired| (absolute where desired is 0), and how many values
    (rows, for arrays of shape (N, C)) are off."""
    a, d = np.asarray(actual, float), np.asarray(desired, float)
    diff = np.abs(a - d)
    off = ~(diff <= atol + rtol * np.abs(d))  # NaN counts as off
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(d != 0, diff / np.abs(d), diff)
    rel = np.where(np.isnan(rel), np.inf, rel)
    rows = off.any(axis=tuple(range(1, off.ndim)))
    return {"ok": not off.any(), "max_rel": float(np.max(rel, initial=0.0)), "off": int(rows.sum())}


def aligned(a, dtype=np.float32):
    """A copy of ``a`` (as ``dtype``) in memory aligned to 64 bytes.

    Dr.Jit's LLVM backend reads a NumPy array where NumPy put it and compiles the kernel for
    that address's alignment (``align 64`` or ``align 1`` in the code it generates): the same
    computation on arrays NumPy happened to place differently is two kernels, a compilation
    each (~0.1 s), and a cache of kernels that hits or misses by chance. Arrays handed over
    through this function always give the first."""
    a = np.asarray(a, dtype)
    size = a.size * a.itemsize
    buf = np.empty(size + 64, np.uint8)
    start = -buf.ctypes.data % 64
    out = buf[start:start + size].view(dtype).reshape(a.shape)
    out[...] = a
    return out


def floats(a, kind=None):
    """``a`` (numbers, any shape) as a flat Dr.Jit array of ``kind`` (``mi.Float`` by
    default) through ``aligned``."""
    kind = kind or mi.Float
    dtype = {"UInt32": np.uint32, "Int32": np.int32, "Float64": np.float64}.get(
        kind.__name__, np.float32)
    return kind(aligned(np.ravel(a), dtype))


def vec(a):
    """Directions (N, 3) as a ``mi.Vector3f`` (``aligned``)."""
    a = np.asarray(a, dtype=np.float32).reshape(-1, 3)
    return mi.Vector3f(floats(a[:, 0]), floats(a[:, 1]), floats(a[:, 2]))


def point2(u, v):
    """Two sample coordinates as a ``mi.Point2f`` (``aligned``)."""
    return mi.Point2f(floats(u), floats(v))


def interaction(wi, n=None):
    """A SurfaceInteraction3f of width n (that of wi by default) with the local direction wi
    (numpy directions or a Dr.Jit vector), uv at the centre, the check wavelengths."""
    wi = wi if isinstance(wi, mi.Vector3f) else vec(wi)
    si = dr.zeros(mi.SurfaceInteraction3f, dr.width(wi) if n is None else n)
    si.wi = wi
    si.uv = mi.Point2f(0.5, 0.5)
    if mi.is_spectral:
        si.wavelengths = mi.UnpolarizedSpectrum(*WAVELENGTHS)
    return si


def unpolarized(x):
    """x, or in a polarized variant the [0, 0] element of a Mueller matrix x: what the BSDF
    does to unpolarized light, the same in every Stokes basis (the rotations that
    ``si.to_world_mueller`` applies leave it unchanged)."""
    if mi.is_polarized and isinstance(x, mi.Spectrum):
        return mi.unpolarized_spectrum(x)
    return x


def to_np(x):
    """A Dr.Jit array (Float or Color3f; a Mueller matrix: its unpolarized part) as numpy,
    shape (N,) or (N, C)."""
    x = unpolarized(x)
    if dr.is_jit_v(x) and dr.depth_v(x) > 1:
        # channel by channel, once evaluated: NumPy's conversion of a colour gathers its
        # channels into one buffer in a kernel whose code holds the width (the channels'
        # offsets) and into which the computation of the value is fused, so that the same
        # BSDF evaluated at another number of directions compiled all of it again
        dr.eval(x)
        channels = [np.array(c) for c in x]
        n = max(len(c) for c in channels)
        a = np.stack([np.broadcast_to(c, (n,)) for c in channels])
    else:
        a = np.array(x)
    return a.T if a.ndim == 2 else a


def rows(x, n, channels=False):
    """A Dr.Jit result as n rows of NumPy (a width-1 result, such as the constant zero of a
    delta lobe's eval, is broadcast): shape (n,), or (n, C) for a colour (with channels,
    also for a monochrome Float)."""
    a = to_np(x)
    if channels and a.ndim == 1:
        a = a[:, None]
    return np.broadcast_to(a, (n,) + a.shape[1:])


# -- calling a BSDF as Mitsuba's integrators do ---------------------------------------------
# Through the C++ entry points of ``mi.BSDF``, with every argument and a full-width
# ``active`` mask given by position: a plugin written in Python is reached through
# Mitsuba's own trampoline, which passes it exactly what an integrator passes (so
# ``active`` may be a required argument) and converts what it returns to Mitsuba's types
# as a render does (an ``eval`` that returns the Python float 0.0 gives a black Spectrum).
# A C++ plugin is called as it is anyway.

def _active(si):
    """The mask integrators pass: every lane active, as wide as si."""
    if dr.is_jit_v(mi.Float):
        return dr.full(mi.Bool, True, dr.width(si))
    return True


#: what Mitsuba takes back from each method, by the names of this variant's types
_RETURNS = {"eval": ("Spectrum",), "pdf": ("Float",), "eval_pdf": ("Spectrum", "Float"),
            "sample": ("BSDFSample3f", "Spectrum")}


def _type_name(x):
    """The name of a value's type as a user wrote it: ``Color3f``, ``float``, ``Spectrum``."""
    return type(x).__name__


def _returned(method, bsdf, args):
    """What the plugin's own ``method`` returns for ``args`` (called directly, as Python),
    said against what Mitsuba takes back, e.g. "sample() returns (BSDFSample3f, Color3f)
    where llvm_ad_spectral takes (BSDFSample3f, Spectrum)"; None when the call raises or
    returns what Mitsuba takes."""
    try:
        out = getattr(bsdf, method)(*args)
    except Exception:  # noqa: BLE001  (the plugin's own error: Mitsuba's message stands)
        return None
    names = {"Spectrum": mi.Spectrum.__name__, "Float": mi.Float.__name__}
    want = tuple(names.get(t, t) for t in _RETURNS[method])
    got = tuple(map(_type_name, out)) if isinstance(out, tuple) else (_type_name(out),)
    if got == want:
        return None
    show = (lambda t: f"({', '.join(t)})" if len(t) > 1 else t[0])
    hint = ""
    if mi.is_spectral and "Color3f" in got:
        hint = ": a Color3f is RGB, build the value as mi.Spectrum (or mi.UnpolarizedSpectrum)"
    elif mi.is_polarized and "Spectrum" in want:
        hint = ": in a polarized variant a Spectrum is a Mueller matrix (mi.depolarizer(x))"
    return (f"{method}() returns {show(got)} where {mi.variant()} takes {show(want)}, and "
            f"Mitsuba cannot convert it (a render fails the same way){hint}")


def _call(method, bsdf, *args):
    """``mi.BSDF.<method>(bsdf, *args)``; when Mitsuba cannot convert what a Python plugin
    returns (its bare "std::bad_cast"), a TypeError that says what it returned instead."""
    try:
        return getattr(mi.BSDF, method)(bsdf, *args)
    except (RuntimeError, TypeError) as e:
        said = _returned(method, bsdf, args) if "cast" in str(e) else None
        if said is None:
            raise
        raise TypeError(said) from None


def call_eval(bsdf, ctx, si, wo):
    """``bsdf.eval(ctx, si, wo, active)`` as an integrator calls it."""
    return _call("eval", bsdf, ctx, si, wo, _active(si))


def call_pdf(bsdf, ctx, si, wo):
    """``bsdf.pdf(ctx, si, wo, active)`` as an integrator calls it."""
    return _call("pdf", bsdf, ctx, si, wo, _active(si))


def call_eval_pdf(bsdf, ctx, si, wo):
    """``bsdf.eval_pdf(ctx, si, wo, active)`` as an integrator calls it."""
    return _call("eval_pdf", bsdf, ctx, si, wo, _active(si))


def call_sample(bsdf, ctx, si, sample1, sample2):
    """``bsdf.sample(ctx, si, sample1, sample2, active)`` as an integrator calls it."""
    return _call("sample", bsdf, ctx, si, sample1, sample2, _active(si))


def sample_bsdf(bsdf, wi, n, seed=0, ctx=None):
    """n samples of ``bsdf`` at a fixed wi: (si, (bs, weight)) with arrays of width n; with
    K directions wi (shape (K, 3)), n samples at each, in one batch of width K n."""
    ctx = ctx or mi.BSDFContext()
    wi = np.repeat(np.asarray(wi, float).reshape(-1, 3), n, axis=0)
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(seed, len(wi))
    si = interaction(wi)
    s1, s2 = sampler.next_1d(), sampler.next_2d()
    # evaluated apart: the sampler's code holds the number of samples, and fused into the
    # BSDF's kernel it would make each sample count compile the BSDF again
    dr.eval(s1, s2)
    return si, call_sample(bsdf, ctx, si, s1, s2)


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
    si, v = interaction(wi), vec(wo)
    return rows(call_eval(bsdf, ctx or mi.BSDFContext(), si, v), max(dr.width(si.wi), dr.width(v)))


def pdf_np(bsdf, wi, wo, ctx=None):
    si, v = interaction(wi), vec(wo)
    return rows(call_pdf(bsdf, ctx or mi.BSDFContext(), si, v), max(dr.width(si.wi), dr.width(v)))


def short(x):
    """A value or vector in few characters: (0.3, 0.4, -0.866), nan, 0.02191."""
    a = np.ravel(np.asarray(x, float))
    text = [f"{c:.4g}" if np.isfinite(c) else str(c) for c in a + 0.0]
    if len(text) == 1:
        return text[0]
    if len(set(text)) == 1 and len(text) == 3:  # a grey colour
        return text[0]
    return "(" + ", ".join(text) + ")"
