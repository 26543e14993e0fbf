"""The requests of the explorer's JSON API, read into Python values before anything runs.

Every body is a JSON object (``decode``: standard JSON only, no NaN or Infinity, nesting
and size bounded by the parser and by ``guard.MAX_BODY``) whose fields are those of its
route, each of its type and in its range (``read``): anything else is an ``EntryError``
naming the field, answered with status 400, and nothing has changed. The query of a
sphere's pass is read the same way (``sphere_query``).

A file the page names (``POST /api/entries``) is one of the folder ``explore`` runs in, or
below it and not hidden, or a scene that comes with the package (``spec``): the page and
whoever holds the token cannot have any other file of the machine read, nor learn whether
it exists. Files named on the command line are the user's choice and load from anywhere.
"""
import json
import math
import os
import re

from .evaluate import PARTS
from .messages import EntryError, shown

__all__ = ["decode", "read", "sphere_query", "PLOTS", "PATCH", "ADD", "FIT", "NONE"]

#: longest text accepted (a plugin name or an XML file's path; a parameter's value)
MAX_TEXT = 4096
_NUMBER = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d{1,3})?")


def _refuse_constant(name):
    raise EntryError(f"the body holds {name}, which JSON does not have: send numbers")


def decode(raw):
    """The request body (bytes) as a dict; empty: ``{}``."""
    if not raw.strip():
        return {}
    try:
        body = json.loads(raw, parse_constant=_refuse_constant)
    except EntryError:
        raise
    except RecursionError:
        raise EntryError("the body is nested too deeply to be a request") from None
    except ValueError as e:  # UnicodeDecodeError and JSONDecodeError among them
        raise EntryError(f"the body is not JSON ({str(e).splitlines()[0][:80]})") from None
    if not isinstance(body, dict):
        raise EntryError(f"the body must be a JSON object, not a {type(body).__name__}")
    return body


# -- a field's type and range ----------------------------------------------------------------

def number(lo, hi):
    def check(key, v):
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise EntryError(f"{key} must be a number in [{lo:g}, {hi:g}] (got {shown(v)})")
        try:
            x = float(v)
        except OverflowError:
            x = math.inf
        if not math.isfinite(x) or not lo <= x <= hi:
            raise EntryError(f"{key} must be in [{lo:g}, {hi:g}] (got {shown(v)})")
        return x
    return check


def boolean(key, v):
    if not isinstance(v, bool):
        raise EntryError(f"{key} must be true or false (got {shown(v)})")
    return v


def colour(key, v):
    if not isinstance(v, str) or not re.fullmatch(r"#[0-9a-fA-F]{6}", v):
        raise EntryError(f"{key} must be a colour #rrggbb (got {shown(v)})")
    return v.lower()


def text(key, v):
    if not isinstance(v, str) or len(v) > MAX_TEXT:
        raise EntryError(f"{key} must be a string of at most {MAX_TEXT} characters "
                         f"(got {shown(v)})")
    return v.strip()


def _inside(path, folder):
    """``path`` relative to ``folder`` (both real), or None if it is not inside."""
    rel = os.path.relpath(path, folder)
    return None if rel == os.pardir or rel.startswith(os.pardir + os.sep) else rel


def spec(key, v):
    """A SPEC from the page: a plugin name, or a file of the folder served (see the
    module)."""
    from ..paths import EXAMPLES, SCENES
    from ..variant import find_input
    v = text(key, v)
    if not v.isprintable():  # a NUL, a control character, half of a surrogate pair
        raise EntryError(f"{shown(v)}: not a plugin name nor a file's name")
    if not (v.lower().endswith(".xml") or os.path.lexists(v)):
        return v  # a plugin name
    try:
        real = os.path.realpath(find_input(v, quiet=True) if v.lower().endswith(".xml")
                                else v)
    except ValueError:  # a NUL, a character no file name can hold
        raise EntryError(f"{shown(v)}: not a plugin name nor a file's name") from None
    for folder in (SCENES, EXAMPLES):
        if _inside(real, os.path.realpath(folder)) is not None:
            return v
    here = os.path.realpath(os.getcwd())
    rel = _inside(real, here)
    if rel is None or any(part.startswith(".") and part != "." for part in rel.split(os.sep)):
        raise EntryError(f"{shown(v)}: the page loads the files of the folder explore "
                         f"runs in ({here}), not hidden ones, and the scenes that come with "
                         f"mitsuba_brdfs; name other files on explore's command line")
    return v


