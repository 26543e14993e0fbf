"""Reading and validating plugin parameters, at load time and after every update.

Every error names the plugin, the parameter and the accepted range. At load it is raised
from the plugin's constructor, so ``mi.load_file``/``mi.load_dict`` report it (as a
RuntimeError whose message carries ours) instead of rendering garbage later. The reader
records the range of every texture parameter (``ParamReader.ranges``), and
``check_range`` is run again from ``parameters_changed`` on each texture that
``params.update()`` touched: a value set through ``mi.traverse`` meets the same check and
the same message as one written in the scene file: a number of the scene is checked as
the texture holds it (float32), and a refused value is printed with the fewest digits that
give it back (``_num``: 1.0000001, not 1), so both messages are the same.

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
import contextlib
import math
import re
import threading

import drjit as dr
import mitsuba as mi

__all__ = ["ParameterError", "ParamReader", "Range", "Samples", "texture_range",
           "check_range", "float32", "constructing"]

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


class ParameterError(ValueError):
    """A plugin parameter is missing its accepted range or type."""


class Range:
    """The accepted values of one texture parameter: [lo, hi], the words of the message, and
    whether the plugin reads it as a float (``eval_1``) rather than a colour."""
    __slots__ = ("lo", "hi", "expected", "scalar")

    def __init__(self, lo, hi, expected, scalar=False):
        self.lo, self.hi, self.expected, self.scalar = lo, hi, expected, scalar


class Samples:
    """A ``<spectrum>`` given as wavelength-value pairs (a number is read as a float)."""
    __slots__ = ("wavelengths", "values")

    def __init__(self, wavelengths, values):
        self.wavelengths, self.values = list(wavelengths), [float(v) for v in values]


def float32(x):
    """``x`` rounded to float32, as a texture stores it (for the ends of a range that a
    stored value must reach)."""
    return dr.scalar.Array1f(x)[0]


def _stored(values):
    """Numbers given in a scene as the texture will hold them (float32), so that a value is
    checked and printed alike at load and after an update; one beyond float32's range
    stays as given (it is refused, and printed as written, not as inf)."""
    return [y if math.isfinite(y) or not math.isfinite(x) else x
            for x, y in ((x, float32(x)) for x in values)]


def _floats(x):
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
        return [v for c in x for v in _floats(c)]
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
        vals = _floats(tex.eval_1(si) if scalar else tex.eval(si))
        out = _merge(out, (math.nan, math.nan) if any(map(math.isnan, vals))
                     else (min(vals), max(vals)))
    return out


def texture_range(tex, scalar=False):
    """(min, max) of the values the texture returns (linear reflectance, in every variant).

    The texture is looked up where it takes its extreme values (``_lookup_grid``): every
    texel of a bitmap, as a colour (in a spectral variant at several wavelengths), or as a
    float if ``scalar``. A JIT variant looks them all up at once; a scalar variant computes
    them from the bitmap's stored array in one pass (``_texel_range``) and looks up only
    the extreme texels (a procedural texture point by point). NaN anywhere gives
    (nan, nan). Raises Mitsuba's RuntimeError if the texture cannot be looked up so (see
    the module docstring).
    """
    if not tex.is_spatially_varying():
        stored = _stored_constant(tex, scalar)
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


def _stored_constant(tex, scalar=False):
    """(min, max) of a constant texture read from its stored value, without a kernel, or
    None where the stored value is not what it returns (a spectral variant's sRGB
    coefficients; a colour looked up as a float, which gives its luminance)."""
    if mi.is_spectral and "SRGB" in tex.class_name():
        return None
    params = mi.traverse(tex)
    keys = [k for k in params.keys() if k.split(".")[-1] == "value"]
    if len(keys) != 1:
        return None
    vals = _floats(params[keys[0]])
    if not vals or (scalar and len(vals) != 1):
        return None
    if any(map(math.isnan, vals)):
        return math.nan, math.nan
    return min(vals), max(vals)


def check_range(plugin, name, tex, rng):
    """Raise the plugin's ``ParameterError`` if ``tex`` returns values outside ``rng``, or
    cannot be looked up as the parameter is (Mitsuba's reason in the message); else return
    the (min, max) it returns."""
    try:
        vmin, vmax = texture_range(tex, rng.scalar)
    except RuntimeError as e:
        # Mitsuba's reason, without its "[Class] " tag and the description of the texture
        reason = re.sub(r"^\[\S*\] ", "", " ".join(str(e).split()))
        reason = re.sub(r" ?\w+\[.*\]", "", reason)
        what = "a float" if rng.scalar else "a colour"
        raise error(plugin, name, rng.expected,
                    f"a texture that {mi.variant()} cannot read as {what}: {reason}") from None
    if math.isnan(vmin) or vmin < rng.lo or vmax > rng.hi or math.isinf(vmax) or math.isinf(vmin):
        raise error(plugin, name, rng.expected, _got(vmin, vmax))
    return vmin, vmax


def _got(vmin, vmax):
    """The values a check refused, written the same way at load and after an update, with
    the digits that tell them from the range's ends (1.0000001 is not 1)."""
    if math.isnan(vmin) or math.isnan(vmax):
        return "NaN"
    return f"values in [{_num(vmin)}, {_num(vmax)}]" if vmin != vmax else _num(vmin)


def _got_raw(raw):
    """``_got`` of a value as given: a number, a colour, or a list of numbers."""
    vals = [float(v) for v in raw] if isinstance(raw, list) else _floats(raw)
    return "NaN" if any(map(math.isnan, vals)) else _got(min(vals), max(vals))


_state = threading.local()


@contextlib.contextmanager
def constructing():
    """Around a plugin's constructor: checks that need a kernel run outside nested ones.

    Mitsuba loads a scene's objects in parallel, and a thread that waits for a kernel runs
    other loading tasks meanwhile, nested on its own stack: a constructor that checks a
    bitmap (a kernel) may find another constructor running inside it, whose check waits in
    turn, and so on; a few hundred textured materials exhaust Python's recursion limit.
    So a constructor nested in another one on the same thread defers its kernel checks to
    the outermost one, which runs them (and those of constructors nested meanwhile) before
    it returns. A refused texture still fails the load, with its own plugin and parameter
    named in the message.
    """
    depth = getattr(_state, "depth", 0)
    if depth == 0:
        _state.pending = []
    _state.depth = depth + 1
    try:
        yield
        while depth == 0 and _state.pending:
            check_range(*_state.pending.pop())
    finally:
        _state.depth = depth


def _check_soon(plugin, name, tex, rng):
    """``check_range`` now, or by the outermost constructor of this thread if nested."""
    if getattr(_state, "depth", 0) > 1:
        _state.pending.append((plugin, name, tex, rng))
    else:
        check_range(plugin, name, tex, rng)


def _num(x):
    """A number as people write it, with the fewest digits that give it back: 0, 0.5,
    1e6, 1.0000001, inf. A value that a texture stores (a float32) gets the fewest digits
    that give back that float32, so 1.0000001 in a texture does not print as
    1.00000011920929."""
    x = float(x)
    if math.isinf(x) or math.isnan(x):
        return str(x)
    text = repr(x)
    if float32(x) == x:
        text = next(t for t in (f"{x:.{p}g}" for p in range(1, 10)) if float32(float(t)) == x)
    text = text.replace("e+0", "e").replace("e+", "e").replace("e-0", "e-")
    return text[:-2] if text.endswith(".0") else text


def _interval(lo, hi):
    """The accepted range: [lo, hi], or [lo, inf) where any finite value above lo is
    (infinity itself is refused)."""
    return f"[{_num(lo)}, inf)" if math.isinf(hi) else f"[{_num(lo)}, {_num(hi)}]"


def error(plugin, name, expected, got):
    return ParameterError(f"{plugin}: parameter '{name}' must be {expected} (got {got})")


class ParamReader:
    """Reads one plugin's properties, validating each value against its range."""

    def __init__(self, plugin, props):
        self.plugin = plugin
        self.props = props
        #: parameter name -> ``Range`` of every texture read, for the checks after updates
        self.ranges = {}
        #: parameter name -> (min, max) of a texture given as a number or colour
        self.known = {}

    def error(self, name, expected, got):
        return error(self.plugin, name, expected, got)

    def _check_range(self, name, tex, lo, hi, expected, raw, default, scalar=False):
        """Check the texture (unless it holds a number or colour already checked, or the
        default) and record its range. The values of a number (or of a colour looked up as
        a colour) are recorded in ``known``: nothing is read back from the texture while
        the scene loads (a kernel waited for in a constructor lets the parallel loader nest
        other constructors)."""
        rng = Range(lo, hi, expected, scalar)
        value = default if raw is None else raw
        vals = None
        if not isinstance(value, (mi.Object, Samples)):
            vals = _floats(value)
            if scalar and len(vals) != 1:  # a colour read as a float: its luminance
                vals = None
        if vals:
            self.known[name] = (min(vals), max(vals))
        else:
            _check_soon(self.plugin, name, tex, rng)
        self.ranges[name] = rng

    def _raw(self, name):
        """The value as given: None if absent, else a number, a colour, a string, an object
        (a texture), or for a ``<spectrum>`` its constant (a number) or its ``Samples``."""
        if name not in self.props:
            return None
        value = self.props.get(name)
        if self.props.type(name) == mi.Properties.Type.Spectrum:
            if not value.wavelengths:  # <spectrum value="0.5"/>: a constant
                return float(value.values[0])
            return Samples(value.wavelengths, value.values)
        return value

    def reflectance(self, name, default):
        """A colour in [0, 1]: <rgb>, <float>, <spectrum> (a constant, or wavelength-value
        pairs, each value in [0, 1]) or a texture. A spectrum becomes what Mitsuba's own
        plugins make of it (``props.get_texture``): a constant stays one, pairs become an
        RGB colour in RGB variants, their luminance in mono ones, and the spectrum itself
        in spectral ones."""
        expected = "a reflectance in [0, 1] (float, rgb, spectrum or texture)"
        raw = self._raw(name)
        if isinstance(raw, str):
            raise self.error(name, expected, repr(raw))
        if raw is not None and not isinstance(raw, mi.Object):
            vals = _stored(raw.values if isinstance(raw, Samples) else _floats(raw))
            if any(math.isnan(v) or v < 0 or v > 1 for v in vals):
                raise self.error(name, expected, _got_raw(vals))
        try:
            tex = self.props.get_texture(name, default)
        except Exception as e:  # Mitsuba's own message does not name the parameter
            raise self.error(name, expected, str(e)) from None
        self._check_range(name, tex, 0.0, 1.0, expected, raw, default)
        return tex

    def scalar(self, name, default, lo=0.0, hi=math.inf, what="a finite float"):
        """A float (or float texture) in [lo, hi], looked up as Mitsuba's plugins look up
        theirs (``eval_1``): an <rgb> gives its luminance, a <spectrum> its constant or,
        in RGB and mono variants, the luminance of the colour its pairs become (a spectral
        variant cannot read pairs as a float, as Mitsuba's ``roughconductor`` cannot: they
        are refused)."""
        expected = f"{what} in {_interval(lo, hi)}"
        raw = self._raw(name)
        if isinstance(raw, str):
            raise self.error(name, expected, repr(raw))
        if isinstance(raw, Samples) and mi.is_spectral:
            raise self.error(name, expected, "a spectrum of wavelength-value pairs, which "
                             f"{mi.variant()} cannot read as a float; give a float, an rgb "
                             "or a constant spectrum")
        if raw is not None and not isinstance(raw, (mi.Object, Samples)):
            vals = _stored(_floats(raw))
            if any(math.isnan(v) for v in vals):
                raise self.error(name, expected, "NaN")
            v = vals[0]
            if len(vals) == 1 and (v < lo or v > hi or math.isinf(v)):
                raise self.error(name, expected, _got_raw(v))
        try:
            tex = self.props.get_unbounded_texture(name, default)
        except Exception as e:
            raise self.error(name, expected, str(e)) from None
        self._check_range(name, tex, lo, hi, expected, raw, default, scalar=True)
        return tex

    def enum(self, name, default, choices):
        """A string from ``choices``."""
        raw = self._raw(name)
        value = default if raw is None else raw
        if not isinstance(value, str) or value not in choices:
            raise self.error(name, "one of " + ", ".join(repr(c) for c in choices), repr(value))
        return value

    def boolean(self, name, default):
        """A boolean (``<boolean>`` in XML, a Python bool in a dict)."""
        raw = self._raw(name)
        value = default if raw is None else raw
        if not isinstance(value, bool):
            raise self.error(name, "a boolean (true or false)", repr(value))
        return value

    def integer(self, name, default, lo=0, hi=2**31 - 1):
        raw = self._raw(name)
        value = default if raw is None else raw
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            raise self.error(name, f"an integer in [{lo}, {hi}]", repr(value))
        return value
