"""Naming a BSDF as the commands take it: a SPEC and ``-p KEY=VALUE`` values.

SPEC is a plugin name (one of Mitsuba's, one of this package's, or one that a Python file
given with ``--load FILE.py`` registers: ``variant.run_file``) or an XML file holding a
``<bsdf>`` or a scene (then every BSDF of its shapes). ``parse_params`` reads the ``-p``
items (a key given twice is refused), ``parse_value`` one value as ``mi.load_dict`` takes
it, and ``load_bsdfs`` loads what SPEC names, refusing in one line what cannot be loaded.
``check``, ``explore``, ``to-rgl``, ``to-merl`` and ``fit-measured`` name BSDFs this way.

Plugin names are words (``roughplastic``, ``ward``): a SPEC with an extension
(``gold-paint.binary``, ``nickel.xml``) or a folder in it (``./ward``, ``data/x``) names a
file (``names_file``), and one that is not there is "no such file" in every command
(``locate``), never an unknown plugin.
"""
import os
import re

from .arguments import UsageError, number, refuse_repeated
from .messages import one_line, unknown_plugin
from .variant import check_file, check_scene, find_input

__all__ = ["parse_value", "parse_params", "names_file", "locate", "load_bsdfs"]

#: the extensions of measured files: a missing one gets a hint where to find or make one
MEASURED_EXTENSIONS = (".binary", ".bsdf")


def parse_value(text):
    """A ``-p`` value: a number is a float, ``r,g,b`` an RGB colour, ``true``/``false`` a
    bool, anything else a string."""
    x = number(text)
    if x is not None:
        return x
    parts = [number(p) for p in text.split(",")]
    if len(parts) == 3 and None not in parts:
        return {"type": "rgb", "value": parts}
    if text.lower() in ("true", "false"):
        return text.lower() == "true"
    return text


def parse_params(items):
    """``KEY=VALUE`` strings -> {key: raw string}; a malformed one, or a key given twice
    (``-p alpha=0.1 -p alpha=0.2``: which one was meant?), is a ValueError."""
    pairs = []
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise ValueError(f"bad -p {item!r}: expected KEY=VALUE (e.g. -p alpha=0.2, "
                             f"-p reflectance=0.8,0.2,0.1, -p distribution=ggx)")
        pairs.append((key.strip(), value.strip()))
    return refuse_repeated(pairs, "-p")


def names_file(spec):
    """Whether SPEC names a file rather than a plugin: it has a folder in it (``./ward``,
    ``data/x.bsdf``) or an extension (``gold-paint.binary``, ``nickel.xml``); plugin names
    are words."""
    spec = os.fspath(spec)
    seps = [os.sep] + ([os.altsep] if os.altsep else []) + ["/"]
    return (any(s in spec for s in seps) or spec.startswith("~")
            or bool(os.path.splitext(spec)[1].strip(".")))


def locate(spec):
    """The file SPEC names, if it names one (``names_file``): SPEC itself, or the copy of
    a scene or example installed with the package that it names as the README does
    (``variant.find_input``: ``scenes/as_sphere.xml`` from any folder). A file that is not
    there is a ``UsageError``, "SPEC: no such file" (with where to get or make one for a
    measured file). A plugin name is returned as it is."""
    spec = os.fspath(spec)
    if not names_file(spec):
        return spec
    found = find_input(spec)
    if not os.path.exists(found):
        hint = ""
        if spec.lower().endswith(MEASURED_EXTENSIONS):
            hint = (" (a measured file: to-rgl or to-merl writes one from any BSDF; "
                    "docs/measured.md says where to download MERL and RGL files)")
        raise UsageError(f"{spec}: no such file{hint}")
    return found


def _plugin_type(bsdf, types):
    """The plugin name of a BSDF: this package's ``NAME``, else the one of ``types`` (the
    plugin types named in the file) that builds an object of the same class."""
    import mitsuba as mi
    name = getattr(bsdf, "NAME", None)
    if name:
        return name
    for t in types:
        try:
            other = mi.load_dict({"type": t})
        except Exception:  # noqa: BLE001  (a plugin that needs parameters to load)
            continue
        if type(other) is type(bsdf) and other.class_name() == bsdf.class_name():
            return t
    return bsdf.class_name()


def _black_default(bsdf):
    """Whether ``bsdf`` is the black diffuse Mitsuba gives a light-emitting shape that has no
    BSDF of its own."""
    text = " ".join(str(bsdf).split())
    return bsdf.class_name() == "SmoothDiffuse" and "reflectance = UniformSpectrum[value=[0]]" in text