def value(key, v):
    """A parameter's value as the page sends it (checked against the parameter's control
    by ``controls.checked``): null, a bool, a number, a string, or a list of numbers."""
    if v is None or isinstance(v, (bool, int, float)):
        return v
    if isinstance(v, str):
        return text(key, v)
    if isinstance(v, list) and len(v) <= 3 and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
        return v
    raise EntryError(f"{key} must be a number, r, g, b, a string, true/false or null "
                     f"(got {shown(v)})")


def parts(key, v):
    if not isinstance(v, list) or not all(isinstance(p, str) and p in PARTS for p in v):
        raise EntryError(f"{key} must be a list of {', '.join(PARTS)} (got {shown(v)})")
    return tuple(dict.fromkeys(v))


def ids(key, v):
    if v is None:
        return None
    if not isinstance(v, list) or len(v) > 1000 or not all(type(i) is int for i in v):
        raise EntryError(f"{key} must be a list of BSDF numbers (got {shown(v)})")
    return set(v)


def change(key, v):
    if v is None:
        return None
    fields = read(v, {"id": (any_value, None), "name": (any_value, None),
                      "value": (value, None)}, key)
    if not isinstance(v, dict) or "id" not in v or "name" not in v:
        raise EntryError(f'{key} must be {{"id", "name", "value"}} (got {shown(v)})')
    return fields["id"], fields["name"], fields["value"]


def any_value(key, v):
    return v


# -- the routes' bodies --------------------------------------------------------------------------

#: field: (check, default)
PLOTS = {"theta_i": (number(0, 89.9), 45.0), "theta_h": (number(0, 90), 30.0),
         "theta_d": (number(0, 90), 30.0), "exposure": (number(-10, 10), 0.0),
         "parts": (parts, PARTS), "ids": (ids, None), "set": (change, None)}
PATCH = {"name": (any_value, None), "value": (value, None), "colour": (colour, None),
         "visible": (boolean, None)}
ADD = {"spec": (spec, "")}
FIT = {"model": (text, "")}
NONE = {}


def read(body, fields, what="the body"):
    """The fields of ``body`` (a dict) checked and with their defaults; EntryError naming
    an unknown field or the first one that cannot be used."""
    if not isinstance(body, dict):
        raise EntryError(f"{what} must be a JSON object (got {shown(body)})")
    unknown = [k for k in body if k not in fields]
    if unknown:
        takes = f"it takes {', '.join(fields)}" if fields else "it takes none"
        raise EntryError(f"{what}: unknown field {shown(unknown[0])} ({takes})")
    return {k: (check(k, body[k]) if k in body else default)
            for k, (check, default) in fields.items()}


def _query_number(q, key, default, lo, hi):
    raw = q.get(key)
    if raw is None:
        return default
    if not _NUMBER.fullmatch(raw.strip()):
        raise EntryError(f"{key} must be a number in [{lo:g}, {hi:g}] (got {shown(raw)})")
    return number(lo, hi)(key, float(raw))


def sphere_query(q):
    """(pass, theta, phi, exposure) of a sphere's query string (a mapping)."""
    unknown = [k for k in q.keys() if k not in ("pass", "theta", "phi", "exposure", "token")]
    if unknown:
        raise EntryError(f"unknown query parameter {shown(unknown[0])} (it takes pass, "
                         f"theta, phi, exposure)")
    raw = q.get("pass", "0")
    if not (raw.isascii() and raw.isdigit() and len(raw) <= 4):
        raise EntryError(f"pass must be an integer in [0, 9999] (got {shown(raw)})")
    return (int(raw), _query_number(q, "theta", 45.0, 0, 180),
            _query_number(q, "phi", 135.0, -360, 360),
            _query_number(q, "exposure", 0.0, -10, 10))
