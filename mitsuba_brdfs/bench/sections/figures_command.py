"""Section "the figures command" of the study's document: its total with an empty and a
filled kernel cache (measured by ``bench.startup.run_figures_command``)."""
from .format import sec, table

__all__ = ["steps", "text", "summary"]


def steps(settings):
    """Progress steps of the measurement."""
    return 2 * settings.figcmd_runs


def summary(fc, doc):
    """Summary bullet: the command's time and its share of compiling."""
    if "compile_share" not in fc:
        return []
    what = "`figures`" + (f" --only {' '.join(fc['settings']['only'])}"
                          if fc["settings"]["only"] else "")
    return [f"- {what} (section {doc.number('figures_command')}): {sec(fc['empty']['process'])} "
            f"with an empty kernel cache, of which {sec(fc['empty']['compile'])} compiling "
            f"({100 * fc['compile_share']:.0f}%); {sec(fc['filled']['process'])} with a "
            "filled one."]


def text(fc, doc):
    """The section's text under its heading."""
    c = fc["settings"]
    what = "python -m mitsuba_brdfs figures" + (f" --only {' '.join(c['only'])}" if c["only"] else "")
    out = [f"`{what}` (quality {c['quality']}) in a fresh process, first with `DRJIT_CACHE_DIR` "
           "naming a new empty folder (every kernel is compiled), then again with that folder "
           f"filled (every kernel is loaded from it); {c['runs']} run(s), medians. *kernels*: "
           "distinct kernels (the same kernel launched again is counted once), *launches*: "
           "all kernel launches. *process*: "
           "from start to exit; *figures*: the rendering loop as the command reports it; "
           "*compile*: the code generation and LLVM compile of every kernel (or its load from "
           "the cache), from Dr.Jit's kernel history, which the command runs with "
           "(`mitsuba_brdfs/bench/child.py`); per figure: the seconds of its `timings.json` "
           "(on a busy machine these move by more than the compile time).", ""]
    if "compile_share" not in fc:
        fails = [x for v in fc["runs"].values() for x in v if x["exit"] != 0 or x.get("status")]
        f = fails[0] if fails else {}
        return out + [f"The command failed: exit {f.get('exit')}: {f.get('error')}", ""]
    e, f = fc["empty"], fc["filled"]
    rows = [["**process**", f"**{sec(e['process'])}**", f"**{sec(f['process'])}**"],
            ["compile", f"{sec(e['compile'])} ({100 * fc['compile_share']:.0f}%)",
             sec(f["compile"])],
            ["kernels / loaded from disk / launches",
             f"{e['kernels']:.0f} / {e['disk_hits']:.0f} / {e.get('launches', 0):.0f}",
             f"{f['kernels']:.0f} / {f['disk_hits']:.0f} / {f.get('launches', 0):.0f}"]]
    if e.get("loop") and f.get("loop"):
        rows.append(["figures", sec(e["loop"]), sec(f["loop"])])
    rows += [[f"`{name}`", sec(v), sec(f["figures"].get(name))]
             for name, v in e["figures"].items()]
    out += table(["", "empty cache", "filled cache"], rows) + [""]
    return out
