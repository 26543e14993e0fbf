"""Writing the performance study: ``docs/performance.md`` and its plots in ``docs/perf/``.

Every number in the document is read from the results of one run (``bench.study.measure``);
the conclusions printed with them are computed from those numbers (ratios against fixed
thresholds), so a new run rewrites them consistently.
"""
import math
import os
import statistics

from ..output import save_figure, write_text

__all__ = ["write", "console_summary", "TARGET_RATIO"]

#: a Python plugin should render within this factor of its C++ neighbour
TARGET_RATIO = 1.1

#: why a pair of section 2 differs, where the difference is understood; printed under the
#: table for the pairs that are slower than TARGET_RATIO in the run
EXPLANATIONS = {
    "oren_nayar": "Mitsuba has no Oren-Nayar plugin: `oren_nayar` evaluates the A and B terms "
                  "and the max(0, cos(phi_i - phi_o)) sin(alpha) tan(beta) factor (or a table "
                  "lookup) on top of what `diffuse` does, so a ratio above 1 is the model's "
                  "price, not overhead.",
    "toon": "Mitsuba has no toon shader: `toon` evaluates its bands, smooth steps and a "
            "specular band on top of a cosine-sampled diffuse lobe, more than `diffuse` does.",
}


# -- formatting ------------------------------------------------------------------------------

def _num(x, digits=3):
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


def _sec(x):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    if x < 1e-3:
        return f"{x * 1e6:.0f} us"
    if x < 1:
        return f"{x * 1e3:.1f} ms"
    if x < 120:
        return f"{x:.2f} s"
    return f"{x / 60:.1f} min"


def _ratio(s, key="ratio"):
    return f"{s[key]:.3f} ({s['ratio_min']:.2f}-{s['ratio_max']:.2f})"


def _f(x):
    """Float from a results value (JSON writes inf/nan as strings)."""
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def _table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return out


# -- plots ---------------------------------------------------------------------------------

def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def plot_error_vs_time(err, path):
    from matplotlib.ticker import NullFormatter
    plt = _plt()
    scenes = err.get("scenes", {})
    if not scenes:
        return False
    cols = 3
    rows = (len(scenes) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.6 * rows), squeeze=False)
    target = err["settings"]["target"]
    for ax, (key, sc) in zip(axes.flat, scenes.items()):
        for name, s in sc["strategies"].items():
            pts = [(t, e) for t, e in zip(s["seconds"], s["rel_rmse"]) if _f(e) > 0]
            if pts:
                t, e = zip(*pts)
                ax.loglog(t, e, marker="o", ms=3, label=name,
                          ls="-" if "MIS" in name else "--")
        ax.axhline(target, color="k", lw=0.7, ls=":")
        ax.xaxis.set_minor_formatter(NullFormatter())  # minor labels overlap on short ranges
        ax.set_title(sc["title"], fontsize=8)
        ax.set_xlabel("render seconds (median)")
        ax.set_ylabel("relative RMSE")
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
    axes.flat[0].legend(fontsize=7)
    for ax in list(axes.flat)[len(scenes):]:
        ax.axis("off")
    fig.tight_layout()
    save_figure(fig, path, dpi=90)
    plt.close(fig)
    return True


def _ratio_bars(items, path, title, xlabel, lines=(1.0,)):
    """Horizontal bars: (label, median, min, max)."""
    plt = _plt()
    if not items:
        return False
    fig, ax = plt.subplots(figsize=(7.5, 0.38 * len(items) + 1.2))
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
    fig.tight_layout()
    save_figure(fig, path, dpi=90)
    plt.close(fig)
    return True


def plot_stable_vs_naive(acc, path):
    plt = _plt()
    forms = acc.get("stable_vs_naive", {}).get("forms", {})
    if not forms:
        return False
    fig, axes = plt.subplots(1, len(forms), figsize=(4.3 * len(forms), 3.3), squeeze=False)
    for ax, (name, row) in zip(axes.flat, forms.items()):
        ex = [float(e) for e in row["error"]]
        for kind, color in (("stable", "#2b6cb0"), ("naive", "#c05621")):
            med = [max(_f(row["error"][k][kind]["median"]), 1e-9) for k in row["error"]]
            mx = [max(_f(row["error"][k][kind]["max"]), 1e-9) for k in row["error"]]
            ax.loglog(ex, med, marker="o", color=color, label=f"{kind}: median")
            ax.loglog(ex, mx, marker="x", ls="--", color=color, alpha=0.7, label=f"{kind}: max")
        ax.set_title(name, fontsize=8)
        ax.set_xlabel("exponent")
        ax.set_ylabel("relative error vs float64")
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
    axes.flat[0].legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, path, dpi=90)
    plt.close(fig)
    return True


def plot_memory(mem, path):
    plt = _plt()
    rs = mem.get("renders", [])
    if not rs:
        return False
    fig, ax = plt.subplots(figsize=(6, 3.2))
    labels = [f"{r['spp']} spp\n{r['passes']} pass{'es' if r['passes'] > 1 else ''}" for r in rs]
    ax.bar(range(len(rs)), [r["peak_rss_mib"] for r in rs],
           color=["#6a8caf" if r["passes"] > 1 else "#c9734f" for r in rs])
    ax.set_xticks(range(len(rs)))
    ax.set_xticklabels(labels, fontsize=8)
    ax.set_ylabel("peak resident memory (MiB)")
    ax.set_title(f"{mem['res']} x {mem['res']} render through the CLI", fontsize=9)
    fig.tight_layout()
    save_figure(fig, path, dpi=90)
    plt.close(fig)
    return True


# -- the document ------------------------------------------------------------------------------

