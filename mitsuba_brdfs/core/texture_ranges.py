"""The values a texture returns, found for the range checks of ``core.params``.

What is checked is what the texture returns (``texture_range``), not what it stores: an
8-bit PNG holds sRGB-encoded bytes and a spectral variant holds the coefficients of a
fitted spectrum, and neither is the reflectance the BSDF sees. A colour is looked up as
the plugin looks it up (``eval``, every channel, several wavelengths), a float parameter
as a float (``eval_1``: one channel, or the luminance of an RGB image).

Bitmaps in spectral variants follow Mitsuba's ``bitmap`` plugin:

- an RGB image (not ``raw``) becomes a fitted reflectance spectrum, which is bounded by
  [0, 1] at every wavelength: an EXR of 2.0 on a reflectance is accepted there and
  evaluates to 1, as Mitsuba's ``diffuse`` does with it (RGB and mono variants refuse it;
  a one-channel image is not fitted, so a one-channel 2.0 is refused in every variant);
- such an image cannot be read as a float (``eval_1``), and an RGB image with
  ``raw = true`` cannot be read as a colour: Mitsuba raises when it is looked up, so both
  are refused at load, naming the parameter (a float parameter takes a one-channel image,
  or an RGB one with ``raw = true``, in every variant).
"""
import math

import drjit as dr
import mitsuba as mi

__all__ = ["texture_range", "floats"]

#: wavelengths (nm) at which a spectral variant's textures are checked: the fitted sRGB
#: spectra are smooth sigmoids, their extremes lie at the ends and the middle of the range
_CHECK_WAVELENGTHS = (360.0, 450.0, 550.0, 650.0, 830.0)
#: texels looked up at once in a JIT variant (bounds the memory of the check)
_CHUNK = 1 << 22
#: sRGB-to-linear of Mitsuba (IEC 61966-2-1), for the bytes of an 8-bit bitmap
_SRGB_LINEAR_END, _SRGB_GAMMA = 0.04045, 2.4
#: luminance weights of linear sRGB (``mi.luminance``): a float lookup of an RGB bitmap
_LUMINANCE = (0.212671, 0.715160, 0.072169)
#: side of the uv grid on which a procedural texture is looked up
_GRID = 64


def floats(x):
    """The values of a number or of a Dr.Jit array (scalar or JIT, any shape) as Python
    floats. A JIT array is read back: keep it to a few values.

    Entries are read one by one, without building a flattened copy: reading a literal (a
    constant parameter) launches no kernel. A kernel waited for inside a plugin's
    constructor lets Mitsuba's parallel scene loader run other constructors on the same
    thread, which nest, so the check launches none where it need not.
    """
    if isinstance(x, (bool, int, float)):
        return [float(x)]
    if dr.depth_v(x) > 1:  # a colour, a vector: its components
        return [v for c in x for v in floats(c)]
    if dr.is_tensor_v(x):
        x = x.array
    return [float(x[i]) for i in range(dr.width(x))]


def _lookup_grid(tex):
    """Where the texture takes every value it can return: (width, height, to_uv inverse).

    A bitmap's values are those of its texel centres (filtering interpolates between them),
    mapped back through the inverse of its ``to_uv`` transform (None: identity); a constant
    texture is looked up once; other spatially varying textures (procedural ones) on a
    ``_GRID`` x ``_GRID`` grid of cell centres of the uv square.
    """
    if not tex.is_spatially_varying():
        return 1, 1, None
    params = mi.traverse(tex)
    data = params["data"] if "data" in params.keys() else None
    if data is None or len(data.shape) != 3:
        return _GRID, _GRID, None
    m = params["to_uv"].inverse().matrix if "to_uv" in params.keys() else None
    return data.shape[1], data.shape[0], m


