"""Reading and validating plugin parameters at load time.

Every error names the plugin, the parameter and the accepted range, and is raised from the
plugin's constructor, so ``mi.load_file``/``mi.load_dict`` report it (as a RuntimeError
whose message carries ours) instead of rendering garbage later.
"""
import math

import mitsuba as mi
import numpy as np

__all__ = ["ParameterError", "ParamReader", "texture_range", "is_constant_zero"]


class ParameterError(ValueError):
    """A plugin parameter is missing its accepted range or type."""


def texture_range(tex):
    """(min, max) over the values a texture can return, or None if unknown.

    Constant and bitmap textures expose their values through ``traverse`` as ``value`` or
    ``data``; other textures (procedural ones) are left unchecked. 8-bit bitmaps (PNG, JPEG)
    keep their integer data: it is read as the fraction of the largest integer (their
    sRGB encoding maps [0, 1] onto itself, so the ends of the range are exact). In spectral
    variants an RGB bitmap of floats holds spectral upsampling coefficients, not colours: it
    is left unchecked, as the sRGB constants are.
    """
    if mi.is_spectral and "SRGB" in tex.class_name():
        return None  # holds spectral upsampling coefficients, not the RGB value
    lo, hi, found = math.inf, -math.inf, False
    for key, value in mi.traverse(tex).items():
        if not (key.endswith("value") or key.endswith("data")):
            continue
        try:
            arr = np.asarray(value)
            scale = 1 / np.iinfo(arr.dtype).max if np.issubdtype(arr.dtype, np.integer) else 1
        except (TypeError, ValueError):
            continue
        if mi.is_spectral and arr.ndim == 3 and arr.shape[-1] == 3 and scale == 1:
            return None  # an RGB bitmap holds spectral upsampling coefficients
        arr = arr.astype(np.float64).ravel() * scale
        if arr.size == 0:
            continue
        if np.isnan(arr).any():
            return (math.nan, math.nan)
        lo, hi, found = min(lo, arr.min()), max(hi, arr.max()), True
    return (float(lo), float(hi)) if found else None


def is_constant_zero(tex):
    """True if the texture is the same zero everywhere (its lobe can be dropped)."""
    if tex.is_spatially_varying():
        return False
    r = texture_range(tex)
    return r is not None and r[0] == 0.0 and r[1] == 0.0


class ParamReader:
    """Reads one plugin's properties, validating each value against its range."""

    def __init__(self, plugin, props):
        self.plugin = plugin
        self.props = props

    def error(self, name, expected, got):
        return ParameterError(
            f"{self.plugin}: parameter '{name}' must be {expected} (got {got})")

    def _check_range(self, name, tex, lo, hi, expected):
        r = texture_range(tex)
        if r is None:
            return
        vmin, vmax = r
        if math.isnan(vmin) or vmin < lo or vmax > hi or math.isinf(vmax):
            got = "NaN" if math.isnan(vmin) else (
                f"values in [{vmin:g}, {vmax:g}]" if vmin != vmax else f"{vmin:g}")
            raise self.error(name, expected, got)

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
            vals = np.asarray(raw, dtype=np.float64).ravel()
            if np.isnan(vals).any() or (vals < 0).any() or (vals > 1).any():
                raise self.error(name, expected, [float(v) for v in vals] if vals.size > 1 else float(vals[0]))
        try:
            tex = self.props.get_texture(name, default)
        except Exception as e:  # Mitsuba's own message does not name the parameter
            raise self.error(name, expected, str(e)) from None
        self._check_range(name, tex, 0.0, 1.0, expected)
        return tex

    def scalar(self, name, default, lo=0.0, hi=math.inf, what="a finite float"):
        """A float (or float texture) in [lo, hi]."""
        expected = f"{what} in [{lo:g}, {hi:g}]"
        raw = self._raw(name)
        if isinstance(raw, str):
            raise self.error(name, expected, repr(raw))
        if raw is not None and not isinstance(raw, mi.Object):
            vals = np.asarray(raw, dtype=np.float64).ravel()
            if vals.size != 1:
                raise self.error(name, expected, [float(v) for v in vals])
            v = float(vals[0])
            if math.isnan(v) or v < lo or v > hi or math.isinf(v):
                raise self.error(name, expected, v)
        try:
            tex = self.props.get_unbounded_texture(name, default)
        except Exception as e:
            raise self.error(name, expected, str(e)) from None
        self._check_range(name, tex, lo, hi, expected)
        return tex

    def enum(self, name, default, choices):
        """A string from ``choices``."""
        raw = self._raw(name)
        value = default if raw is None else raw
        if not isinstance(value, str) or value not in choices:
            raise self.error(name, "one of " + ", ".join(repr(c) for c in choices), repr(value))
        return value

    def integer(self, name, default, lo=0, hi=2**31 - 1):
        raw = self._raw(name)
        value = default if raw is None else raw
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            raise self.error(name, f"an integer in [{lo}, {hi}]", repr(value))
        return value
