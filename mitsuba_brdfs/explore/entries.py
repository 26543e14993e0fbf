"""The BSDFs the explorer shows: how each is loaded, its controls, updates and exports.

An ``Entry`` keeps the ``load_dict`` dictionary of its BSDF (``props``: what the user set,
the plugin's defaults for the rest), which is what the exports write. A change of a value
that ``mi.traverse`` exposes with the same type is written into the loaded BSDF and
``params.update()`` is called: its parameters are opaque, so the kernels of the plots and
of the sphere are found in Dr.Jit's cache. Any other change (a choice, a float becoming a
colour, a parameter set for the first time) loads the plugin again from ``props``. A value
the plugin refuses leaves the entry as it was, and the message is returned to the page.

Controls come from the model's docstring table for this package's plugins (type, default,
range and choices, as ``manual.parameters`` reads them), and from ``mi.traverse`` with
ranges guessed from the parameter's name for Mitsuba's plugins and the user's. The
conversions between scene XML and ``load_dict`` dictionaries are in ``xmldict``.
"""
import math
import os

import drjit as dr
import mitsuba as mi

from ..check import load_bsdfs, parse_value
from .xmldict import (EntryError, _plugin_models, _xml_dicts, dict_to_python,  # noqa: F401
                      dict_to_xml, xml_to_dict)

__all__ = ["BUILTINS", "jsonable", "Entry", "EntryError", "make_entries", "xml_to_dict", "dict_to_xml",
           "dict_to_python"]

#: Mitsuba's BSDF plugins offered by the page's "add" menu (any other name can be typed)
BUILTINS = ("diffuse", "roughplastic", "plastic", "roughconductor", "conductor",
            "roughdielectric", "dielectric", "thindielectric", "principled",
            "principledthin")

#: the string parameters of Mitsuba's BSDFs, as choices (their traverse does not show them)
BUILTIN_CHOICES = {
    "roughplastic": {"distribution": ("beckmann", "ggx")},
    "roughconductor": {"distribution": ("beckmann", "ggx"),
                       "material": ("none", "Ag", "Al", "Au", "Cr", "Cu", "Hg", "Ni", "Pt",
                                    "Ti", "W")},
    "conductor": {"material": ("none", "Ag", "Al", "Au", "Cr", "Cu", "Hg", "Ni", "Pt", "Ti",
                               "W")},
    "roughdielectric": {"distribution": ("beckmann", "ggx")},
}

#: name fragments of Mitsuba parameters in [0, 1] (reflectances, weights, roughness)
_UNIT = ("reflectance", "transmittance", "alpha", "roughness", "metallic", "specular",
         "sheen", "clearcoat", "spec_trans", "anisotropic", "flatness", "spec_tint",
         "diff_trans", "weight", "base_color", "color")


def _is_colour(v):
    return isinstance(v, dict) and v.get("type") == "rgb"


def _display(value):
    """A props value as the page shows it: a number, [r, g, b], a string, a bool."""
    if _is_colour(value):
        return [float(x) for x in value["value"]]
    if isinstance(value, dict) and value.get("type") == "spectrum" and isinstance(
            value.get("value"), (int, float)):
        return float(value["value"])
    return value


def _number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def _doc_controls(plugin):
    """Controls of one of this package's plugins, from its docstring table."""
    from ..manual import parameters
    out = []
    for p in parameters(plugin):
        default = p.default.strip("`")
        b = p.bounds()
        lo, hi = (b[0], b[1]) if b else (-math.inf, math.inf)
        c = {"name": p.name, "doc": p.description, "range": p.range, "lo": lo, "hi": hi}
        if p.type == "string":
            c.update(kind="choice", choices=p.choices(), default=default)
        elif p.type == "boolean":
            c.update(kind="bool", default=default.lower() == "true")
        elif p.type == "integer":
            c.update(kind="int", default=int(_number(default) or 0), slider=[lo, min(hi, 512)])
        elif p.type.startswith("spectrum"):
            c.update(kind="colour", default=_number(default))
        elif p.type.startswith("float"):
            d = _number(default)
            c.update(kind="float", default=d)
            c["slider"], c["log"] = _slider(lo, hi, d)
        else:  # a texture only (a ramp): shown, not edited
            c.update(kind="fixed", default=default)
        out.append(c)
    return out


def _slider(lo, hi, default):
    """The slider's [lo, hi] and whether it is logarithmic, for an accepted range."""
    if hi > 1000:  # exponents: 1 .. 1e4 on a log scale (any value can be typed)
        return [max(lo, 0.1), 1e4], True
    if math.isinf(hi):
        return [lo, max(lo + 2, 3 * (default or 1))], False
    return [lo, hi], False


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