#: section key -> its number in the document
SECTION_NUMBERS = {"error": 1, "cpp": 2, "accuracy": 3, "effects": 4, "figures": 4, "memory": 5,
                   "startup": 6, "optimisation": 7, "figures_command": 8}


def _run_lines(run, what):
    """Commit, machine and load of one run."""
    g, m = run["git"], run["machine"]
    dirty = (f" **with uncommitted changes in: {', '.join(g['dirty'])}**" if g.get("dirty") else "")
    loads = run.get("load_average_end") or [math.nan] * 3
    return [f"{what} from commit `{g.get('commit') or 'unknown'}` ({g.get('date') or 'no date'})"
            f"{dirty}, in {_sec(run.get('total_seconds', math.nan))}. "
            f"Machine: {m['cpu']}, {m['cores']} cores, Dr.Jit on {m['drjit_threads']} threads; "
            f"Mitsuba {m['mitsuba']}, Dr.Jit {m['drjit']}, LLVM {m['llvm']}, Python {m['python']}, "
            f"variant `{m['variant']}`. Load average (1, 5, 15 min) at the start "
            f"{', '.join(f'{x:.2f}' for x in run['load_average_start'])}, at the end "
            f"{', '.join(f'{x:.2f}' for x in loads)}.", ""]


def _header(res):
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
            secs = sorted({SECTION_NUMBERS.get(x, 0) for x in run["sections"]})
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
    for sec in res["sections"]:
        for note in res.get(sec, {}).get("skipped", []):
            skipped.append(f"{sec}: {note}")
    if skipped:
        lines += ["Skipped:", ""] + [f"- {s}" for s in skipped] + [""]
    return lines


def _recompiled(res):
    """Timed renders that were repeated because a kernel was compiled during them."""
    n = 0
    for sec in ("cpp", "effects"):
        n += sum(v.get("recompiled", 0) for v in res.get(sec, {}).get("pairs", {}).values())
    n += sum(v.get("recompiled", 0) for v in res.get("figures", {}).get("scenes", {}).values())
    for sc in res.get("error", {}).get("scenes", {}).values():
        n += sum(s.get("recompiled", 0) for s in sc["strategies"].values())
    acc = res.get("accuracy", {})
    for group in ("render_naive", "oren_nayar_lut"):
        n += sum(v.get("recompiled", 0) for v in acc.get(group, {}).values())
    n += sum(g["render"].get("recompiled", 0)
             for g in acc.get("ggx_visible", {}).get("roughness", {}).values())
    return n


