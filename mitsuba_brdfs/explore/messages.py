"""What the explorer says when something cannot be done: ``EntryError`` (a request that
cannot be used, answered with status 400 and its one line), ``Busy`` (a check is running:
409), the one line of a plugin's exception (``message``) and values quoted in messages, cut
short (``shown``).

A plugin that refuses a value raises from its constructor, inside Mitsuba's loader, which
wraps the message (``At dictionary node "root": failed to instantiate ... plugin of type
...: Traceback ...``); ``message`` says it as the command line does (``messages.one_line``:
the plugin's name and its own sentence, which names the parameter and the range).
"""
__all__ = ["EntryError", "Busy", "message", "shown"]


class EntryError(ValueError):
    """A value or request that cannot be used; its message is shown in the page."""


class Busy(Exception):
    """A check is running: one at a time."""


def shown(value, width=60):
    """``repr(value)``, cut to ``width`` characters (a value quoted in a message)."""
    text = repr(value)
    return text if len(text) <= width else text[:width] + "..."


def message(e, label):
    """The one line of an exception that the page shows, about the BSDF ``label``: of the
    innermost exception when Dr.Jit wrapped the plugin's own (a render does), in one line
    as the command line says it (``messages.one_line``), starting with the BSDF's name."""
    from ..messages import one_line
    while (e.__cause__ or e.__context__) is not None:
        e = e.__cause__ or e.__context__
    text = one_line(str(e)) or type(e).__name__
    plugin = label.split(" ")[0]
    return text if text.startswith((label, plugin + ":")) else f"{label}: {text}"
