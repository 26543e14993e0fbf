"""Argument types shared by the commands.

Each type refuses a bad value with one line that names it, which the command line prints
with exit status 2 before anything runs. ``UsageError`` is the same for checks that need
more than one argument (an output path against the scene, a variant against the build).
"""
import argparse
import math
import os

__all__ = ["UINT32_MAX", "OUT_ROOT", "default_out", "UsageError", "int_range", "positive_int",
           "nonnegative_int", "uint32", "finite_float", "define", "refuse_repeated", "add_load",
           "number"]

#: Mitsuba's sample counts and seeds are 32-bit unsigned integers
UINT32_MAX = 2 ** 32 - 1

#: where the commands that write several files (figures, properties, fit, bench, manual)
#: write when no ``--out`` is given: one folder of the current directory, named after the
#: package so that it is recognised and deleted at once, with a sub-folder per command.
#: The repository ignores it (.gitignore): run in a checkout, no command overwrites the
#: tracked docs/ or renders/ (``make docs`` regenerates those, with explicit --out).
OUT_ROOT = "mitsuba_brdfs-out"


def default_out(command):
    """The default output folder of ``command``: ``mitsuba_brdfs-out/<command>``."""
    return os.path.join(OUT_ROOT, command)


class UsageError(ValueError):
    """A bad invocation: the command line prints its message in one line, exit status 2."""


def int_range(low, high=None):
    """An argparse type: an integer in [low, high] (no upper bound when ``high`` is None)."""
    def parse(text):
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if value < low or (high is not None and value > high):
            bound = f">= {low}" if high is None else f"in {low}..{high}"
            raise argparse.ArgumentTypeError(f"must be {bound}, got {value}")
        return value
    parse.__name__ = "integer"  # argparse names the type in its messages
    return parse


positive_int = int_range(1)
nonnegative_int = int_range(0)
uint32 = int_range(0, UINT32_MAX)


def finite_float(text):
    """An argparse type: a finite real number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {text!r}")
    return value


def define(text):
    """An argparse type: ``key=value`` (Mitsuba's ``-D``) as a (key, value) pair."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise argparse.ArgumentTypeError(f"expected key=value, got {text!r}")
    return key.strip(), value.strip()


def refuse_repeated(pairs, option):
    """(key, value) pairs of a repeatable ``option`` (``-p``, ``-D``) as a dict; a key given
    twice is a ``UsageError`` naming both values, rather than the last one kept silently."""
    out = {}
    for key, value in pairs:
        if key in out:
            same = " (the same value twice)" if out[key] == value else ""
            raise UsageError(f"{option} {key} given twice ({option} {key}={out[key]}, "
                             f"{option} {key}={value}){same}: give it once")
        out[key] = value
    return out


def add_load(p):
    """The ``--load FILE.py`` option of the commands that take a user's plugins
    (``variant.run_file`` runs each file)."""
    p.add_argument("--load", action="append", default=[], metavar="FILE.py",
                   help="run this Python file once the variant is set, e.g. to register a "
                        "plugin with mi.register_bsdf (repeatable)")


def number(x):
    """``x`` as a float when it is a number: an int or a float, or text written with digits
    ("0.5", "1e-3"; "nan" and "inf" stay words), else None."""
    if isinstance(x, bool):
        return None
    if isinstance(x, (int, float)):
        return float(x)
    try:
        value = float(x)
    except (TypeError, ValueError, OverflowError):
        return None
    return value if any(c.isdigit() for c in str(x)) else None
