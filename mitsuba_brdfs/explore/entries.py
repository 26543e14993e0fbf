"""The BSDFs the explorer shows: how each is loaded, what the page sees of it, and how it is
changed. A measured file's entry (``measured_entry``, ``measurement``) is Mitsuba's
``measured`` plugin without controls; a fitted model's is a plugin of this package whose
state carries its fit's summary.

An ``Entry`` keeps the ``load_dict`` dictionary of its BSDF (``props``: what the user set,
the plugin's defaults for the rest), which is what the exports write. A change of a value
that ``mi.traverse`` exposes with the same type is written into the loaded BSDF and
``params.update()`` is called: its parameters are opaque, so the kernels of the plots and
of the sphere are found in Dr.Jit's cache. Any other change (a choice, a float becoming a
colour, a parameter set for the first time, another parametrisation) loads the plugin
again from ``props``. A value the plugin refuses leaves the entry as it was, and the
message is returned to the page.

A parameter with partners (``alpha_u`` and ``alpha_v``) is set one at a time: the others
keep their current value, or take the same value when they were not in use; a parameter
with alternatives (``alpha_u`` instead of ``nu``, ``nv``) takes them out of the dictionary
(``controls``). Back to the default (``None``), a parameter goes with its partners.
"""
import math
import os

import drjit as dr
import mitsuba as mi

from .controls import active, checked, doc_controls, is_colour, traverse_controls
from .messages import EntryError, message, shown
from .xmldict import xml_dicts

__all__ = ["Entry", "load", "make_entries", "measured_entry", "plugin_models"]


def plugin_models():
    """{plugin name: model class} of this package."""
    from ..core.registry import models
    return models()


def load(props, label):
    """``mi.load_dict(props)`` as a BSDF; ``EntryError`` with the plugin's reason."""
    try:
        obj = mi.load_dict(props)
    except Exception as e:  # noqa: BLE001 (any plugin's refusal is said in the page)
        raise EntryError(message(e, label)) from None
    if not isinstance(obj, mi.BSDF):
        raise EntryError(f"{label}: {shown(props.get('type'))} is not a BSDF plugin")
    return obj


def _display(value):
    """A props value as the page shows it: a number, [r, g, b], a string, a bool."""
    if is_colour(value):
        return [float(x) for x in value["value"]]
    if isinstance(value, dict) and value.get("type") == "spectrum" and isinstance(
            value.get("value"), (int, float)):
        return float(value["value"])
    return value


def _bound(x):
    """A range's end as the page takes it: the number, or None where the range is open."""
    return x if math.isfinite(x) else None


def _class(bsdf):
    """A BSDF's class: Mitsuba's name, or for a Python plugin (whose class name Mitsuba
    gives as "BSDF") the head of its ``to_string``."""
    name = bsdf.class_name()
    return name if name != "BSDF" else str(bsdf).split("[")[0].strip() or name


class Entry:
    """One BSDF of the page: its dictionary, the loaded BSDF, its controls and colour."""

    def __init__(self, ident, label, props, bsdf, colour, source=None, measured=None,
                 fit=None):
        self.id, self.label, self.props, self.bsdf = ident, label, props, bsdf
        self.colour, self.visible, self.version = colour, True, 0
        self.source = source  #: an XML file's path, else None
        #: a measured file's entry: what ``measurement.rgl_file`` says of it, else None
        self.measured = measured
        #: a fitted entry: what the fit says of it (``fitting.summary``), else None
        self.fit = fit
        self.fit_data = None  #: a measured entry's samples for fits, made at the first
        self.ours = props is not None and props.get("type") in plugin_models()
        self.plugin = props.get("type") if props else _class(bsdf)
        self.controls = (doc_controls(self.plugin) if self.ours else
                         traverse_controls(bsdf, self.plugin))

    # what the page sees
    def state(self):
        """The entry as the page receives it: its controls with their values, which are
        set in the dictionary, and which are in use (the parametrisation in force); an
        open end of a control's range (``lo``, ``hi``) is None."""
        used = active(self.controls, self.bsdf)
        params = mi.traverse(self.bsdf)
        controls = []
        for c in self.controls:
            set_ = self.props is not None and c["name"] in self.props
            value = _display(self.props[c["name"]]) if set_ else self._current(c, params)
            ends = {k: _bound(c[k]) for k in ("lo", "hi") if k in c}
            controls.append({**c, **ends, "value": value, "set": set_,
                             "active": used[c["name"]]})
        return {"id": self.id, "label": self.label, "plugin": self.plugin,
                "colour": self.colour, "visible": self.visible, "version": self.version,
                "exportable": self.props is not None, "controls": controls,
                "measured": self._measured_state(), "fit": self.fit}

    def _measured_state(self):
        if self.measured is None:
            return None
        from .measurement import describe
        m = self.measured
        return {"kind": m["kind"], "file": m["file"], "rgl": m["rgl"], "note": m["note"],
                "text": describe(m)}

    def _current(self, c, params):
        """The value a control shows when the dictionary does not set it."""
        if "key" in c:
            v = params[c["key"]]
            if isinstance(v, float):
                return v
            return float(v[0]) if c["kind"] == "float" else [float(x[0]) for x in v]
        return c["default"]

    def control(self, name):
        if not isinstance(name, str):
            raise EntryError(f"{self.label}: a parameter's name is a string (got "
                             f"{shown(name)})")
        for c in self.controls:
            if c["name"] == name:
                return c
        raise EntryError(f"{self.label}: no parameter {shown(name)} (it has "
                         f"{', '.join(c['name'] for c in self.controls)})")

    # changes
    def set(self, name, value):
        """Set one parameter (``value`` None: back to the plugin's default)."""
        c = self.control(name)
        new = None if value is None else checked(c, value, self.label)
        if self.props is None:  # an XML file's BSDF without a dictionary: traverse only
            if new is None or not self._update_in_place(c, new):
                raise EntryError(f"{self.label}: '{name}' can be changed here only as it is "
                                 f"(a {c['kind']}); edit {self.source} for more")
            self.version += 1
            return
        props = self._with(c, new)
        same_keys = set(props) == set(self.props)
        if not (same_keys and self._update_in_place(c, new)):
            self.bsdf = load(dict(props), self.label)  # refused: nothing changed
        self.props.clear()
        self.props.update(props)
        self.version += 1

    def _with(self, c, new):
        """The dictionary with ``new`` for control ``c``: its alternatives out, its partners
        at their current value (or at ``new`` when they were not set)."""
        props = dict(self.props)
        group = [c["name"], *c.get("partners", ())]
        if new is None:
            for n in group:
                props.pop(n, None)
            return props
        props[c["name"]] = new
        for n in c.get("alternatives", ()):
            props.pop(n, None)
        for n in group[1:]:
            props.setdefault(n, new)
        return props

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
        colour = is_colour(new)
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
        except Exception as e:  # noqa: BLE001 (the plugin's refusal, said in the page)
            params[key] = old
            params.update()
            raise EntryError(message(e, self.label)) from None
        return True


