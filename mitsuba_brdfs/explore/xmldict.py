"""The explorer's conversions between Mitsuba's scene XML and ``load_dict`` dictionaries.

``xml_to_dict`` reads a ``<bsdf>`` element (with ``$name`` substitution from the file's
``<default>``s and ``-D`` values) into the dictionary an ``Entry`` keeps; ``dict_to_xml`` and
``dict_to_python`` write it back out as the page's "Mitsuba XML" and ``load_dict`` exports.
"""
import os
import xml.etree.ElementTree as ET

from ..bsdf_xml import dict_to_xml as _dict_to_xml
from ..scene_xml import defaults as scene_defaults
from .messages import EntryError

__all__ = ["xml_to_dict", "xml_dicts", "dict_to_xml", "dict_to_python"]


def _subst(text, defaults):
    """``$name`` in an XML attribute, from the file's ``<default>`` tags and ``-p``."""
    for k in sorted(defaults, key=len, reverse=True):
        text = text.replace("$" + k, str(defaults[k]))
    return text


def _numbers(text):
    return [float(x) for x in text.replace(",", " ").split()]


def xml_to_dict(elem, defaults=None, folder="."):
    """A ``<bsdf>`` (or texture) element as a ``load_dict`` dictionary. Relative file names
    are made absolute from ``folder``. Raises ``EntryError`` for what it does not know
    (a ``<ref>``, a transform)."""
    defaults = defaults or {}
    out = {"type": _subst(elem.get("type", ""), defaults)}
    for child in elem:
        name = _subst(child.get("name", ""), defaults)
        value = _subst(child.get("value", ""), defaults)
        tag = child.tag
        if tag in ("float",):
            out[name] = float(value)
        elif tag == "integer":
            out[name] = int(value)
        elif tag == "boolean":
            out[name] = value.lower() == "true"
        elif tag == "string":
            path = os.path.join(folder, value)
            out[name] = path if name == "filename" and os.path.exists(path) else value
        elif tag == "rgb":
            v = _numbers(value)
            out[name] = {"type": "rgb", "value": v * 3 if len(v) == 1 else v}
        elif tag == "spectrum":
            v = _numbers(value) if ":" not in value else None
            out[name] = ({"type": "spectrum", "value": v[0]} if v and len(v) == 1 else
                         {"type": "spectrum", "value": [tuple(map(float, p.split(":")))
                                                        for p in value.replace(",", " ").split()]})
        elif tag in ("bsdf", "texture"):
            key = name or child.get("id") or f"{tag}_{len(out)}"
            out[key] = xml_to_dict(child, defaults, folder)
        else:
            raise EntryError(f"<{tag}> inside the <bsdf> is not shown by explore")
    return out


def _defaults(root, params):
    return {**scene_defaults(root), **params}


def xml_dicts(path, params):
    """[(id, dict or None)] of the BSDFs of an XML file: the file's root ``<bsdf>``, or the
    BSDF of every shape in file order (its ``<bsdf>``, the one its ``<ref>`` names, or
    Mitsuba's default ``diffuse``), each once, as ``spec.load_bsdfs`` lists them."""
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError):
        return []
    defaults, folder = _defaults(root, params), os.path.dirname(os.path.abspath(path))

    def convert(e):
        try:
            return xml_to_dict(e, defaults, folder)
        except (EntryError, ValueError):
            return None
    if root.tag == "bsdf":
        return [(root.get("id"), convert(root))]
    named = {e.get("id"): e for e in root.findall("bsdf")}
    out, seen = [], set()
    for shape in root.findall("shape"):
        e, ref = shape.find("bsdf"), shape.find("ref")
        if e is None and ref is not None:
            e = named.get(ref.get("id"))
        if e is None:  # Mitsuba's default: black on an emitter, else diffuse 0.5
            black = shape.find("emitter") is not None
            out.append((None, {"type": "diffuse", **({"reflectance": 0.0} if black else {})}))
        elif e.get("id") is None or e.get("id") not in seen:
            seen.add(e.get("id"))
            out.append((e.get("id"), convert(e)))
    return out


def dict_to_xml(d):
    """A ``load_dict`` dictionary of a BSDF (or texture) as Mitsuba XML (``bsdf_xml``);
    ``EntryError`` for a value XML cannot hold."""
    try:
        return _dict_to_xml(d)
    except ValueError as e:
        raise EntryError(str(e)) from None


def dict_to_python(d):
    """The ``mi.load_dict(...)`` call of a dictionary, as Python source."""
    return "mi.load_dict(" + _py(d, 0) + ")"


def _py(v, indent):
    if isinstance(v, dict):
        pad = " " * (indent + 4)
        items = [f"{pad}{k!r}: {_py(x, indent + 4)}," for k, x in v.items()]
        return "{\n" + "\n".join(items) + "\n" + " " * indent + "}"
    if isinstance(v, float):
        return _fmt(v) if "." in _fmt(v) or "e" in _fmt(v) else _fmt(v) + ".0"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_py(x, indent) for x in v) + "]"
    return repr(v)


def _fmt(x):
    return f"{x:.6g}"

