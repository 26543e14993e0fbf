"""One-line errors and suggestions, shared by every command.

Mitsuba reports a bad scene or plugin in several lines: a source location, the parser's
context, a plugin's Python traceback. The commands print one line instead (``one_line``),
which names the file, the plugin or the parameter, and for a misspelt name the closest one
there is (``suggest``): an unknown parameter gets the closest parameter the plugin takes
(``explain_unknown``), an unknown plugin the closest plugin name of its kind
(``unknown_plugin``): Mitsuba's plugins, this package's, and those that the user's
``--load`` files register (``note_registered``). Nothing here imports a command.
"""
import difflib
import os
import re

__all__ = ["suggest", "last_line", "one_line", "explain_unknown", "known_parameters",
           "plugin_names", "note_registered", "unknown_plugin"]

#: plugin names that the user's Python files register (name -> kind, e.g. "bsdf")
_REGISTERED = {}


def suggest(word, choices, cutoff=0.6):
    """`` (did you mean 'x'?)`` with the closest of ``choices`` (difflib), or ''."""
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=cutoff)
    return f" (did you mean '{close[0]}'?)" if close else ""


def last_line(e):
    """The last non-blank line of an error's message (Mitsuba's put the cause last)."""
    lines = [ln.strip() for ln in str(e).splitlines() if ln.strip()]
    return lines[-1] if lines else ""


# -- plugin names --------------------------------------------------------------------------

def note_registered(path):
    """Remember the plugin names a user's Python file registers (``mi.register_bsdf("x",
    ...)`` and the other ``register_*`` calls, read from its text), for suggestions."""
    try:
        with open(path, errors="replace") as f:
            text = f.read()
    except OSError:
        return []
    found = re.findall(r"register_(\w+)\(\s*['\"]([^'\"]+)['\"]", text)
    for kind, name in found:
        _REGISTERED[name] = kind
    return [name for _, name in found]


def _mitsuba_plugins():
    """{name: kind} of Mitsuba's own plugins (its plugin libraries), kind as
    ``mi.ObjectType`` names it in lower case ("bsdf", "shape", ...)."""
    import mitsuba as mi
    folder = os.path.join(os.path.dirname(mi.__file__), "plugins")
    try:
        files = os.listdir(folder)
    except OSError:
        return {}
    manager = mi.PluginManager.instance()
    out = {}
    for f in sorted(files):
        name, ext = os.path.splitext(f)
        if ext not in (".so", ".dll", ".dylib"):
            continue
        try:
            out[name] = manager.plugin_type(name).name.lower()
        except Exception:  # noqa: BLE001  (a library that is not a plugin)
            continue
    return out


_MITSUBA = None


def plugin_names(kind=None):
    """The plugin names Mitsuba knows here, of ``kind`` ("bsdf", "shape", ...; None: all):
    Mitsuba's own, this package's (BSDFs) and those noted from the user's files."""
    global _MITSUBA
    if _MITSUBA is None:
        _MITSUBA = _mitsuba_plugins()
    from .core.registry import models
    names = dict(_MITSUBA)
    names.update({name: "bsdf" for name in models()})
    names.update(_REGISTERED)
    return sorted(n for n, k in names.items() if kind is None or k == kind)


def unknown_plugin(name, kind=None, say_kind=False):
    """``unknown plugin 'wardd' (did you mean 'ward'?)``: the closest name of the plugins of
    ``kind`` ("bsdf", ...; of any kind when it is None or "unknown"); with ``say_kind``,
    ``unknown bsdf plugin 'wardd' ...``."""
    kind = None if kind == "unknown" else kind
    what = f"{kind} plugin" if kind and say_kind else "plugin"
    return f"unknown {what} '{name}'{suggest(name, plugin_names(kind))}"


# -- Mitsuba's messages as one line --------------------------------------------------------

def known_parameters(plugin):
    """(names, complete): the parameter names ``plugin`` reads, from the table of its
    docstring for this package's plugins (complete), else those ``mi.traverse`` exposes of
    it built with its defaults (Mitsuba's and users' plugins: a part of them)."""
    import mitsuba as mi
    try:
        from .docstrings import parameters
        return [p.name for p in parameters(plugin)], True
    except (KeyError, ValueError, StopIteration):
        pass
    try:
        keys = mi.traverse(mi.load_dict({"type": plugin})).keys()
    except Exception:  # noqa: BLE001  (a plugin that needs parameters to load)
        return [], False
    return list(dict.fromkeys(k.split(".")[0] for k in keys)), False


