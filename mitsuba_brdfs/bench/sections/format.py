"""What every section of the study's document writes with: numbers, times, tables, plots."""
import math

__all__ = ["Document", "num", "sec", "ratio", "f", "table", "plt", "ratio_bars", "save",
           "ratio_items"]


class Document:
    """What a section's text needs to know of the document it goes into.

    ``perf``: the folder of the plots, relative to the document; ``plots``: the file names
    of the plots written for this document; ``number(key)``: a section's number.
    """

    def __init__(self, numbers, plots=(), perf="perf"):
        """Section numbers, plots written and the plot folder."""
        self._numbers, self.plots, self.perf = dict(numbers), set(plots), perf

    def number(self, key):
        """The number of the section ``key`` in the document."""
        return self._numbers[key]

    def image(self, name, alt):
        """The Markdown lines of plot ``name`` (none when it was not written)."""
        return [f"![{alt}]({self.perf}/{name})", ""] if name in self.plots else []


def num(x, digits=3):
    """A number in a few significant digits (scientific notation when tiny or huge)."""
    if x is None:
        return "-"
    if isinstance(x, str):
        return x
    x = float(x)
    if not math.isfinite(x):
        return "inf" if x > 0 else ("-inf" if x < 0 else "-")
    if x == 0:
        return "0"
    if abs(x) < 1e-3 or abs(x) >= 1e5:
        return f"{x:.{max(digits - 1, 1)}e}"
    return f"{x:.{digits}g}"


def sec(x):
    """Seconds in the unit that reads best (us, ms, s, min)."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    if x < 1e-3:
        return f"{x * 1e6:.0f} us"
    if x < 1:
        return f"{x * 1e3:.1f} ms"
    if x < 120:
        return f"{x:.2f} s"
    return f"{x / 60:.1f} min"


def ratio(s, key="ratio"):
    """A compared pair's median ratio and its range."""
    return f"{s[key]:.3f} ({s['ratio_min']:.2f}-{s['ratio_max']:.2f})"


def f(x):
    """Float from a results value (JSON writes inf/nan as strings)."""
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def table(header, rows):
    """A Markdown table."""
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return out


def plt():
    """matplotlib's pyplot, drawing into files."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as pyplot
    return pyplot


def save(fig, path):
    """Write the figure and free it."""
    fig.tight_layout()
    from ...output import save_figure
    save_figure(fig, path, dpi=90)
    plt().close(fig)
    return True


def ratio_items(pairs):
    """(label, median, min, max) of each compared pair, for ``ratio_bars``."""
    return [(k, v["ratio"], v["ratio_min"], v["ratio_max"]) for k, v in pairs.items()]


def ratio_bars(items, path, title, xlabel, lines=(1.0,)):
    """Horizontal bars: (label, median, min, max); False when there is nothing to draw."""
    if not items:
        return False
    fig, ax = plt().subplots(figsize=(7.5, 0.38 * len(items) + 1.2))
    y = range(len(items))
    med = [i[1] for i in items]
    lo = [i[1] - i[2] for i in items]
    hi = [i[3] - i[1] for i in items]
    ax.barh(list(y), med, xerr=[lo, hi], color="#6a8caf", capsize=3)
    ax.set_yticks(list(y))
    ax.set_yticklabels([i[0] for i in items], fontsize=8)
    ax.invert_yaxis()
    for x in lines:
        ax.axvline(x, color="k", lw=0.8, ls="--" if x != 1.0 else "-")
    ax.set_xlabel(xlabel)
    ax.set_title(title, fontsize=9)
    return save(fig, path)