def _summary(res):
    """Conclusions computed from the ratios."""
    out = ["## Summary", ""]
    cpp = res.get("cpp", {}).get("pairs", {})
    if cpp:
        slow = {k: v for k, v in cpp.items() if v["ratio"] > TARGET_RATIO}
        out.append(f"- Against Mitsuba's C++ plugins: {len(cpp) - len(slow)} of {len(cpp)} "
                   f"Python configurations render within {TARGET_RATIO}x of their neighbour"
                   + (": all of them." if not slow else "; slower: "
                      + ", ".join(f"`{k}` {v['ratio']:.2f}x" for k, v in slow.items())
                      + " (see section 2)."))
    err = res.get("error", {})
    alone = err.get("bsdf_alone", {}).get("incidences", {})
    if alone:
        r = alone.get("45") or alone.get(45) or next(iter(alone.values()))
        out.append(f"- Importance sampling: at nu = nv = 1000, AS half-vector sampling of the BSDF "
                   f"alone is {_num(_f(r['efficiency_ratio']))} times as efficient "
                   f"(1 / (variance x time)) as cosine sampling at 45 degrees incidence.")
    scenes = err.get("scenes", {})
    tail = []
    if scenes:
        names = list(next(iter(scenes.values()))["strategies"])
        out.append(f"- Time each sampling strategy needs to reach a relative RMSE of "
                   f"{err['settings']['target']:g}: the table below (* extrapolated; section 1).")
        rows = []
        for sc in scenes.values():
            st = sc["strategies"]
            rows.append([sc["title"]] + [_sec(_f(st[n]["time_to_target"])) + (" *" if st[n]["extrapolated"] else "")
                                         for n in names])
        tail = [""] + _table(["scene"] + names, rows)
    calls = [(v["call_a"], v["call_b"]) for v in cpp.values() if "call_a" in v]
    if calls:
        out.append("- Fixed cost of a render call (16 x 16 pixels, 1 spp; section 2): median "
                   f"{_sec(statistics.median(a for a, _ in calls))} with the Python plugins, "
                   f"{_sec(statistics.median(b for _, b in calls))} with their C++ neighbours "
                   f"(median difference {_sec(statistics.median(a - b for a, b in calls))}).")
    acc = res.get("accuracy", {})
    rn = acc.get("render_naive", {})
    forms = acc.get("stable_vs_naive", {}).get("forms", {})
    if rn or forms:
        parts = [f"render time naive / stable {v['ratio']:.2f} at nu = nv = {n}" for n, v in rn.items()]
        for name, row in forms.items():
            top = list(row["error"])[-1]
            er = row["error"][top]
            parts.append(f"{name.split(',')[0]} at {top}: max error {_num(_f(er['stable']['max']), 2)} "
                         f"stable, {_num(_f(er['naive']['max']), 2)} naive "
                         f"({_num(er['naive']['nonfinite'], 2)} non-finite), time naive / stable "
                         f"{row['ratio_naive_stable']:.2f}")
        out.append("- Stable formulas against the printed ones (section 3): " + "; ".join(parts) + ".")
    eff = res.get("effects", {}).get("pairs", {})
    wrong = [k for k, v in eff.items() if _lobe_verdict(k, v).startswith("**")]
    if eff:
        out.append("- Lobes that are not present cost nothing: "
                   + ("true for every model measured." if not wrong else
                      "**not true for " + ", ".join(f"`{k}`" for k in wrong) + "** (section 4)."))
    mem = res.get("memory", {}).get("renders", [])
    if mem:
        ps = res["memory"]["pass_samples"]
        split = [r for r in mem if r["pass_samples"] == ps]
        whole = [r for r in mem if r["pass_samples"] != ps]
        out.append(f"- Peak memory of {res['memory']['res']} x {res['memory']['res']} CLI renders "
                   "in passes: " + ", ".join(f"{r['spp']} spp {r['peak_rss_mib']:.0f} MiB" for r in split)
                   + (" (max / min " + f"{max(r['peak_rss_mib'] for r in split) / min(r['peak_rss_mib'] for r in split):.2f}); "
                      if split else "; ")
                   + ("in one pass: " + ", ".join(f"{r['spp']} spp {r['peak_rss_mib']:.0f} MiB" for r in whole)
                      if whole else "") + ".")
    st = res.get("startup", {}).get("pairs", {})
    if st:
        parts = []
        for v in st.values():
            for state in ("empty", "filled"):
                e = v[state]
                parts.append(f"`{v['plugin']}` {_sec(e['python']['first_image'])} against "
                             f"`{v['cpp_plugin']}` {_sec(e['cpp']['first_image'])} with {state} "
                             f"cache (ratio {e['first_image_ratio']['ratio']:.2f})")
        out.append("- Time to the first image in a fresh process (section 6): " + "; ".join(parts)
                   + ".")
    op = res.get("optimisation", {})
    if op.get("pairs"):
        parts = [f"`{v['plugin']}` {_sec(v['python_plain']['seconds'])} traced, "
                 f"{_sec(v['python_frozen']['seconds'])} frozen (`{v['cpp_plugin']}` "
                 f"{_sec(v['cpp_plain']['seconds'])}, {_sec(v['cpp_frozen']['seconds'])})"
                 for v in op["pairs"].values()]
        fit = [f for f in _fits(op) if f["default"]]
        out.append("- Seconds per optimisation iteration (section 7): " + "; ".join(parts) + "."
                   + (f" `fit` at its defaults ({fit[0]['res']} x {fit[0]['res']}, "
                      f"{fit[0]['spp']} spp): {_sec(fit[0]['frozen'])} frozen against "
                      f"{_sec(fit[0]['plain'])} traced per iteration "
                      f"(ratio {fit[0]['ratio']:.2f})." if fit else ""))
    fc = res.get("figures_command", {})
    if "compile_share" in fc:
        what = "`figures`" + (f" --only {' '.join(fc['settings']['only'])}"
                              if fc["settings"]["only"] else "")
        out.append(f"- {what} (section 8): {_sec(fc['empty']['process'])} with an empty kernel "
                   f"cache, of which {_sec(fc['empty']['compile'])} compiling "
                   f"({100 * fc['compile_share']:.0f}%); {_sec(fc['filled']['process'])} with a "
                   "filled one.")
    return out + tail + [""]


def _section_error(res, perf_rel):
    err = res.get("error")
    if not err:
        return []
    st = err["settings"]
    out = ["## 1. Error against time", "",
           f"The sphere of `mitsuba_brdfs/scenes/as_sphere.xml` at {st['res']} x {st['res']}, "
           f"spp "
           f"{', '.join(map(str, st['spps']))}, {st['runs']} runs per point (medians of the "
           f"time, mean of the squared error), against a reference of {st['reference_spp']} spp "
           "(the model's importance sampling with MIS, two independent halves; the variance it "
           "still carries is subtracted). RMSE is relative to the reference's mean. Strategies "
           "(Mitsuba's `direct` integrator, which is what the path tracer does at each vertex): "
           "the model's importance sampling or cosine-weighted sampling "
           "(`ashikhmin_shirley`'s `sampling = cosine`; for the other models the study's "
           "`bench_cosine` wrapper, which samples cosine-weighted directions and calls the "
           "model's `eval`), each with emitter sampling and MIS (one emitter and one BSDF "
           "sample per pixel sample) or BSDF sampling alone.", ""]
    if plot_ok(perf_rel, "error_vs_time.png"):
        out += [f"![RMSE against time]({perf_rel}/error_vs_time.png)", ""]
    out += [f"Time to reach a relative RMSE of **{st['target']:g}** (interpolated between "
            "measured points, or extrapolated from the largest spp with RMSE^2 x time = const, "
            "marked *); *slope* is the fitted d log RMSE / d log time (-0.5 for Monte Carlo once "
            "the time grows with spp; steeper where a fixed per-render cost dominates); "
            "*efficiency* is 1 / (relative MSE x seconds) at the largest spp, relative to "
            "importance + MIS; *compile* is the warm-up's JIT time at the first spp.", ""]
    for key, sc in err.get("scenes", {}).items():
        out += [f"**{sc['title']}** (`{sc['plugin']}`; reference noise {sc['reference_rel_std']:.2g} "
                "per pixel, relative)", ""]
        base = _f(sc["strategies"]["importance + MIS"]["efficiency"])
        rows = []
        for name, s in sc["strategies"].items():
            t = _f(s["time_to_target"])
            rows.append([name, _sec(t) + (" *" if s["extrapolated"] else ""),
                         _num(_f(s["slope"]), 2), _num(_f(s["efficiency"]) / base, 3),
                         _num(s["rel_rmse"][-1], 3), _sec(s["seconds"][-1]),
                         _sec(s["compile_s"][0]), s["instructions"][-1]])
        out += _table(["strategy", "time to target", "slope", "efficiency", "RMSE at max spp",
                       "seconds at max spp", "compile", "instr."], rows) + [""]
    alone = err.get("bsdf_alone")
    if alone:
        out += ["**BSDF alone, AS nu = nv = 1000 (metal).** The estimator is the sampled weight "
                "f cos / pdf at a fixed incidence (its mean is the albedo); variance over "
                f"{alone['samples']} samples, seconds per sample of the `sample` call "
                "(interleaved medians), efficiency = 1 / (variance x time).", ""]
        rows = []
        for th, r in alone["incidences"].items():
            hv, cs = r["half_vector"], r["cosine"]
            rows.append([th, _num(hv["albedo"]), _num(cs["albedo"]), _num(hv["variance"]),
                         _num(cs["variance"]), _num(hv["seconds_per_sample"] * 1e9, 3),
                         _num(cs["seconds_per_sample"] * 1e9, 3), _num(_f(r["efficiency_ratio"]))])
        out += _table(["incidence (deg)", "albedo half-vector", "albedo cosine",
                       "variance half-vector", "variance cosine", "ns/sample half-vector",
                       "ns/sample cosine", "efficiency half-vector / cosine"], rows) + [""]
    return out