def _traverse_controls(bsdf, plugin):
    """Controls of another plugin: its width-1 Float and Color3f traverse values."""
    params = mi.traverse(bsdf)
    out = []
    for key in params.keys():
        v = params[key]
        if key.count(".") > (1 if key.endswith(".value") else 0):
            continue  # nested objects: not shown
        name = key[:-len(".value")] if key.endswith(".value") else key
        if isinstance(v, float) or isinstance(v, mi.Float) and dr.width(v) == 1:
            x = float(v if isinstance(v, float) else v[0])
            lo, hi, slider = _guess(key, x)
            out.append({"name": name, "key": key, "kind": "float", "default": x, "lo": lo,
                        "hi": hi, "slider": slider, "log": False, "doc": "", "range": ""})
        elif isinstance(v, mi.Color3f) and dr.width(v) == 1:
            rgb = [float(c[0]) for c in v]
            lo, hi, _ = _guess(key, max(rgb))
            out.append({"name": name, "key": key, "kind": "colour", "default": rgb, "lo": lo,
                        "hi": hi, "doc": "", "range": ""})
    for name, choices in BUILTIN_CHOICES.get(plugin, {}).items():
        out.append({"name": name, "kind": "choice", "choices": list(choices),
                     "default": choices[0], "doc": "", "range": ""})
    return out


# -- entries -----------------------------------------------------------------------------

class Entry:
    """One BSDF of the page: its dictionary, the loaded BSDF, its controls and colour."""

    def __init__(self, ident, label, props, bsdf, colour, source=None):
        self.id, self.label, self.props, self.bsdf = ident, label, props, bsdf
        self.colour, self.visible, self.version = colour, True, 0
        self.source = source  #: an XML file's path, else None
        self.ours = props is not None and props.get("type") in _plugin_models()
        self.plugin = props.get("type") if props else _class(bsdf)
        self.controls = (_doc_controls(self.plugin) if self.ours else
                         _traverse_controls(bsdf, self.plugin))

    # what the page sees
    def state(self):
        controls = []
        for c in self.controls:
            set_ = self.props is not None and c["name"] in self.props
            value = _display(self.props[c["name"]]) if set_ else self._current(c)
            controls.append({**c, "value": value, "set": set_})
        return {"id": self.id, "label": self.label, "plugin": self.plugin,
                "colour": self.colour, "visible": self.visible, "version": self.version,
                "exportable": self.props is not None, "controls": jsonable(controls)}

    def _current(self, c):
        """The value a control shows when the dictionary does not set it."""
        if "key" in c:
            v = mi.traverse(self.bsdf)[c["key"]]
            if isinstance(v, float):
                return v
            return float(v[0]) if c["kind"] == "float" else [float(x[0]) for x in v]
        return c["default"]

    def control(self, name):
        for c in self.controls:
            if c["name"] == name:
                return c
        raise EntryError(f"{self.label}: no parameter {name!r} (it has "
                         f"{', '.join(c['name'] for c in self.controls)})")

    # changes
    def set(self, name, value):
        """Set one parameter (``value`` None: back to the plugin's default)."""
        c = self.control(name)
        new = None if value is None else self._checked(c, value)
        if self.props is None:  # an XML file's BSDF without a dictionary: traverse only
            if new is None or not self._update_in_place(c, new):
                raise EntryError(f"{self.label}: '{name}' can be changed here only as it is "
                                 f"(a {c['kind']}); edit {self.source} for more")
            self.version += 1
            return
        old = dict(self.props)
        if new is None:
            self.props.pop(name, None)
        else:
            self.props[name] = new
        try:
            if not self._update_in_place(c, new):
                bsdf = _load(self.props, self.label)
                self.bsdf = bsdf
        except EntryError:
            self.props.clear()
            self.props.update(old)
            raise
        self.version += 1

    def _checked(self, c, value):
        """The page's value as a props value, refused with the plugin, parameter and range."""
        what = f"{self.label}: parameter '{c['name']}'"
        kind = c["kind"]
        if kind == "choice":
            if value not in c["choices"]:
                raise EntryError(f"{what} must be one of {', '.join(c['choices'])} "
                                 f"(got {value!r})")
            return value
        if kind == "bool":
            if not isinstance(value, bool):
                raise EntryError(f"{what} must be true or false (got {value!r})")
            return value
        if kind == "fixed":
            raise EntryError(f"{what} is a texture: set it in XML (export, then edit)")
        if kind == "colour" and isinstance(value, str):
            value = parse_value(value)
            value = value["value"] if _is_colour(value) else value
        values = value if isinstance(value, list) else [value]
        nums = [_number(v) for v in values]
        rng = c.get("range") or f"[{c['lo']:g}, {c['hi']:g}]"
        if None in nums or len(nums) not in ((1, 3) if kind == "colour" else (1,)):
            expect = "a number or r, g, b" if kind == "colour" else "a number"
            raise EntryError(f"{what} must be {expect} in {rng} (got {value!r})")
        for x in nums:
            if not math.isfinite(x) or x < c["lo"] or x > c["hi"]:
                raise EntryError(f"{what} must be in {rng} (got {x:g})")
        if kind == "int":
            if not float(nums[0]).is_integer():
                raise EntryError(f"{what} must be an integer in {rng} (got {nums[0]:g})")
            return int(nums[0])
        if kind == "colour" and len(nums) == 3:
            return {"type": "rgb", "value": nums}
        return float(nums[0])

    def _update_in_place(self, c, new):
        """Write ``new`` through ``mi.traverse`` if the loaded BSDF exposes it with the same
        type (then the kernels are reused); False if the plugin must be loaded again."""
        if new is None or isinstance(new, (str, bool, int)):
            return False
        params = mi.traverse(self.bsdf)
        key = c.get("key") or next((k for k in (f"{c['name']}.value", c["name"])
                                    if k in params.keys()), None)
        if key is None:
            return False
        cur = params[key]
        colour = _is_colour(new)
        if isinstance(cur, mi.Color3f) and dr.width(cur) == 1:
            value = mi.Color3f(*(new["value"] if colour else [new] * 3))
        elif isinstance(cur, mi.Float) and dr.width(cur) == 1 and not colour:
            value = mi.Float(new)
        else:  # a Python float (a load-time value), a bitmap, a float becoming a colour
            return False
        old = type(cur)(cur)
        params[key] = value
        try:
            params.update()
        except Exception as e:
            params[key] = old
            params.update()
            raise EntryError(_message(e, self.label)) from None
        return True


