"""The controls of a BSDF in the page: what can be set, its range, and how a value the page
sends is checked.

For this package's plugins every control comes from the model's docstring table (type,
default, range, choices: ``docstrings.parameters``), and the relations between parameters
from those the model declares (``RELATIONS``, ``core.relations``):

- parameters that come together (``alpha_u``, ``alpha_v`` of ``ashikhmin_shirley``; ``a``,
  ``b`` of ``oren_nayar``) are **partners**: the page sets one at a time, and the others
  are sent with it at their current value;
- parameters that exclude each other (another parametrisation of the same thing: ``nu``
  and ``alpha``, a ramp and its bands) are **alternatives**: setting one takes the others
  out of the dictionary (both ways).

Which parameters are in use is what the loaded BSDF's ``mi.traverse`` exposes (``active``):
the parametrisation in force. Choices, booleans and integers are read at load time and
always count as in use.

For Mitsuba's plugins and the user's, the controls are the width-1 Float and Color3f
values of ``mi.traverse``, with ranges guessed from the parameter's name, and the string
parameters Mitsuba's own BSDFs document (``BUILTIN_CHOICES``).
"""
import math
import re

import drjit as dr
import mitsuba as mi

from ..arguments import number
from .messages import EntryError, shown

__all__ = ["BUILTINS", "BUILTIN_CHOICES", "doc_controls", "traverse_controls", "active",
           "checked", "plain", "is_colour"]

#: Mitsuba's BSDF plugins offered by the page's "add" menu (any other name can be typed)
BUILTINS = ("diffuse", "roughplastic", "plastic", "roughconductor", "conductor",
            "roughdielectric", "dielectric", "thindielectric", "principled",
            "principledthin")

_MATERIALS = ("none", "Ag", "Al", "Au", "Cr", "Cu", "Hg", "Ni", "Pt", "Ti", "W")
#: the string parameters of Mitsuba's BSDFs, as choices (their traverse does not show them)
BUILTIN_CHOICES = {
    "roughplastic": {"distribution": ("beckmann", "ggx")},
    "roughconductor": {"distribution": ("beckmann", "ggx"), "material": _MATERIALS},
    "conductor": {"material": _MATERIALS},
    "roughdielectric": {"distribution": ("beckmann", "ggx")},
}

#: name fragments of Mitsuba parameters in [0, 1] (reflectances, weights, roughness)
_UNIT = ("reflectance", "transmittance", "alpha", "roughness", "metallic", "specular",
         "sheen", "clearcoat", "spec_trans", "anisotropic", "flatness", "spec_tint",
         "diff_trans", "weight", "base_color", "color")


def is_colour(v):
    """True for a dictionary's ``{"type": "rgb", ...}`` value."""
    return isinstance(v, dict) and v.get("type") == "rgb"


def plain(text):
    """A docstring's reStructuredText as the plain text of a tooltip: ``x`` -> x."""
    text = re.sub(r"``(.+?)``", r"\1", text)
    text = re.sub(r":\w+:`(.+?)`", r"\1", text)
    return re.sub(r"`(.+?)`_?", r"\1", text).replace("\\", "")


def _slider(lo, hi, default):
    """The slider's [lo, hi] and whether it is logarithmic, for an accepted range."""
    if hi > 1000:  # exponents: 1 .. 1e4 on a log scale (any value can be typed)
        return [max(lo, 0.1), 1e4], True
    if math.isinf(hi):
        return [lo, max(lo + 2, 3 * (default or 1))], False
    return [lo, hi], False


def _relations(plugin, names):
    """{name: (partners, alternatives)} of a plugin's parameters, from the relations its
    model declares (``core.relations``)."""
    from ..core import relations
    from ..core.registry import models
    declared = models()[plugin].RELATIONS
    return {n: (relations.partners(declared, n), relations.alternatives(declared, n))
            for n in names}


def _options(plugin):
    """The plugin's load-time choices (its model's ``OPTIONS``: what the plugin accepts)."""
    from ..core.registry import models
    model = models().get(plugin)
    return getattr(model, "OPTIONS", {}) if model is not None else {}


def doc_controls(plugin):
    """Controls of one of this package's plugins, from its docstring table; the choices of
    a string parameter are the model's ``OPTIONS`` where it lists them (a new option or
    value shows up in the page as the plugin accepts it), else the values its row names.
    A string option of ``OPTIONS`` that the table lacks is offered too."""
    from ..docstrings import parameters
    params = parameters(plugin)
    options = _options(plugin)
    relations = _relations(plugin, [p.name for p in params])
    out = []
    for p in params:
        default = p.default.strip("`")
        b = p.bounds()
        lo, hi = (b[0], b[1]) if b else (-math.inf, math.inf)
        partners, alternatives = relations[p.name]
        c = {"name": p.name, "doc": plain(p.description), "range": p.range, "lo": lo,
             "hi": hi, "partners": partners, "alternatives": alternatives}
        if p.type == "string":
            choices = options.get(p.name) or p.choices()
            c.update(kind="choice", choices=list(choices), default=default)
        elif p.type == "boolean":
            c.update(kind="bool", default=default.lower() == "true")
        elif p.type == "integer":
            c.update(kind="int", default=int(number(default) or 0), slider=[lo, min(hi, 512)])
        elif p.type.startswith("spectrum"):
            c.update(kind="colour", default=number(default))
        elif p.type.startswith("float"):
            d = number(default)
            c.update(kind="float", default=d)
            c["slider"], c["log"] = _slider(lo, hi, d)
        else:  # a texture only (a ramp): shown, not edited
            c.update(kind="fixed", default=default)
        out.append(c)
    named = {c["name"] for c in out}
    for name, choices in options.items():
        if name not in named and isinstance(choices[0], str):
            out.append({"name": name, "doc": "", "range": "", "lo": -math.inf, "hi": math.inf,
                        "partners": [], "alternatives": [], "kind": "choice",
                        "choices": list(choices), "default": choices[0]})
    return out