def _section_cpp(res, perf_rel):
    cpp = res.get("cpp")
    if not cpp:
        return []
    st = cpp["settings"]
    out = ["## 2. Speed against Mitsuba's C++ plugins", "",
           f"The sphere at {st['res']} x {st['res']}, {st['spp']} spp, `{st['integrator']}` "
           f"integrator; {st['runs']} paired runs after a warm-up. Ratio = Python / C++ "
           f"(median of the per-pair ratios, range); target <= {TARGET_RATIO}.", ""]
    items = [(k, v["ratio"], v["ratio_min"], v["ratio_max"]) for k, v in cpp["pairs"].items()]
    if items and plot_ok(perf_rel, "speed_vs_cpp.png"):
        out += [f"![Python / C++ time ratios]({perf_rel}/speed_vs_cpp.png)", ""]
    rows = []
    for k, v in cpp["pairs"].items():
        verdict = "ok" if v["ratio"] <= TARGET_RATIO else "**slower**"
        ba, bb = v["bsdf_instr_a"], v["bsdf_instr_b"]
        rows.append([f"`{k}`", f"`{v['cpp_plugin']}`", _sec(v["median_a"]), _sec(v["median_b"]),
                     _ratio(v), verdict, f"{v['instr_a']} / {v['instr_b']}",
                     f"{ba['sample']} / {bb['sample']}", f"{ba['eval_pdf']} / {bb['eval_pdf']}",
                     f"{_sec(v['compile_a'])} / {_sec(v['compile_b'])}", v["note"]])
    out += _table(["Python configuration", "C++", "Python", "C++ time", "ratio (range)", "",
                   "instr. render Python / C++", "instr. sample", "instr. eval_pdf",
                   "compile Python / C++", "closest neighbour because"], rows) + [""]
    calls = [(v["call_a"], v["call_b"]) for v in cpp["pairs"].values() if "call_a" in v]
    if calls:
        extra = statistics.median([a - b for a, b in calls])
        out += [f"Fixed cost of a render call (16 x 16 pixels, 1 spp, where the kernel has almost "
                f"nothing to do; medians over the pairs): Python plugins "
                f"{_sec(statistics.median(a for a, _ in calls))}, C++ plugins "
                f"{_sec(statistics.median(b for _, b in calls))}, a median difference of "
                f"{_sec(extra)} per call. A Python BSDF is traced by running its Python methods "
                "at every `mi.render` call (the kernel itself comes from the cache); that cost "
                "does not grow with the image, so it weighs on many small renders (an "
                "optimisation loop) and not on one large one.", ""]
    out += ["*instr. sample* and *instr. eval_pdf*: the BSDF's own methods traced alone, outside "
            "a scene (the render kernel also holds the camera, the shapes, the emitters and the "
            "integrator, the same for both).", ""]
    out += ["Parameters of each pair:", ""]
    for k, v in cpp["pairs"].items():
        out.append(f"- `{k}`: `{_compact(v['python'])}` against `{_compact(v['cpp'])}`")
    out.append("")
    slow = [k for k, v in cpp["pairs"].items() if v["ratio"] > TARGET_RATIO]
    if slow:
        out += ["Where a Python plugin is slower:", ""]
        for k in slow:
            v = cpp["pairs"][k]
            ba, bb = v["bsdf_instr_a"], v["bsdf_instr_b"]
            more = [m for m in ("sample", "eval_pdf") if ba[m] > bb[m]]
            traced = (f"its {' and '.join(more)} trace"
                      + "".join(f" {ba[m]} instructions against {bb[m]}" + (";" if m != more[-1] else "")
                                for m in more)
                      if more else "its methods trace no more instructions than the C++ ones, "
                      "so the difference is not in the work per sample")
            why = EXPLANATIONS.get(k) or EXPLANATIONS.get(v["plugin"]) or ""
            out.append(f"- `{k}` ({v['ratio']:.2f}x): {traced}. {why}".rstrip())
        out.append("")
    return out


def _compact(d):
    if isinstance(d, dict):
        if d.get("type") == "rgb":
            return str(d["value"])
        if d.get("type") == "bitmap":
            return "bitmap"
        return "{" + ", ".join(f"{k}: {_compact(v)}" for k, v in d.items()) + "}"
    return repr(d) if isinstance(d, str) else f"{d:g}" if isinstance(d, float) else str(d)


