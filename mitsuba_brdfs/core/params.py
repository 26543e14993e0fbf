"""Reading and validating plugin parameters, at load time and after every update.

Every error names the plugin, the parameter and the accepted range. At load it is raised
from the plugin's constructor, so ``mi.load_file``/``mi.load_dict`` report it (as a
RuntimeError whose message carries ours) instead of rendering garbage later. The reader
records the range of every texture parameter (``ParamReader.ranges``), and
``check_range`` is run again from ``parameters_changed`` on each texture that
``params.update()`` touched: a value set through ``mi.traverse`` meets the same check and
the same message as one written in the scene file.

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

__all__ = ["ParameterError", "ParamReader", "Range", "texture_range", "check_range",
           "float32", "constructing"]

#: wavelengths (nm) at which a spectral variant's textures are checked: the fitted sRGB
#: spectra are smooth sigmoids, their extremes lie at the ends and the middle of the range
_CHECK_WAVELENGTHS = (360.0, 450.0, 550.0, 650.0, 830.0)
#: texels looked up at once in a JIT variant (bounds the memory of the check)
_CHUNK = 1 << 22
#: texels looked up one by one in a scalar variant (a strided subset beyond this)
_SCALAR_TEXELS = 1 << 16
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


def float32(x):
    """``x`` rounded to float32, as a texture stores it (for the ends of a range that a
    stored value must reach)."""
    return dr.scalar.Array1f(x)[0]


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

    The texture is looked up where it takes its extreme values (``_lookup_grid``), as a
    colour (in a spectral variant at several wavelengths), or as a float if ``scalar``. A
    scalar variant looks texels up one by one, at most ``_SCALAR_TEXELS`` of them (a
    strided subset of a larger image). NaN anywhere gives (nan, nan). Raises Mitsuba's
    RuntimeError if the texture cannot be looked up so (see the module docstring).
    """
    if not tex.is_spatially_varying():
        stored = _stored_constant(tex)
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
        for index in range(0, n, max(1, n // _SCALAR_TEXELS)):
            out = _merge(out, _eval_range_scalar(tex, *_uv(index, w, h, m), scalar))
            if math.isnan(out[0]):
                break
        return out


def _stored_constant(tex):
    """(min, max) of a constant texture read from its stored value, without a kernel, or
    None where the stored value is not what it returns (a spectral variant's sRGB
    coefficients)."""
    if mi.is_spectral and "SRGB" in tex.class_name():
        return None
    params = mi.traverse(tex)
    keys = [k for k in params.keys() if k.split(".")[-1] == "value"]
    if len(keys) != 1:
        return None
    vals = _floats(params[keys[0]])
    if not vals:
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
    """The values a check refused, written the same way at load and after an update."""
    if math.isnan(vmin) or math.isnan(vmax):
        return "NaN"
    return f"values in [{vmin:g}, {vmax:g}]" if vmin != vmax else f"{vmin:g}"


def _got_raw(raw):
    vals = _floats(raw)
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
    """A range bound as people write it: 0, 0.5, 1e6, inf."""
    return f"{x:g}".replace("e+0", "e").replace("e+", "e").replace("e-0", "e-")


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
        default) and record its range. The values of a number or colour are recorded in
        ``known``: nothing is read back from the texture while the scene loads (a kernel
        waited for in a constructor lets the parallel loader nest other constructors)."""
        rng = Range(lo, hi, expected, scalar)
        value = default if raw is None else raw
        try:
            vals = None if isinstance(value, mi.Object) else _floats(value)
        except (TypeError, ValueError):  # e.g. a spectrum given as wavelength-value pairs
            vals = None
        if vals:
            self.known[name] = (min(vals), max(vals))
        else:
            _check_soon(self.plugin, name, tex, rng)
        self.ranges[name] = rng

    def _raw(self, name):
        if name not in self.props:
            return None
        return self.props.get(name)

    def reflectance(self, name, default):
        """A colour in [0, 1]: <rgb>, <float>, <spectrum> or a texture."""
        expected = "a reflectance in [0, 1] (float, rgb or texture)"
        raw = self._raw(name)
        if isinstance(raw, str):
            raise self.error(name, expected, repr(raw))
        if raw is not None and not isinstance(raw, mi.Object):
            vals = _floats(raw)
            if any(math.isnan(v) or v < 0 or v > 1 for v in vals):
                raise self.error(name, expected, _got_raw(vals))
        try:
            tex = self.props.get_texture(name, default)
        except Exception as e:  # Mitsuba's own message does not name the parameter
            raise self.error(name, expected, str(e)) from None
        self._check_range(name, tex, 0.0, 1.0, expected, raw, default)
        return tex

    def scalar(self, name, default, lo=0.0, hi=math.inf, what="a finite float"):
        """A float (or float texture) in [lo, hi]."""
        expected = f"{what} in [{_num(lo)}, {_num(hi)}]"
        raw = self._raw(name)
        if isinstance(raw, str):
            raise self.error(name, expected, repr(raw))
        if raw is not None and not isinstance(raw, mi.Object):
            vals = _floats(raw)
            if len(vals) != 1:
                raise self.error(name, expected, _got_raw(vals))
            v = vals[0]
            if math.isnan(v) or v < lo or v > hi or math.isinf(v):
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