def _guess(name, value):
    """(lo, hi, slider) of a Mitsuba parameter from its name and value."""
    base = name.rsplit(".value", 1)[0].split(".")[-1]
    if base == "eta":
        return 0.0, math.inf, [1.0, 3.0]
    if base == "k":
        return 0.0, math.inf, [0.0, 10.0]
    if any(f in base for f in _UNIT):
        return 0.0, 1.0, [0.0, 1.0]
    top = max(1.0, 4 * abs(value))
    return -math.inf, math.inf, [min(0.0, value), top]


def traverse_controls(bsdf, plugin):
    """Controls of another plugin: its width-1 Float and Color3f traverse values."""
    params = mi.traverse(bsdf)
    out = []
    base = {"doc": "", "range": "", "partners": [], "alternatives": []}
    for key in params.keys():
        v = params[key]
        if key.count(".") > (1 if key.endswith(".value") else 0):
            continue  # nested objects: not shown
        name = key[:-len(".value")] if key.endswith(".value") else key
        if isinstance(v, float) or isinstance(v, mi.Float) and dr.width(v) == 1:
            x = float(v if isinstance(v, float) else v[0])
            lo, hi, slider = _guess(key, x)
            out.append({**base, "name": name, "key": key, "kind": "float", "default": x,
                        "lo": lo, "hi": hi, "slider": slider, "log": False})
        elif isinstance(v, mi.Color3f) and dr.width(v) == 1:
            rgb = [float(c[0]) for c in v]
            lo, hi, _ = _guess(key, max(rgb))
            out.append({**base, "name": name, "key": key, "kind": "colour", "default": rgb,
                        "lo": lo, "hi": hi})
    for name, choices in BUILTIN_CHOICES.get(plugin, {}).items():
        out.append({**base, "name": name, "kind": "choice", "choices": list(choices),
                    "default": choices[0]})
    return out


def active(controls, bsdf):
    """{name: in use} of the controls: a float, colour or texture parameter is in use when
    the loaded BSDF's ``mi.traverse`` exposes it; the others always are."""
    keys = {k.removesuffix(".value") for k in mi.traverse(bsdf).keys()}
    return {c["name"]: c["kind"] not in ("float", "colour", "fixed") or "key" in c
            or c["name"] in keys for c in controls}


def checked(c, value, label):
    """The page's ``value`` for control ``c`` as a dictionary value (a float, an int, a
    string, a bool, ``{"type": "rgb", ...}``); ``EntryError`` naming the BSDF, the parameter
    and its range if it cannot be used."""
    what = f"{label}: parameter '{c['name']}'"
    kind = c["kind"]
    if kind == "choice":
        if not isinstance(value, str) or value not in c["choices"]:
            raise EntryError(f"{what} must be one of {', '.join(c['choices'])} "
                             f"(got {shown(value)})")
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            raise EntryError(f"{what} must be true or false (got {shown(value)})")
        return value
    if kind == "fixed":
        raise EntryError(f"{what} is a texture: set it in XML (export, then edit)")
    if isinstance(value, str) and kind == "colour":
        value = [v.strip() for v in value.split(",")] if "," in value else value
    values = value if isinstance(value, list) else [value]
    nums = [None if isinstance(v, bool) or not isinstance(v, (int, float, str)) else
            number(v) for v in values]
    lo, hi = c["lo"], c["hi"]
    rng = c.get("range") or f"[{lo:g}, {hi:g}]"
    if None in nums or len(nums) not in ((1, 3) if kind == "colour" else (1,)):
        expect = "a number or r, g, b" if kind == "colour" else "a number"
        raise EntryError(f"{what} must be {expect} in {rng} (got {shown(value)})")
    for x in nums:
        if not math.isfinite(x) or x < lo or x > hi:
            raise EntryError(f"{what} must be in {rng} (got {x:g})")
    if kind == "int":
        if not float(nums[0]).is_integer():
            raise EntryError(f"{what} must be an integer in {rng} (got {nums[0]:g})")
        return int(nums[0])
    if kind == "colour" and len(nums) == 3:
        return {"type": "rgb", "value": nums}
    return float(nums[0])