def _section_accuracy(res, perf_rel):
    acc = res.get("accuracy")
    if not acc:
        return []
    out = ["## 3. The price of accuracy choices", ""]
    sv = acc.get("stable_vs_naive")
    if sv:
        out += ["### Stable exponent forms against the formulas as printed", "",
                "Inputs are drawn from each lobe itself (where a renderer evaluates it), "
                f"{sv['error_samples']} per exponent; errors are relative to a float64 "
                "evaluation of the same float32 inputs; *non-finite* is the fraction of NaN/inf "
                f"results. Time: {sv['samples']} evaluations per kernel, stable and naive "
                "interleaved, at exponent 1e4 (an opaque value: one kernel for every exponent). "
                "The naive forms are written in `mitsuba_brdfs/bench/plugins.py` only.", ""]
        if plot_ok(perf_rel, "stable_vs_naive.png"):
            out += [f"![error of stable and naive forms]({perf_rel}/stable_vs_naive.png)", ""]
        rows = []
        for name, row in sv["forms"].items():
            for e, er in row["error"].items():
                s, n = er["stable"], er["naive"]
                rows.append([name, e, f"{_num(_f(s['median']), 2)} / {_num(_f(n['median']), 2)}",
                             f"{_num(_f(s['max']), 2)} / {_num(_f(n['max']), 2)}",
                             f"{_num(s['nonfinite'], 2)} / {_num(n['nonfinite'], 2)}"])
        out += _table(["form", "exponent", "median rel. error stable / naive",
                       "max rel. error stable / naive", "non-finite stable / naive"], rows) + [""]
        rows = [[name, _num(row["ns_stable"], 3), _num(row["ns_naive"], 3),
                 f"{row['ratio_naive_stable']:.3f} ({row['ratio_min']:.2f}-{row['ratio_max']:.2f})"]
                for name, row in sv["forms"].items()]
        out += _table(["form", "ns / evaluation, stable", "naive", "time naive / stable"], rows) + [""]
    rn = acc.get("render_naive")
    if rn:
        out += ["Whole renders: `bench_as_naive` (eq. 4, 6, 9, 10 as printed) against "
                "`ashikhmin_shirley` on the metal sphere (section 2's settings). *mean diff.* "
                "is (naive - stable) / stable of the image means (same seed).", ""]
        rows = [[n, _ratio(v), f"{v['instr_a']} / {v['instr_b']}", v["nonfinite_pixels"],
                 _num(v["mean_rel_diff"], 2)] for n, v in rn.items()]
        out += _table(["nu = nv", "time naive / stable", "instr. naive / stable",
                       "non-finite pixels (naive)", "mean diff."], rows) + [""]
    on = acc.get("oren_nayar_lut")
    if on:
        out += ["### Oren-Nayar: analytic against the table", "",
                "`oren_nayar` (reflectance 0.8, sigma 0.5) with `lut_resolution` N against the "
                "analytic form (N = 0): render time ratio, and the eval error over 100000 random "
                "direction pairs relative to the largest analytic value.", ""]
        rows = [[n, _ratio(v), _num(v["max_abs_err_rel"], 2), _num(v["mean_abs_err_rel"], 2),
                 f"{v['instr_a']} / {v['instr_b']}", _sec(v["compile_a"])] for n, v in on.items()]
        out += _table(["lut_resolution", "time table / analytic", "max error", "mean error",
                       "instr. table / analytic", "compile (table)"], rows) + [""]
    gv = acc.get("ggx_visible")
    if gv:
        out += ["### GGX: visible-normal sampling against sampling D cos", "",
                "`cook_torrance` (GGX D and G, metal) with `sample_visible` true and false. "
                "Per incidence: relative variance var(w) / E[w]^2 of the sampled weight, "
                "nanoseconds per `sample` call (interleaved medians), and the efficiency ratio "
                "(variance x time of D cos over that of visible normals; > 1: visible normals "
                "win). Render: time ratio visible / plain on the sphere and the pixel variance "
                "(from two seeds).", ""]
        rows = []
        for rho, g in gv["roughness"].items():
            for th, r in g["bsdf"].items():
                rows.append([rho, th, f"{_num(r['visible']['rel_variance'])} / "
                             f"{_num(r['plain']['rel_variance'])}",
                             f"{_num(r['visible']['ns_per_sample'])} / {_num(r['plain']['ns_per_sample'])}",
                             _num(_f(r["efficiency_ratio"]))])
        out += _table(["roughness", "incidence", "rel. variance visible / plain",
                       "ns/sample visible / plain", "efficiency visible / plain"], rows) + [""]
        rows = [[rho, _ratio(g["render"]), f"{g['render']['instr_a']} / {g['render']['instr_b']}",
                 f"{_num(g['render']['pixel_variance_visible'])} / "
                 f"{_num(g['render']['pixel_variance_plain'])}",
                 _num(_f(g["render"]["render_efficiency_ratio"]))]
                for rho, g in gv["roughness"].items()]
        out += _table(["roughness", "render time visible / plain", "instr. visible / plain",
                       "pixel variance visible / plain", "render efficiency visible / plain"],
                      rows) + [""]
    c2 = acc.get("chi2")
    if c2:
        eps = sorted({float(e) for r in c2["samples"].values() for e in r["scale"]})
        out += ["### The chi-square test: sample count against the error it detects", "",
                f"`mitsuba.chi2` on `cook_torrance` (GGX, rho = 0.3, metal) at "
                f"{c2['theta_i']} degrees, res {c2['res']}, ires {c2['ires']}, significance "
                f"{c2['significance']}. The samples are right; the pdf is planted wrong: "
                "*scale* = pdf x (1 + eps) (integrates to 1 + eps), *tilt* = pdf x "
                "(1 + eps sign(wo_y)) (still integrates to 1: a shape error). A cell is R "
                "when the test rejects (detects the error), . when it passes. *clean* is the "
                "unplanted pdf (R there is a false alarm). Seconds: one test after a warm-up.",
                ""]
        rows = []
        for n, r in c2["samples"].items():
            cells = []
            for k in ("scale", "tilt"):
                cells.append(" ".join("R" if r[k][f"{e:g}"]["rejected"] else "." for e in eps))
            rows.append([n, "R" if r["clean"]["rejected"] else ".", cells[0], cells[1],
                         _num(_f(r["scale_threshold"])), _num(_f(r["tilt_threshold"])),
                         _sec(r["median_seconds"]), _sec(r["warmup_s"])])
        out += _table(["samples", "clean", "scale, eps = " + " ".join(f"{e:g}" for e in eps),
                       "tilt, eps = same", "smallest scale error detected",
                       "smallest tilt error detected", "seconds per test", "warm-up"], rows) + [""]
    return out


