"""A ``mi.load_dict`` dictionary of a BSDF as Mitsuba XML: one writer for the presets, the
fitted models of ``fit-measured``, the explorer's export and the tests.

``dict_to_xml(d)`` writes ``<bsdf type="...">`` (a texture's dictionary as ``<texture>``)
with each value as Mitsuba reads it back: ``<boolean>``, ``<integer>``, ``<float>``,
``<string>``, ``<rgb>`` (``{"type": "rgb", "value": [r, g, b]}``), ``<spectrum>`` (a
constant or wavelength:value pairs) and nested dictionaries (a texture, a nested BSDF) as
elements of their own. Numbers are written with ``digits`` significant digits (9 give back
a float32 exactly); ``version`` adds the attribute a file's root element needs
(``version="3.0.0"``, which Mitsuba refuses on an element nested in a scene).
"""
from xml.sax.saxutils import quoteattr

__all__ = ["XML_VERSION", "TEXTURES", "dict_to_xml"]

#: the scene format version a ``<bsdf>`` file's root element names
XML_VERSION = "3.0.0"
#: plugin types written as ``<texture>``
TEXTURES = ("bitmap", "checkerboard", "mesh_attribute")


def _num(x, digits):
    return f"{float(x):.{digits}g}"


def _value(name, value, indent, digits):
    pad, q = " " * indent, quoteattr(name)
    if isinstance(value, bool):
        return [f'{pad}<boolean name={q} value="{str(value).lower()}"/>']
    if isinstance(value, int):
        return [f'{pad}<integer name={q} value="{value}"/>']
    if isinstance(value, float):
        return [f'{pad}<float name={q} value="{_num(value, digits)}"/>']
    if isinstance(value, str):
        return [f'{pad}<string name={q} value={quoteattr(value)}/>']
    if isinstance(value, dict) and value.get("type") == "rgb":
        text = ", ".join(_num(v, digits) for v in value["value"])
        return [f'{pad}<rgb name={q} value="{text}"/>']
    if isinstance(value, dict) and value.get("type") == "spectrum":
        v = value["value"]
        text = _num(v, digits) if isinstance(v, (int, float)) else ", ".join(
            f"{_num(a, digits)}:{_num(b, digits)}" for a, b in v)
        return [f'{pad}<spectrum name={q} value="{text}"/>']
    if isinstance(value, dict):
        return dict_to_xml(value, indent, name, digits=digits).splitlines()
    raise ValueError(f"{name}: cannot write {type(value).__name__} as XML")


def dict_to_xml(d, indent=0, name=None, version=False, digits=6):
    """The dictionary ``d`` (with its ``type``) as an XML element (see the module)."""
    tag = "texture" if d["type"] in TEXTURES else "bsdf"
    pad = " " * indent
    attrs = (f" name={quoteattr(name)}" if name else "") + (
        f' version="{XML_VERSION}"' if version else "") + f" type={quoteattr(d['type'])}"
    lines = [f"{pad}<{tag}{attrs}>"]
    for k, v in d.items():
        if k != "type":
            lines += _value(k, v, indent + 4, digits)
    if len(lines) == 1:
        return f"{pad}<{tag}{attrs}/>"
    return "\n".join(lines + [f"{pad}</{tag}>"])
