"""A model's docstring read as the plugin reference reads it: its title, its parameter
table (an RST simple table: name, type, description ending in "(Default: ...)", the range
written "in [lo, hi]" or ">= lo") as ``Parameter`` records, and the rest of its lines.
``manual`` turns them into pages; ``check`` and the tests read the parameters and ranges.
"""
import inspect
import math
import os
import re
import sys

from .core.registry import models as plugin_models

__all__ = ["ROOT", "BORDER", "Parameter", "model_doc", "blocks", "indent", "parse_table",
           "split_doc", "parameters", "summary"]

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BORDER = re.compile(r"^\s*=+( +=+)+\s*$")  # a simple-table border: "=====  ===="
_DEFAULT = re.compile(r"\(Default:\s*")
_RANGE = re.compile(r"\bin ([\[(][^\[\](),]+,[^\[\]()]+[\])])|((?<![-=>])>=?\s*[-+\w.]*\w)")


def model_doc(plugin):
    """(the cleaned docstring of ``plugin``'s model module, its file relative to ROOT)."""
    cls = plugin_models()[plugin]
    module = sys.modules[cls.__module__]
    return inspect.cleandoc(module.__doc__ or ""), os.path.relpath(module.__file__, ROOT)


def blocks(lines):
    """Runs of non-blank lines."""
    out, cur = [], []
    for line in lines + [""]:
        if line.strip():
            cur.append(line)
        elif cur:
            out.append(cur)
            cur = []
    return out


def indent(block):
    """The smallest indentation of a block's lines."""
    return min(len(ln) - len(ln.lstrip()) for ln in block)


def parse_table(lines):
    """An RST simple table (its lines, borders included) -> (header cells, rows of cells).

    Columns start where the first border's runs of ``=`` start; a line whose first cell is
    blank continues the row above; the last column may run past its border.
    """
    starts = [m.start() for m in re.finditer("=+", lines[0])]
    groups, rows = [], []
    for line in lines[1:]:
        if BORDER.match(line):
            groups.append(rows)
            rows = []
        elif line.strip():
            cells = [line[a:b].strip() for a, b in zip(starts, starts[1:] + [None])]
            if rows and not cells[0]:
                rows[-1] = [f"{x} {y}".strip() for x, y in zip(rows[-1], cells)]
            else:
                rows.append(cells)
    if rows:  # no closing border
        groups.append(rows)
    header = [" ".join(c).strip() for c in zip(*groups[0])] if len(groups) > 1 else []
    return header, (groups[-1] if groups else [])


def split_doc(doc):
    """(title paragraph, parameter-table lines, other lines) of a cleaned docstring.

    The parameter table is the first table after a "Parameters" heading (or the first table
    if there is no such heading); the heading goes with it.
    """
    lines = doc.splitlines() + [""]
    cut = lines.index("")
    title, rest = " ".join(ln.strip() for ln in lines[:cut]), lines[cut:]
    heading = next((i for i, ln in enumerate(rest) if ln.strip() == "Parameters"), 0)
    start = next((i for i, ln in enumerate(rest) if i >= heading and BORDER.match(ln)), None)
    if start is None:
        return title, [], rest
    end = next(i for i in range(start, len(rest)) if not rest[i].strip())
    return title, rest[start:end], rest[:heading or start] + rest[end:]


def _cut_default(text):
    """(text without its "(Default: ...)", the default) — parentheses inside are balanced."""
    m = _DEFAULT.search(text)
    if not m:
        return text, ""
    depth, i = 1, m.end()
    while i < len(text) and depth:
        depth += {"(": 1, ")": -1}.get(text[i], 0)
        i += 1
    return (text[:m.start()] + text[i:]).strip(), text[m.end():i - 1].strip()


def _bound(text):
    """"1e-4", "pi/2", "2 pi", "inf" -> float."""
    t = text.replace(" ", "").replace("*", "")
    m = re.fullmatch(r"([-+]?[\d.]+(?:e[-+]?\d+)?)?(pi|inf)?(?:/([\d.]+))?", t)
    if not m or not (m.group(1) or m.group(2)):
        raise ValueError(f"not a number: {text!r}")
    unit = {"pi": math.pi, "inf": math.inf, None: 1.0}[m.group(2)]
    return float(m.group(1) or 1) * unit / float(m.group(3) or 1)


class Parameter:
    """One row of a docstring's parameter table."""

    def __init__(self, name, type, description, default, range):
        self.name, self.type, self.description = name, type, description
        self.default, self.range = default, range

    def __repr__(self):
        return (f"Parameter({self.name!r}, {self.type!r}, default={self.default!r}, "
                f"range={self.range!r})")

    def bounds(self):
        """(lo, hi, lo included, hi included) of the range (None if it has none).

        "[0, 1]", "(0, pi/2]", ">= 0", "> 0"; pi and inf are understood.
        """
        m = re.match(r"([\[(])(.+),(.+)([\])])$|(>=?)\s*(.+)$", self.range)
        if not m:
            return None
        if m.group(1):
            lo, hi, closed = m.group(2), m.group(3), (m.group(1) == "[", m.group(4) == "]")
        else:
            lo, hi, closed = m.group(6), "inf", (m.group(5) == ">=", False)
        try:
            return _bound(lo), _bound(hi), *closed
        except ValueError:  # a range in words: shown as written, not checked
            return None

    def contains(self, value):
        """True if ``value`` (text) is a number in the range, or cannot be compared."""
        try:
            lo, hi, lo_in, hi_in = self.bounds()
            v = float(value)
            return (lo < v or lo_in and lo == v) and (v < hi or hi_in and v == hi)
        except (TypeError, ValueError):  # no bounds, or not a number
            return True

    def choices(self):
        """The string values a ``string`` parameter names in its description (``x``)."""
        words = re.findall(r"``([A-Za-z_][\w]*)``", self.description)
        return list(dict.fromkeys(words)) if self.type == "string" else []


def parameters(plugin):
    """The parameter table of ``plugin``'s docstring, as a list of ``Parameter``."""
    table = split_doc(model_doc(plugin)[0])[1]
    out = []
    for row in (parse_table(table)[1] if table else []):
        row = (row + ["", "", ""])[:3]
        description, default = _cut_default(row[2])
        m = _RANGE.search(description)
        rng = (m.group(1) or m.group(2)) if m else ""
        for name in re.findall(r"[A-Za-z_]\w*", row[0]):  # "``nu``, ``nv``": two of them
            out.append(Parameter(name, row[1].replace("/", " or "), description, default, rng))
    return out


def summary(plugin):
    """(title, one line): "Ward anisotropic BRDF (`ward`)", "Ward anisotropic BRDF."."""
    first = split_doc(model_doc(plugin)[0])[0]
    m = re.match(r"(.*?)\s*\(``" + re.escape(plugin) + r"``\)(.*)$", first)
    if not m:
        return f"{first.rstrip('.')} (`{plugin}`)", first
    return f"{m.group(1)} (`{plugin}`)", (m.group(1) + m.group(2)).rstrip(".") + "."