def _lobe_verdict(key, v):
    if v.get("kind") != "lobe":
        return ""
    if v["instr_a"] < v["instr_b"] and v["ratio"] <= 1.02:
        return "dropped: fewer instructions, less time"
    if v["instr_a"] < v["instr_b"]:
        return "dropped: fewer instructions; time difference within noise"
    return "**the absent lobe is still traced: plugin wrong**"


def _section_effects(res, perf_rel):
    eff = res.get("effects")
    out = []
    if eff:
        st = eff["settings"]
        out += ["## 4. Only the effects a scene calls for", "",
                f"The sphere at {st['res']} x {st['res']}, {st['spp']} spp, `direct`; "
                f"{st['runs']} paired runs. Ratio = A / B, A being the configuration without the "
                "effect. A lobe whose weight is a constant zero must be dropped from the kernel "
                "(fewer instructions, ratio < 1); one weighted 1e-6 is kept.", ""]
        items = [(k, v["ratio"], v["ratio_min"], v["ratio_max"]) for k, v in eff["pairs"].items()]
        if items and plot_ok(perf_rel, "effects.png"):
            out += [f"![effect time ratios]({perf_rel}/effects.png)", ""]
        rows = [[f"`{k}`", v["what"], _ratio(v), f"{v['instr_a']} / {v['instr_b']}",
                 f"{_sec(v['compile_a'])} / {_sec(v['compile_b'])}", _lobe_verdict(k, v)]
                for k, v in eff["pairs"].items()]
        out += _table(["pair", "A / B", "time ratio (range)", "instr. A / B", "compile A / B",
                       "verdict"], rows) + [""]
    fig = res.get("figures")
    if fig:
        st = fig["settings"]
        out += ["### `direct` against `path` on the figure scenes", "",
                f"Every `mitsuba_brdfs/scenes/fig*.xml` that loads, at {st['res']} x {st['res']}, "
                f"{st['spp']} spp: its own integrator and the other one (`path` with the scene's max_depth, "
                "or 16 for a `direct` scene; the same `hide_emitters`). *mean diff.* = "
                "(path - direct) / path of the image means: the light `direct` leaves out "
                "(interreflections), plus noise.", ""]
        rows = [[f"`{f}`", v["own"] + (f" (max_depth {v['own_max_depth']})" if v["own_max_depth"] else ""),
                 v["path_max_depth"], _ratio(v), _num(v["mean_rel_diff"], 2),
                 f"{v['instr_a']} / {v['instr_b']}",
                 f"{_sec(v['compile_a'])} / {_sec(v['compile_b'])}"]
                for f, v in fig["scenes"].items()]
        out += _table(["scene", "its integrator", "path max_depth", "time path / direct",
                       "mean diff.", "instr. path / direct", "compile path / direct"], rows) + [""]
    return out


def _section_memory(res, perf_rel):
    mem = res.get("memory")
    if not mem:
        return []
    out = ["## 5. Memory", "",
           f"`python -m mitsuba_brdfs render {mem['scene']} -D res={mem['res']} --spp N` as a "
           "child process; peak resident set size from `os.wait4` (that child alone). The "
           f"command renders in passes of at most {mem['pass_samples']} samples; the rows with "
           "one pass render all their samples in one `mi.render` call, for contrast.", ""]
    if plot_ok(perf_rel, "memory.png"):
        out += [f"![peak memory]({perf_rel}/memory.png)", ""]
    rows = [[r["spp"], r["passes"], f"{r['samples']:,}", f"{r['peak_rss_mib']:.0f}", _sec(r["seconds"]),
             "ok" if r["status"] == 0 else f"exit {r['status']}: {r['error']}"]
            for r in mem["renders"]]
    out += _table(["spp", "passes", "samples", "peak RSS (MiB)", "wall time", "status"], rows) + [""]
    return out