#: Mitsuba's parser: where (a file and line, a dictionary node), the kind of plugin and its
#: name, then "Plugin "x" not found"
_NOT_FOUND = re.compile(
    r'(?:At (?P<where>.*?): )?failed to instantiate (?P<kind>\w+) plugin of type '
    r'"(?P<name>[^"]+)": \[PluginManager\] Plugin "[^"]+" not found!?')


def _where(text):
    """Mitsuba's 'file "scene.xml" (line 3, col 5)' as 'scene.xml (line 3, col 5)';
    a dictionary's root node as nothing."""
    if not text or text == 'dictionary node "root"':
        return ""
    m = re.match(r'file "(.*)" (\(line .*\))', text)
    return f"{m.group(1)} {m.group(2)}" if m else text


def _at(where, text):
    """``text`` after where it happened (``_where``), if anywhere."""
    where = _where(where)
    return f"{where}: {text}" if where else text


#: Mitsuba's parser around the error of a plugin it could not build: where (a file and line,
#: a dictionary node), the kind of plugin and its name, then the plugin's own message
_FAILED = re.compile(r'^(?:At|While loading) (?P<where>.*?): failed to instantiate '
                     r'(?P<kind>\w+) plugin of type "(?P<name>[^"]+)": (?P<cause>.*)$')


def _plugin_error(message):
    """Mitsuba's "At scene.xml (line 5, col 27): failed to instantiate bsdf plugin of type
    "ward": ParameterError: ward: parameter 'alpha_u' must be ..." as "scene.xml (line 5,
    col 27): ward: parameter 'alpha_u' must be ...": where, the plugin's name once, and its
    message without the exception's class when the message names the plugin itself, or a
    C++ class tag ("[SRGBReflectanceSpectrum] "). Other messages are returned unchanged."""
    m = _FAILED.match(message)
    if not m:
        return message
    name, cause = m.group("name"), m.group("cause")
    cause = re.sub(r"^(?:\[[\w:]+\]\s*)+", "", cause)
    named = re.match(r"^\w+(?:Error|Exception): (.*)$", cause)
    if named and named.group(1).startswith(f"{name}:"):
        cause = named.group(1)
    return _at(m.group("where"), cause if cause.startswith(f"{name}:") else f"{name}: {cause}")


def explain_unknown(message):
    """Mitsuba's messages for unknown names, with the closest known name:

    - a plugin that does not exist ("Plugin "wardd" not found"): ``unknown bsdf plugin
      'wardd' (did you mean 'ward'?)``, after where the file or dictionary names it;
    - parameters a plugin did not read ("Found 1 unreferenced property in ... plugin of
      type "ward": - float "alpah_u": 0.1"): each unknown parameter with the closest name
      the plugin takes, after where the file names the plugin.

    Other messages are returned unchanged."""
    m = _NOT_FOUND.search(message)
    if m:
        return _at(m.group("where"), unknown_plugin(m.group("name"), m.group("kind"),
                                                    say_kind=True))
    m = re.search(r'(?:While loading (?P<where>.*?): )?Found \d+ unreferenced propert'
                  r'(?:y|ies) in .*?plugin of type "(?P<plugin>\w+)"', message)
    if not m:
        return message
    plugin = m.group("plugin")
    given = re.findall(r'\s-?\s*\w+ "([^"]+)"', message[m.end():])
    known, complete = known_parameters(plugin)
    parts = [f"unknown parameter '{name}'{suggest(name, known)}" for name in given]
    if not parts:
        return message
    takes = f"; {plugin} takes {', '.join(known)}" if known and complete else ""
    return _at(m.group("where"), f"{plugin}: {', '.join(parts)}{takes}")


def one_line(message):
    """One line of an error (its message, or the exception itself): Mitsuba's source
    locations dropped, its lists joined, of a plugin's Python traceback embedded in the
    message only the context and the cause, unknown names explained (``explain_unknown``),
    and a plugin's own error said after where it happened and the plugin's name, once
    (``_plugin_error``)."""
    message = str(message)
    if "Traceback" in message:
        head = message.split("Traceback")[0].rstrip(" :")
        lines = [ln for ln in message.splitlines() if ln.strip()]
        message = f"{head}: {lines[-1].strip()}"
    lines = [ln.strip().removeprefix("- ") for ln in message.splitlines() if ln.strip()]
    text = " ".join(lines).replace("\u200b", "")
    text = re.sub(r"\[[\w./-]+\.cpp:\d+\]\s*", "", text)
    if text.startswith("Found unused parameters:"):
        text += " (a -D KEY=VALUE whose $KEY the scene does not use)"
    explained = explain_unknown(text)
    return _plugin_error(text) if explained == text else explained