def _uv(index, w, h, m):
    """uv of the grid cell centres ``index`` (row-major, x fastest), through ``m``."""
    u = (mi.Float(index % w) + 0.5) / w
    v = (mi.Float(index // w) + 0.5) / h
    if m is None:
        return u, v
    return (m[0][0] * u + m[0][1] * v + m[0][2], m[1][0] * u + m[1][1] * v + m[1][2])


def _wavelength_sets(scalar):
    """The wavelengths to look textures up at: four per lookup where a colour is looked up
    in a spectral variant (a float does not depend on them)."""
    if scalar or not mi.is_spectral:
        return [None]
    w = _CHECK_WAVELENGTHS
    return [((list(w[i:i + 4]) * 4)[:4]) for i in range(0, len(w), 4)]


def _merge(a, b):
    """The union of two (min, max) ranges; NaN wins."""
    if math.isnan(a[0]) or math.isnan(b[0]):
        return math.nan, math.nan
    return min(a[0], b[0]), max(a[1], b[1])


def _eval_range(tex, u, v, scalar):
    """(min, max) of ``tex.eval`` (``tex.eval_1`` if ``scalar``) at the JIT points (u, v),
    over the check wavelengths."""
    si = dr.zeros(mi.SurfaceInteraction3f, dr.width(u))
    si.uv = mi.Point2f(u, v)
    out = (math.inf, -math.inf)
    for waves in _wavelength_sets(scalar):
        if waves is not None:
            si.wavelengths = mi.UnpolarizedSpectrum(*waves)
        vals = tex.eval_1(si) if scalar else tex.eval(si)
        lo, hi = dr.min(vals, axis=None), dr.max(vals, axis=None)
        bad = dr.any(dr.isnan(vals), axis=None)
        dr.eval(lo, hi, bad)  # one kernel, then three reads
        out = _merge(out, (math.nan, math.nan) if bad[0] else (lo[0], hi[0]))
    return out


def _eval_range_scalar(tex, u, v, scalar):
    """(min, max) of ``tex.eval`` (``tex.eval_1``) at one point of a scalar variant."""
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.uv = mi.Point2f(u, v)
    out = (math.inf, -math.inf)
    for waves in _wavelength_sets(scalar):
        if waves is not None:
            si.wavelengths = mi.UnpolarizedSpectrum(*waves)
        vals = floats(tex.eval_1(si) if scalar else tex.eval(si))
        out = _merge(out, (math.nan, math.nan) if any(map(math.isnan, vals))
                     else (min(vals), max(vals)))
    return out


def texture_range(tex, scalar=False, traversed=None):
    """(min, max) of the values the texture returns (linear reflectance, in every variant).

    The texture is looked up where it takes its extreme values (``_lookup_grid``): every
    texel of a bitmap, as a colour (in a spectral variant at several wavelengths), or as a
    float if ``scalar``. A JIT variant looks them all up at once; a scalar variant computes
    them from the bitmap's stored array in one pass (``_texel_range``) and looks up only
    the extreme texels (a procedural texture point by point). NaN anywhere gives
    (nan, nan). Raises Mitsuba's RuntimeError if the texture cannot be looked up so (see
    the module docstring). ``traversed``: ``mi.traverse(tex)`` where the caller has it.
    """
    if not tex.is_spatially_varying():
        stored = _stored_constant(tex, scalar, traversed)
        if stored is not None:
            return stored
    w, h, m = _lookup_grid(tex)
    n = w * h
    out = (math.inf, -math.inf)
    with dr.suspend_grad():
        if dr.is_jit_v(mi.Float):
            for start in range(0, n, _CHUNK):
                index = dr.arange(mi.UInt32, start, min(start + _CHUNK, n))
                out = _merge(out, _eval_range(tex, *_uv(index, w, h, m), scalar))
                if math.isnan(out[0]):
                    break
            return out
        if n > 1:
            # looks up one texel first: raises where Mitsuba cannot look it up so
            _eval_range_scalar(tex, *_uv(0, w, h, m), scalar)
            fast = _texel_range(tex, w, h, m, scalar)
            if fast is not None:
                return fast
        for index in range(n):
            out = _merge(out, _eval_range_scalar(tex, *_uv(index, w, h, m), scalar))
            if math.isnan(out[0]):
                break
        return out


# -- every texel of a bitmap in a scalar variant, without a Python loop ----------------------

def _texel_values(tex, scalar):
    """Per texel, the smallest and the largest value that the bitmap ``tex`` returns at its
    centre (two Dr.Jit scalar arrays), computed from its stored array at once: bytes
    decoded (``/ 255``, then sRGB to linear unless ``raw``), the luminance for a float
    lookup of an RGB image, a spectral variant's fitted spectra evaluated at the check
    wavelengths. None for a texture without texels (procedural) or a layout not listed
    here (the caller looks every point up)."""
    params = mi.traverse(tex)
    data = params["data"] if "data" in params.keys() else None
    if data is None or len(data.shape) != 3:
        return None
    channels = data.shape[2]
    stored = data.array
    kind = dr.type_v(stored)
    x = dr.scalar.ArrayXf(stored)
    if kind in (dr.VarType.UInt8, dr.VarType.UInt16):
        x = x / (255.0 if kind == dr.VarType.UInt8 else 65535.0)
        if "raw = 1" not in str(tex):
            x = dr.select(x <= _SRGB_LINEAR_END, x / 12.92,
                          dr.power((x + 0.055) / 1.055, _SRGB_GAMMA))
    elif kind not in (dr.VarType.Float16, dr.VarType.Float32):
        return None
    n = dr.width(x) // channels
    index = dr.arange(dr.scalar.ArrayXu, n) * channels
    chans = [dr.gather(dr.scalar.ArrayXf, x, index + c) for c in range(channels)]
    if channels == 1:
        return chans[0], chans[0]
    if channels != 3:
        return None
    if scalar:  # eval_1 of an RGB image: its luminance
        lum = sum(w * c for w, c in zip(_LUMINANCE, chans))
        return lum, lum
    if not mi.is_spectral:
        return (dr.minimum(dr.minimum(chans[0], chans[1]), chans[2]),
                dr.maximum(dr.maximum(chans[0], chans[1]), chans[2]))
    # the sigmoid spectra of Mitsuba's sRGB model (``srgb_model_eval``), coefficients c
    lo, hi = None, None
    for wavelength in _CHECK_WAVELENGTHS:
        t = dr.fma(dr.fma(chans[0], wavelength, chans[1]), wavelength, chans[2])
        v = dr.fma(0.5 * t, dr.rsqrt(dr.fma(t, t, 1.0)), 0.5)
        v = dr.select(dr.isinf(chans[2]), dr.fma(dr.sign(chans[2]), 0.5, 0.5), v)
        lo = v if lo is None else dr.minimum(lo, v)
        hi = v if hi is None else dr.maximum(hi, v)
    return lo, hi


def _reduce(x, op):
    """``op`` (dr.minimum or dr.maximum) over a scalar array, halving it each step (one
    C++ pass per step, where ``dr.min`` of a scalar array costs some 250 ns a value)."""
    n = dr.width(x)
    while n > 1:
        half = (n + 1) // 2  # the halves overlap by one value when n is odd
        index = dr.arange(dr.scalar.ArrayXu, half)
        x = op(dr.gather(dr.scalar.ArrayXf, x, index),
               dr.gather(dr.scalar.ArrayXf, x, index + (n - half)))
        n = half
    return x[0]


def _texel_range(tex, w, h, m, scalar):
    """(min, max) of what a bitmap returns at every texel, in a scalar variant: from
    ``_texel_values``, then the texels holding the extremes (and the first and last one)
    looked up through Mitsuba, whose values are returned. None if the two disagree (a
    layout read wrongly): the caller looks every texel up instead."""
    values = _texel_values(tex, scalar)
    if values is None:
        return None
    lo, hi = values
    if dr.any(dr.isnan(lo)) or dr.any(dr.isnan(hi)):
        return math.nan, math.nan
    vmin, vmax = _reduce(lo, dr.minimum), _reduce(hi, dr.maximum)
    at_min = dr.compress(lo == vmin)[0]
    at_max = dr.compress(hi == vmax)[0]
    out = {}
    for index in {at_min, at_max, 0, w * h - 1}:
        out[index] = _eval_range_scalar(tex, *_uv(index, w, h, m), scalar)
        for got, want in zip(out[index], (lo[index], hi[index])):
            if not (got == want or abs(got - want) <= 1e-5 * (1.0 + abs(want))):  # inf == inf
                return None
    return out[at_min][0], out[at_max][1]


def _stored_constant(tex, scalar=False, traversed=None):
    """(min, max) of a constant texture read from its stored value, without a kernel, or
    None where the stored value is not what it returns (a spectral variant's sRGB
    coefficients; a colour looked up as a float, which gives its luminance).
    ``traversed``: ``mi.traverse(tex)``, if the caller has it (a fit updates its
    parameters at every step, and traversing is most of this check's time)."""
    if mi.is_spectral and "SRGB" in tex.class_name():
        return None
    params = mi.traverse(tex) if traversed is None else traversed
    keys = [k for k in params.keys() if k.split(".")[-1] == "value"]
    if len(keys) != 1:
        return None
    vals = floats(params[keys[0]])
    if not vals or (scalar and len(vals) != 1):
        return None
    if any(map(math.isnan, vals)):
        return math.nan, math.nan
    return min(vals), max(vals)