def _section_startup(res, perf_rel):
    st = res.get("startup")
    if not st:
        return []
    c = st["settings"]
    out = ["## 6. Time to the first image", "",
           f"A fresh Python process renders the sphere of `mitsuba_brdfs/scenes/as_sphere.xml` "
           f"({c['res']} x {c['res']}, {c['spp']} spp, `{c['integrator']}`) with a Python plugin, "
           "or with its C++ neighbour (section 2), and times each step "
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
    if plot_ok(perf_rel, "startup.png"):
        out += [f"![time to the first image]({perf_rel}/startup.png)", ""]
    rows = []
    for key, v in st["pairs"].items():
        for state in ("empty", "filled"):
            e = v[state]
            for side, name in (("python", v["plugin"]), ("cpp", v["cpp_plugin"])):
                m = e[side]
                ratio = e["first_image_ratio"]
                rows.append([f"`{name}`", state, _sec(m["import_mitsuba"]),
                             _sec(m["import_package"]) if side == "python" else "-",
                             _sec(m["load"]), _sec(m["trace"]), _sec(m["compile"]),
                             _sec(m["execute"]), f"**{_sec(m['first_image'])}**",
                             _sec(m["process"]), _sec(m["second_render"]),
                             f"{m['kernels']:.0f} / {m['disk_hits']:.0f}",
                             _ratio(ratio) if side == "python" and ratio else ""])
    out += _table(["plugin", "cache", "import", "package", "load", "trace", "compile",
                   "execute", "first image", "process", "again", "kernels / disk",
                   "Python / C++"], rows) + [""]
    py = [v[state]["python"] for v in st["pairs"].values() for state in ("empty", "filled")]
    mib = [m["package_mib"] for m in py if m.get("package_mib") is not None]
    if mib:
        out += [f"`import mitsuba_brdfs` after `import mitsuba` takes "
                f"{_sec(min(m['import_package'] for m in py))}-"
                f"{_sec(max(m['import_package'] for m in py))} and adds "
                f"{min(mib):.1f}-{max(mib):.1f} MiB of resident memory (the rows above).", ""]
    return out


def _section_optimisation(res, perf_rel):
    op = res.get("optimisation")
    if not op:
        return []
    c = op["settings"]
    out = ["## 7. Optimisation loops, traced and frozen", "",
           f"Each configuration recovers one colour parameter of the sphere's BSDF ({c['res']} x "
           f"{c['res']}, {c['spp']} spp, `{c['integrator']}` with max_depth {c['max_depth']}, "
           "Adam, mean squared error against a target render), with the loop a user writes: "
           "`params.update(opt)` (*update*: the plugins check the new value's range there and "
           "read it back), the render, the loss and `dr.backward`, either traced at every "
           "iteration or frozen with `@dr.freeze` (recorded on the first calls, replayed after), "
           "then `opt.step()`, the clamping into range and the loss read back. Seconds per "
           f"iteration: median of {c['iterations']} iterations after {c['warmup']} untimed ones "
           "(tracing, compiling, recording), then the median over "
           f"{c['runs']} rounds in which the four configurations of a pair run alternately, "
           "each built alone; ratios are medians of the per-round ratios (range).", ""]
    rows = []
    for key, v in op["pairs"].items():
        for side, name in (("python", v["plugin"]), ("cpp", v["cpp_plugin"])):
            p, f = v[f"{side}_plain"], v[f"{side}_frozen"]
            rows.append([f"`{name}`", f"`{v['parameter']}`", _sec(p["seconds"]),
                         _sec(f["seconds"]), _ratio(v[f"{side}_frozen_vs_plain"]),
                         f"{_sec(p['update'])} / {_sec(f['update'])}", f["recordings"],
                         f"{_num(p['loss_first'], 2)} -> {_num(p['loss_last'], 2)}"])
    out += _table(["plugin", "parameter", "traced", "frozen", "frozen / traced",
                   "update traced / frozen", "recordings", "loss first -> last (traced)"],
                  rows) + [""]
    rows = [[f"`{v['plugin']}` / `{v['cpp_plugin']}`", _ratio(v["python_vs_cpp_plain"]),
             _ratio(v["python_vs_cpp_frozen"])] for v in op["pairs"].values()]
    out += _table(["Python / C++", "traced", "frozen"], rows) + [""]
    fits = _fits(op)
    if fits:
        from .. import fit as fit_module
        sizes = ("its default size and a larger one" if len(fits) == 2 and fits[0]["default"]
                 else " and ".join(f"{f['res']} x {f['res']}" for f in fits))
        rounds = f"{c['runs']} round" + ("s" if c["runs"] != 1 else "")
        out += [f"**`fit`** (`python -m mitsuba_brdfs fit`) at {sizes}: a whole fit of "
                f"{c['fit_iterations']} iterations (fit's default: {fit_module.ITERATIONS}), the "
                f"first {c['warmup']} not timed, frozen (`@dr.freeze`) against traced "
                f"(`--no-freeze`), alternately, the median over {rounds}. *per iteration*: "
                "median of the timed iterations; *loop*: the whole optimisation loop; *off "
                "by*: the final values' relative errors against the truth (nu, nv, Rs), "
                "frozen and traced alike.", ""]
        rows = []
        for f in fits:
            ef, ep = f["errors_frozen"], f["errors_plain"]
            same = all(math.isclose(f["final_frozen"][k], f["final_plain"][k], rel_tol=1e-4)
                       for k in f["final_frozen"])
            rows.append([f"{f['res']} x {f['res']}" + (" (default)" if f["default"] else ""),
                         f["spp"], _sec(f["plain"]), _sec(f["frozen"]), _ratio(f),
                         f"{_sec(f['loop_plain'])} / {_sec(f['loop_frozen'])}",
                         f["recordings"],
                         ", ".join(f"{100 * ef[k]:.2f}%" for k in ef)
                         + ("" if same else " (traced: " + ", ".join(
                             f"{100 * ep[k]:.2f}%" for k in ep) + ")")])
        out += _table(["image", "spp", "traced per iteration", "frozen per iteration",
                       "frozen / traced", "loop traced / frozen", "recordings", "off by"],
                      rows) + [""]
    return out


def _fits(op):
    """The fit rows of section 7 (none in results written before fit had sizes)."""
    fits = op.get("fit")
    return fits if isinstance(fits, list) else []


def _section_figures_command(res, perf_rel):
    fc = res.get("figures_command")
    if not fc:
        return []
    c = fc["settings"]
    what = "python -m mitsuba_brdfs figures" + (f" --only {' '.join(c['only'])}" if c["only"] else "")
    out = ["## 8. The figures command", "",
           f"`{what}` (quality {c['quality']}) in a fresh process, first with `DRJIT_CACHE_DIR` "
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
    rows = [["**process**", f"**{_sec(e['process'])}**", f"**{_sec(f['process'])}**"],
            ["compile", f"{_sec(e['compile'])} ({100 * fc['compile_share']:.0f}%)",
             _sec(f["compile"])],
            ["kernels / loaded from disk / launches",
             f"{e['kernels']:.0f} / {e['disk_hits']:.0f} / {e.get('launches', 0):.0f}",
             f"{f['kernels']:.0f} / {f['disk_hits']:.0f} / {f.get('launches', 0):.0f}"]]
    if e.get("loop") and f.get("loop"):
        rows.append(["figures", _sec(e["loop"]), _sec(f["loop"])])
    rows += [[f"`{name}`", _sec(v), _sec(f["figures"].get(name))]
             for name, v in e["figures"].items()]
    out += _table(["", "empty cache", "filled cache"], rows) + [""]
    return out


#: the heading that opens each section's part of the document
_HEADINGS = {"## 1.": "error", "## 2.": "cpp", "## 3.": "accuracy", "## 4.": "effects",
             "### `direct` against `path`": "figures", "## 5.": "memory", "## 6.": "startup",
             "## 7.": "optimisation", "## 8.": "figures_command"}


def _with_run_notes(res, lines):
    """In a study written in several runs, each section's heading followed by its run."""
    runs = res.get("runs")
    if not runs:
        return lines
    out = []
    for line in lines:
        out.append(line)
        key = next((k for h, k in _HEADINGS.items() if line.startswith(h)), None)
        i = next((n for n, r in enumerate(runs, 1) if key in r["sections"]), None)
        if i is not None:
            commit = (runs[i - 1]["git"].get("commit") or "unknown")[:10]
            out += ["", f"*From run {i} (commit `{commit}`).*"]
    return out


def plot_startup(st, path):
    """Stacked bars: the phases of the first image per plugin and cache."""
    plt = _plt()
    bars = []
    for v in st.get("pairs", {}).values():
        for state in ("empty", "filled"):
            for side, name in (("python", v["plugin"]), ("cpp", v["cpp_plugin"])):
                bars.append((f"{name}, {state}", v[state][side]))
    if not bars:
        return False
    phases = [("import_mitsuba", "import"), ("import_package", "package"), ("load", "load"),
              ("trace", "trace"), ("compile", "compile"), ("execute", "execute")]
    fig, ax = plt.subplots(figsize=(7.5, 0.4 * len(bars) + 1.4))
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
    fig.tight_layout()
    save_figure(fig, path, dpi=90)
    plt.close(fig)
    return True


_PLOTS = {}


def plot_ok(perf_rel, name):
    return _PLOTS.get(name, False)


def write(res, out_dir):
    """Write performance.md into ``out_dir`` and the plots into ``out_dir/perf``."""
    perf = os.path.join(out_dir, "perf")
    os.makedirs(perf, exist_ok=True)
    _PLOTS.clear()
    if "error" in res:
        _PLOTS["error_vs_time.png"] = plot_error_vs_time(res["error"], os.path.join(perf, "error_vs_time.png"))
    if "cpp" in res:
        items = [(k, v["ratio"], v["ratio_min"], v["ratio_max"]) for k, v in res["cpp"]["pairs"].items()]
        _PLOTS["speed_vs_cpp.png"] = _ratio_bars(items, os.path.join(perf, "speed_vs_cpp.png"),
                                                 "render time, Python plugin / C++ neighbour",
                                                 "time ratio (median, range)", (1.0, TARGET_RATIO))
    if "effects" in res:
        items = [(k, v["ratio"], v["ratio_min"], v["ratio_max"]) for k, v in res["effects"]["pairs"].items()]
        _PLOTS["effects.png"] = _ratio_bars(items, os.path.join(perf, "effects.png"),
                                            "render time without / with the effect",
                                            "time ratio A / B (median, range)")
    if "accuracy" in res:
        _PLOTS["stable_vs_naive.png"] = plot_stable_vs_naive(res["accuracy"],
                                                             os.path.join(perf, "stable_vs_naive.png"))
    if "memory" in res:
        _PLOTS["memory.png"] = plot_memory(res["memory"], os.path.join(perf, "memory.png"))
    if "startup" in res:
        _PLOTS["startup.png"] = plot_startup(res["startup"], os.path.join(perf, "startup.png"))
    lines = _header(res) + _summary(res)
    for sec in (_section_error, _section_cpp, _section_accuracy, _section_effects, _section_memory,
                _section_startup, _section_optimisation, _section_figures_command):
        lines += _with_run_notes(res, sec(res, "perf"))
    lines += ["## Reproduce", "",
              "```sh",
              "python -m mitsuba_brdfs bench            # the full study (on a quiet machine)",
              "python -m mitsuba_brdfs bench --quick    # a reduced run that checks it works",
              "python -m mitsuba_brdfs bench --sections cpp effects   # some parts, "
              "replaced in the study",
              "```", "",
              "Raw numbers (every run's seconds included): [`perf/results.json`](perf/results.json).",
              ""]
    path = os.path.join(out_dir, "performance.md")
    write_text(path, "\n".join(lines))
    return path


def console_summary(res):
    return "\n".join(ln for ln in _summary(res)[2:] if ln)