def _class(bsdf):
    """A BSDF's class: Mitsuba's name, or for a Python plugin (whose class name Mitsuba
    gives as "BSDF") the head of its ``to_string``."""
    name = bsdf.class_name()
    return name if name != "BSDF" else str(bsdf).split("[")[0].strip() or name


def _message(e, label):
    """The one line of an exception the page shows: of the innermost one, when Dr.Jit
    wrapped the plugin's own (a render does)."""
    from ..__main__ import one_line
    while (e.__cause__ or e.__context__) is not None:
        e = e.__cause__ or e.__context__
    text = one_line(str(e))
    return text if text.startswith(label) or ":" in text[:40] else f"{label}: {text}"


def _load(props, label):
    try:
        obj = mi.load_dict(props)
    except Exception as e:
        raise EntryError(_message(e, label)) from None
    if not isinstance(obj, mi.BSDF):
        raise EntryError(f"{label}: {props.get('type')!r} is not a BSDF plugin")
    return obj


def jsonable(x):
    if isinstance(x, dict):
        return {k: jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None if math.isnan(x) else (1e308 if x > 0 else -1e308)
    return x


def _same(a, b):
    """True if two BSDFs are the same plugin with the same traverse values."""
    if a.class_name() != b.class_name():
        return False
    pa, pb = mi.traverse(a), mi.traverse(b)
    if sorted(pa.keys()) != sorted(pb.keys()):
        return False
    for k in pa.keys():
        x, y = pa[k], pb[k]
        if isinstance(x, (int, float)) or isinstance(y, (int, float)):
            if not (isinstance(x, (int, float)) and isinstance(y, (int, float))
                    and math.isclose(x, y, rel_tol=1e-5)):
                return False
        elif type(x) is not type(y) or dr.width(x) != dr.width(y) or not dr.allclose(x, y):
            return False
    return True


def _from_file(bsdf, dicts, used, label):
    """(dict, BSDF loaded from it) of the file's dict that gives ``bsdf`` (same plugin, same
    values), else (None, bsdf): the file's BSDFs are matched by what they are, whatever the
    order of the scene's shapes."""
    for k, (_, d) in enumerate(dicts):
        if d is None or k in used:
            continue
        try:
            b = _load(dict(d), label)
        except EntryError:
            continue
        if _same(b, bsdf):
            used.add(k)
            return d, b
    return None, bsdf


def make_entries(spec, params, first_id, colours):
    """The entries SPEC names (``check``'s SPEC: a plugin, or an XML file's BSDFs), with the
    ``-p`` values ``params`` (raw strings). Raises ValueError as ``check`` does. A BSDF of
    an XML file that its dictionary does not give again (a texture with a transform, say)
    is shown with controls from ``mi.traverse`` and cannot be exported."""
    loaded = load_bsdfs(spec, params)
    is_file = spec.lower().endswith(".xml") or os.path.isfile(spec)
    dicts, used = (_xml_dicts(spec, params) if is_file else []), set()
    out = []
    for name, bsdf in loaded:
        if is_file:
            label, source = f"{name} ({os.path.basename(spec)})", spec
            props, bsdf = _from_file(bsdf, dicts, used, label)
        else:
            props = {"type": spec, **{k: parse_value(v) for k, v in params.items()}}
            label, source = spec, None
            bsdf = _load(dict(props), label)
        ident = first_id + len(out)
        entry = Entry(ident, label, props, bsdf, colours[ident % len(colours)], source)
        if not is_file:
            _check_params(entry, params)
        out.append(entry)
    return out


def _check_params(entry, params):
    """Refuse ``-p`` values outside their control's range, as the page does (a plugin of
    Mitsuba's accepts many values it is not meant for, an alpha of -3 among them)."""
    for name, raw in params.items():
        c = next((c for c in entry.controls if c["name"] == name), None)
        if c is None or c["kind"] not in ("float", "int", "colour"):
            continue
        value = parse_value(raw)
        if isinstance(value, dict):
            value = value.get("value", value)
        entry._checked(c, value)
