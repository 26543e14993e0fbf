"""What the explorer says when something cannot be done: ``EntryError`` (a request that
cannot be used, answered with status 400 and its one line), the one line of a plugin's
exception (``message``) and values quoted in messages, cut short (``shown``).

A plugin of this package that refuses a value raises from its constructor, inside
Mitsuba's loader, which wraps the message: ``At dictionary node "root": failed to
instantiate unknown plugin of type "ashikhmin_shirley": Traceback ... ParameterError:
ashikhmin_shirley: parameter 'nu' must be ...`` (Mitsuba calls a plugin registered from
Python "unknown" although it found it). ``message`` gives the cause alone, which names the
plugin, the parameter and the range.
"""
import re

__all__ = ["EntryError", "message", "cause", "shown", "jsonable"]

#: Mitsuba's loader's words around the plugin's own message
_WRAPPER = re.compile(r'^(?:At (?:dictionary )?node "[^"]*": )?failed to instantiate '
                      r'(?:\w+ )?plugin of type "[^"]*":\s*')
#: the exception's class that a Python traceback embedded in a message ends with
_CLASS = re.compile(r"(?:^|(?<=: ))(?:\w+\.)*\w*(?:Error|Exception): ")


class EntryError(ValueError):
    """A value or request that cannot be used; its message is shown in the page."""


def shown(value, width=60):
    """``repr(value)``, cut to ``width`` characters (a value quoted in a message)."""
    text = repr(value)
    return text if len(text) <= width else text[:width] + "..."


def cause(text):
    """A one-line message without Mitsuba's loader's wrapper and the class names of the
    exceptions inside it, a repeated "plugin: " said once: the plugin's own sentence."""
    text = re.sub(r"\[[\w./-]+\.cpp:\d+\]\s*", "", text)  # Mitsuba's source locations
    for _ in range(3):  # "node: failed ...: ParameterError: plugin: ..." -> "plugin: ..."
        text = _CLASS.sub("", _WRAPPER.sub("", text.strip())).strip()
        text = re.sub(r"^(\w+: )\1", r"\1", text)
    return re.sub(r'(\w+: )(?:At (?:dictionary )?node "[^"]*": )?failed to instantiate '
                  r'(?:\w+ )?plugin of type "[^"]*":\s*', r"\1", text)


def message(e, label):
    """The one line of an exception that the page shows, about the BSDF ``label``: of the
    innermost exception when Dr.Jit wrapped the plugin's own (a render does), without
    Mitsuba's loader's wrapper (``cause``), starting with the BSDF's name."""
    from ..__main__ import one_line
    while (e.__cause__ or e.__context__) is not None:
        e = e.__cause__ or e.__context__
    text = cause(one_line(str(e))) or type(e).__name__
    plugin = label.split(" ")[0]
    return text if text.startswith((label, plugin + ":")) else f"{label}: {text}"


def jsonable(x):
    """``x`` as JSON holds it: NumPy values as Python ones, NaN and infinities as None."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if hasattr(x, "tolist") and not isinstance(x, (str, bytes)):  # NumPy scalars and arrays
        return jsonable(x.tolist())
    if isinstance(x, float) and not (x - x == 0):
        return None
    return x
