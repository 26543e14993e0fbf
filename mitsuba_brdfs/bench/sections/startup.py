"""Section "time to the first image" of the study's document: a fresh process with an
empty and a filled kernel cache, split into import, load, trace, compile and render
(measured by ``bench.startup.run``)."""
from .format import plt, ratio, save, sec, table

__all__ = ["steps", "text", "summary", "plot"]


def steps(settings):
    """Progress steps of the measurement."""
    return 2 * settings.startup_runs * len(settings.startup_pairs)


def summary(st, doc):
    """Summary bullet: the first image with each plugin and cache."""
    parts = []
    for v in st.get("pairs", {}).values():
        for state in ("empty", "filled"):
            e = v[state]
            parts.append(f"`{v['plugin']}` {sec(e['python']['first_image'])} against "
                         f"`{v['cpp_plugin']}` {sec(e['cpp']['first_image'])} with {state} "
                         f"cache (ratio {e['first_image_ratio']['ratio']:.2f})")
    if not parts:
        return []
    return [f"- Time to the first image in a fresh process (section {doc.number('startup')}): "
            + "; ".join(parts) + "."]


def text(st, doc):
    """The section's text under its heading."""
    c = st["settings"]
    out = [f"A fresh Python process renders the sphere of `scenes/as_sphere.xml` "
           f"({c['res']} x {c['res']}, {c['spp']} spp, `{c['integrator']}`) with a Python plugin, "
           f"or with its C++ neighbour (section {doc.number('cpp')}), and times each step "
           "(`mitsuba_brdfs/bench/child.py`): *import* Mitsuba and set the variant, "
           "*package* `import mitsuba_brdfs` (Python plugins only), *load* the scene file, then "
           "the first `mi.render` until its image is evaluated, split with `dr.kernel_history` "
           "into *compile* (Dr.Jit's code generation and LLVM, or loading the kernel from the "
           "cache), *execute* (the kernels running) and *trace* (the rest: Python and C++ "
           "building the kernels, where a Python BSDF's methods run; the first render runs with "
           "`LaunchBlocking`, so that the three do not overlap). *first image* is their "
           "sum; *process* is the child's wall time from start to exit (interpreter start-up "
           "and shutdown included); *again* a second render in the same process. *Empty*: "
           "`DRJIT_CACHE_DIR` names a new empty folder, every kernel is compiled; *filled*: the "
           "same folder in the next process, every kernel is loaded from it (*disk*: kernels "
           f"found there). Medians of {c['runs']} runs, the two plugins alternately; the ratio "
           "is Python / C++ of the first-image time (median of the per-run ratios, range).", ""]
    out += doc.image("startup.png", "time to the first image")
    rows = []
    for key, v in st["pairs"].items():
        for state in ("empty", "filled"):
            e = v[state]
            for side, name in (("python", v["plugin"]), ("cpp", v["cpp_plugin"])):
                m = e[side]
                first = e["first_image_ratio"]
                rows.append([f"`{name}`", state, sec(m["import_mitsuba"]),
                             sec(m["import_package"]) if side == "python" else "-",
                             sec(m["load"]), sec(m["trace"]), sec(m["compile"]),
                             sec(m["execute"]), f"**{sec(m['first_image'])}**",
                             sec(m["process"]), sec(m["second_render"]),
                             f"{m['kernels']:.0f} / {m['disk_hits']:.0f}",
                             ratio(first) if side == "python" and first else ""])
    out += table(["plugin", "cache", "import", "package", "load", "trace", "compile",
                  "execute", "first image", "process", "again", "kernels / disk",
                  "Python / C++"], rows) + [""]
    py = [v[state]["python"] for v in st["pairs"].values() for state in ("empty", "filled")]
    mib = [m["package_mib"] for m in py if m.get("package_mib") is not None]
    if mib:
        out += [f"`import mitsuba_brdfs` after `import mitsuba` takes "
                f"{sec(min(m['import_package'] for m in py))}-"
                f"{sec(max(m['import_package'] for m in py))} and adds "
                f"{min(mib):.1f}-{max(mib):.1f} MiB of resident memory (the rows above).", ""]
    return out


def plot(st, path):
    """Stacked bars: the phases of the first image per plugin and cache."""
    bars = []
    for v in st.get("pairs", {}).values():
        for state in ("empty", "filled"):
            for side, name in (("python", v["plugin"]), ("cpp", v["cpp_plugin"])):
                bars.append((f"{name}, {state}", v[state][side]))
    if not bars:
        return False
    phases = [("import_mitsuba", "import"), ("import_package", "package"), ("load", "load"),
              ("trace", "trace"), ("compile", "compile"), ("execute", "execute")]
    fig, ax = plt().subplots(figsize=(7.5, 0.4 * len(bars) + 1.4))
    left = [0.0] * len(bars)
    for key, label in phases:
        widths = [b[1][key] for b in bars]
        ax.barh(range(len(bars)), widths, left=left, label=label)
        left = [a + w for a, w in zip(left, widths)]
    ax.set_yticks(range(len(bars)))
    ax.set_yticklabels([b[0] for b in bars], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("seconds (medians)")
    ax.set_title("time to the first image in a fresh process", fontsize=9)
    ax.legend(fontsize=7, ncol=3)
    return save(fig, path)