def _shapes(scene):
    """(where, shape) of the shapes of a scene: "shape 'id'", or "shape K" for the K-th of
    ``scene.shapes()``; then those of its shape groups ("shape K of group 'g'"), which
    ``scene.shapes()`` does not list, and without their instances: an instance's
    ``bsdf()`` is the grey diffuse Mitsuba gives every shape by default, not the user's."""
    import mitsuba as mi
    out = [(k, shape) for k, shape in enumerate(scene.shapes())
           if shape.class_name() != "Instance"]
    groups = []

    class Walk(mi.TraversalCallback):
        def __init__(self, into):
            super().__init__()
            self.into = into

        def put(self, name, value, *rest):
            if isinstance(value, mi.Shape) and value.class_name() == "ShapeGroupPlugin":
                members = []
                value.traverse(Walk(members))
                groups.append((value.id() or name, members))
            elif isinstance(value, mi.Shape) and self.into is not None:
                self.into.append(value)

    try:
        scene.traverse(Walk(None))
    except Exception:  # noqa: BLE001  (a traversal this Mitsuba refuses: the plain list)
        groups = []
    named = [(f"shape '{shape.id()}'" if shape.id() else f"shape {k}", shape) for k, shape in out]
    for group, members in groups:
        named += [(f"shape '{shape.id()}'" if shape.id() else f"shape {k} of group '{group}'",
                   shape) for k, shape in enumerate(members)]
    return named


def _name(bsdf, fallback, types=()):
    """How a BSDF is called in the output: its id, or its plugin type and ``fallback`` (the
    shape that holds it), e.g. "lambert (shape 0)"."""
    if bsdf.id():
        return bsdf.id()
    return f"{_plugin_type(bsdf, types)} ({fallback})"


def load_bsdfs(spec, params):
    """The BSDFs SPEC names, as (name, BSDF) pairs: the plugin with params (raw strings,
    read with ``parse_value``), or those of an XML file (params fill its ``$name``
    defaults). What cannot be loaded is a ValueError in one line: a file that is not there
    (``locate``), a folder, a Python file (it is for --load), an empty or malformed file, an
    unknown plugin (with the closest name), a scene whose shapes lack a
    BSDF (Mitsuba would give them a default diffuse, which is not the user's)."""
    import mitsuba as mi
    spec = locate(spec)
    if os.path.isdir(spec):
        raise UsageError(f"{spec}: is a folder, not a plugin name or an XML file")
    if spec.lower().endswith(".py") and os.path.isfile(spec):
        raise UsageError(f"{spec} is a Python file: run it with --load {spec} and name the "
                         f"plugin it registers as SPEC")
    if spec.lower().endswith(".xml") or os.path.isfile(spec):
        check_file(spec, "")
        try:
            obj = mi.load_file(spec, **params)
        except Exception as e:
            # check's -p gives the file's $KEY defaults, as render's -D does
            reason = one_line(str(e)).replace("(a -D KEY=VALUE", "(a -p KEY=VALUE")
            raise ValueError(reason if reason.startswith((spec, os.path.basename(spec)))
                             else f"{spec} does not load: {reason}") from None
        if isinstance(obj, mi.BSDF):
            return [(_name(obj, os.path.basename(spec)), obj)]
        if not isinstance(obj, mi.Scene):
            raise ValueError(f"{spec} holds a {type(obj).__name__}, not a <bsdf> or a scene")
        check_scene(obj, spec, params, render=False)
        found = []
        with open(spec, errors="replace") as f:
            types = list(dict.fromkeys(re.findall(r'<bsdf\b[^>]*\btype="(\w+)"', f.read())))
        for where, shape in _shapes(obj):
            b = shape.bsdf()
            if shape.is_emitter() and _black_default(b):  # an area light's, not the user's
                continue
            if b is not None and not any(b is f for _, f in found):
                found.append((_name(b, where, types), b))
        if not found:
            raise ValueError(f"{spec}: the scene has no shape, so no BSDF to check")
        return found
    try:
        obj = mi.load_dict({"type": spec, **{k: parse_value(v) for k, v in params.items()}})
    except Exception as e:
        message = str(e)
        if "not found" in message and "Plugin" in message:
            raise ValueError(f"{unknown_plugin(spec, 'bsdf')}: neither Mitsuba's nor this "
                             f"package's (a plugin of your own: --load FILE.py registers it)"
                             ) from None
        reason = one_line(message)
        raise ValueError(reason if reason.startswith(f"{spec}:") else f"{spec}: {reason}"
                         ) from None
    if not isinstance(obj, mi.BSDF):
        raise ValueError(f"{spec!r} is a {type(obj).__name__} plugin, not a BSDF")
    return [(spec, obj)]
