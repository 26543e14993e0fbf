"""Reading a scene XML file as text (ElementTree), without loading it in Mitsuba: its
``<default>`` values (``defaults``) and its integrator (``scene_integrator``).
"""
import xml.etree.ElementTree as ET

__all__ = ["defaults", "scene_integrator"]


def defaults(scene):
    """{name: value} of the ``<default>`` elements of ``scene`` (a file's path, or the root
    element of a parsed file), values as written."""
    root = ET.parse(scene).getroot() if isinstance(scene, str) else scene
    return {d.get("name"): d.get("value") for d in root.iter("default")}


def scene_integrator(path, defines=None):
    """The integrator of a scene XML as a dict (``type`` and its properties), with the
    ``<default>`` values (overridden by ``defines``) substituted."""
    root = ET.parse(path).getroot()
    values = defaults(root)
    values.update({k: str(v) for k, v in (defines or {}).items()})

    def resolve(text):
        return values[text[1:]] if text.startswith("$") else text

    (elem,) = root.findall("integrator")
    props = {"type": resolve(elem.get("type"))}
    for child in elem:
        value = resolve(child.get("value"))
        props[child.get("name")] = {"integer": int, "float": float,
                                    "boolean": lambda v: v.lower() == "true"}[child.tag](value)
    return props