# -- making entries from a SPEC ------------------------------------------------------------

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
            b = load(dict(d), label)
        except EntryError:
            continue
        if _same(b, bsdf):
            used.add(k)
            return d, b
    return None, bsdf


def _file_label(name, spec):
    """"ward (nickel.xml)" for a BSDF of nickel.xml whose name does not say the file
    already (``check`` names a BSDF by its id, or by its plugin and where it is)."""
    base = os.path.basename(spec)
    return name if base in name else f"{name} ({base})"


def make_entries(spec, params, first_id, colours):
    """The entries SPEC names (``check``'s SPEC: a plugin, or an XML file's BSDFs; or a
    measured file: ``measured_entry``), with the ``-p`` values ``params`` (raw strings).
    Raises ValueError as ``check`` does. An XML
    file that is not in the current folder but installed with the package, named as the
    README names it (``scenes/as_sphere.xml``), is that copy (``variant.find_input``, as
    ``check`` and ``render`` take it). A BSDF of an XML file that its dictionary does not
    give again (a texture with a transform, say) is shown with controls from
    ``mi.traverse`` and cannot be exported."""
    from ..spec import load_bsdfs, parse_value
    from ..variant import find_input
    from .measurement import is_measured
    if is_measured(spec):
        return [measured_entry(spec, params, first_id, colours)]
    if spec.lower().endswith(".xml"):  # a scene the README names, from any folder
        spec = find_input(spec)
    loaded = load_bsdfs(spec, params)  # refused as check refuses it (ValueError)
    is_file = spec.lower().endswith(".xml") or os.path.isfile(spec)
    dicts, used = (xml_dicts(spec, params) if is_file else []), set()
    out = []
    for name, bsdf in loaded:
        if is_file:
            label, source = _file_label(name, spec), spec
            props, bsdf = _from_file(bsdf, dicts, used, label)
        else:
            props = {"type": spec, **{k: parse_value(v) for k, v in params.items()}}
            label, source = spec, None
            bsdf = load(dict(props), label)
        ident = first_id + len(out)
        entry = Entry(ident, label, props, bsdf, colours[ident % len(colours)], source)
        if not is_file:
            _check_params(entry, params)
        out.append(entry)
    return out


def measured_entry(path, params, ident, colours):
    """The entry of a measured file (RGL or MERL; ``measurement.rgl_file``): Mitsuba's
    ``measured`` plugin on its RGL file, without controls. ValueError in one line for a
    file that cannot be shown, or ``-p`` values (measured data have no parameters)."""
    from .measurement import rgl_file
    if params:
        raise ValueError(f"{path}: measured data take no -p parameters (got "
                         f"{', '.join(params)}; -p SPEC:KEY=VALUE gives one to another SPEC)")
    info = rgl_file(path)
    label = os.path.basename(path)
    props = {"type": "measured", "filename": info["rgl"]}
    bsdf = load(dict(props), label)
    return Entry(ident, label, props, bsdf, colours[ident % len(colours)], measured=info)


def _check_params(entry, params):
    """Refuse ``-p`` values outside their control's range, as the page does (a plugin of
    Mitsuba's accepts many values it is not meant for, an alpha of -3 among them)."""
    from ..spec import parse_value
    for name, raw in params.items():
        c = next((c for c in entry.controls if c["name"] == name), None)
        if c is None or c["kind"] not in ("float", "int", "colour"):
            continue
        value = parse_value(raw)
        if isinstance(value, dict):
            value = value.get("value", value)
        checked(c, value, entry.label)
