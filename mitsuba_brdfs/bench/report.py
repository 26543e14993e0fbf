"""Writing the performance study: ``docs/performance.md`` and its plots in ``docs/perf/``.

Every number in the document is read from the results of one run (``bench.study.measure``);
the conclusions printed with them are computed from those numbers (ratios against fixed
thresholds), so a new run rewrites them consistently. The document is the header, the
summary and each section of ``bench.sections.SECTIONS`` in its order: the table gives each
section's number, heading, text, summary lines and plots.
"""
import math
import os

from .sections import SECTIONS, numbers
from .sections.cpp import TARGET_RATIO
from .sections.format import Document, sec

from ..output import write_text

__all__ = ["write", "console_summary", "TARGET_RATIO"]


def _run_lines(run, what):
    """Commit, machine and load of one run."""
    g, m = run["git"], run["machine"]
    dirty = (f" **with uncommitted changes in: {', '.join(g['dirty'])}**" if g.get("dirty") else "")
    loads = run.get("load_average_end") or [math.nan] * 3
    return [f"{what} from commit `{g.get('commit') or 'unknown'}` ({g.get('date') or 'no date'})"
            f"{dirty}, in {sec(run.get('total_seconds', math.nan))}. "
            f"Machine: {m['cpu']}, {m['cores']} cores, Dr.Jit on {m['drjit_threads']} threads; "
            f"Mitsuba {m['mitsuba']}, Dr.Jit {m['drjit']}, LLVM {m['llvm']}, Python {m['python']}, "
            f"variant `{m['variant']}`. Load average (1, 5, 15 min) at the start "
            f"{', '.join(f'{x:.2f}' for x in run['load_average_start'])}, at the end "
            f"{', '.join(f'{x:.2f}' for x in loads)}.", ""]


def _header(res):
    """The document's title, where and how it was measured, what was skipped."""
    lines = ["# Performance: what accuracy costs in time", ""]
    quick = " --quick" if res["mode"] != "full" else ""
    if res["mode"] != "full":
        lines += ["> **This is a `--quick` run** (small images, few runs): it checks that the study "
                  "works, and its numbers are not the study's. Run `python -m mitsuba_brdfs bench` "
                  "on a quiet machine for the real ones.", ""]
    runs = res.get("runs")
    if runs:
        lines += [f"Written by `python -m mitsuba_brdfs bench{quick}` in {len(runs)} runs: each "
                  "section names the run it comes from; numbers are compared within a run only.",
                  ""]
        for i, run in enumerate(runs, 1):
            secs = sorted({numbers().get(x, 0) for x in run["sections"]})
            lines += _run_lines(run, f"Run {i} (section{'s' if len(secs) > 1 else ''} "
                                     f"{', '.join(map(str, secs))})")
    else:
        lines += _run_lines(res, f"Written by `python -m mitsuba_brdfs bench{quick}`")
    lines += [
        "How everything is measured: the numbers of a section come from one run. Each timed "
        "configuration is rendered once first (the warm-up: it compiles the kernels, or loads "
        "them from Dr.Jit's disk cache; those seconds are reported apart as *compile*), then "
        "several times; times are medians. Configurations that are compared are timed "
        "alternately (A B B A ...), so both see the same machine load, and each comparison is "
        "the median of the per-pair ratios with its range. Conclusions rest on those ratios: "
        "absolute seconds depend on the machine and its load. *instr.* is the number of "
        "instructions in the LLVM IR of the rendering kernel (the largest JIT kernel of a "
        "render, from `dr.kernel_history`, with the functions it calls): for the same scene "
        "it measures the work traced per sample. Mitsuba dispatches BSDF calls over every "
        "BSDF alive in the process, so a render traces the methods of all of them: every "
        "timed render here builds its scene afresh, alone, and the warm-up that gives "
        "*compile* and *instr.* sees that scene only.",
        "",
    ]
    redone = _recompiled(res)
    if redone:
        lines += [f"{redone} timed render(s) had to compile a kernel or load it from the disk "
                  "cache (it was not in memory) and were timed again, so that no compile time "
                  "is counted as render time.", ""]
    skipped = []
    if res.get("missing"):
        skipped.append("Plugins not registered when this ran (their rows are skipped): "
                       + ", ".join(f"`{x}`" for x in res["missing"]) + ".")
    for key in res["sections"]:
        for note in res.get(key, {}).get("skipped", []):
            skipped.append(f"{key}: {note}")
    if skipped:
        lines += ["Skipped:", ""] + [f"- {s}" for s in skipped] + [""]
    return lines


def _recompiled(res):
    """Timed renders that were repeated because a kernel was compiled during them."""
    return sum(s.recompiled(res[s.key]) for s in SECTIONS if res.get(s.key))


def _summary(res, doc):
    """Conclusions computed from the ratios: each section's bullets, then its tables."""
    bullets, after = [], []
    for s in SECTIONS:
        if s.summary is not None and res.get(s.key):
            for line in s.summary(res[s.key], doc):
                (bullets if line.startswith("- ") else after).append(line)
    return ["## Summary", ""] + bullets + after + [""]


def _run_note(res, key):
    """In a study written in several runs, the line naming the run of section ``key``."""
    runs = res.get("runs") or []
    i = next((n for n, r in enumerate(runs, 1) if key in r["sections"]), None)
    if i is None:
        return []
    commit = (runs[i - 1]["git"].get("commit") or "unknown")[:10]
    return ["", f"*From run {i} (commit `{commit}`).*"]


def _sections(res, doc):
    """Every measured section: its heading, the run it comes from, its text."""
    lines = []
    for s in SECTIONS:
        if res.get(s.key):
            lines += [s.heading()] + _run_note(res, s.key) + [""] + s.text(res[s.key], doc)
    return lines


def _plots(res, perf):
    """Draw every section's plots into ``perf``; returns the names of those drawn."""
    drawn = set()
    for s in SECTIONS:
        for name, plot in s.plots:
            if s.key in res and plot(res[s.key], os.path.join(perf, name)):
                drawn.add(name)
    return drawn


def write(res, out_dir):
    """Write performance.md into ``out_dir`` and the plots into ``out_dir/perf``."""
    perf = os.path.join(out_dir, "perf")
    os.makedirs(perf, exist_ok=True)
    doc = Document(numbers(), _plots(res, perf))
    lines = _header(res) + _summary(res, doc) + _sections(res, doc)
    lines += ["## Reproduce", "",
              "```sh",
              "python -m mitsuba_brdfs bench            # the full study (on a quiet machine)",
              "python -m mitsuba_brdfs bench --quick    # a reduced run that checks it works",
              "python -m mitsuba_brdfs bench --sections cpp effects   # some parts, "
              "replaced in the study",
              "python -m mitsuba_brdfs bench --variant cuda_ad_rgb --sections cpp energy"
              "   # on a GPU",
              "```", "",
              "Raw numbers (every run's seconds included): [`perf/results.json`](perf/results.json).",
              ""]
    path = os.path.join(out_dir, "performance.md")
    write_text(path, "\n".join(lines))
    return path


def console_summary(res):
    """The summary's lines, for the terminal."""
    return "\n".join(ln for ln in _summary(res, Document(numbers()))[2:] if ln)
