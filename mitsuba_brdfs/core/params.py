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

What a texture returns is found by ``core.texture_ranges`` (``texture_range``);
``check_range`` here refuses what is out of range, with the message.
"""
import contextlib
import math
import re
import threading

import drjit as dr
import mitsuba as mi

from .texture_ranges import floats as _floats, texture_range

__all__ = ["ParameterError", "ParamReader", "Range", "Samples", "texture_range",
           "check_range", "float32", "constructing"]


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


def check_range(plugin, name, tex, rng, traversed=None):
    """Raise the plugin's ``ParameterError`` if ``tex`` returns values outside ``rng``, or
    cannot be looked up as the parameter is (Mitsuba's reason in the message); else return
    the (min, max) it returns. ``traversed``: ``mi.traverse(tex)``, where the caller has it."""
    try:
        vmin, vmax = texture_range(tex, rng.scalar, traversed)
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
