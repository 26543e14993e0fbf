"""Section "memory" of the study's document: the peak memory of command-line renders at
growing spp (measured by ``bench.memory``)."""
from .format import plt, save, sec, table

__all__ = ["steps", "text", "summary", "plot"]


def steps(settings):
    """Progress steps of the measurement."""
    return len(settings.mem_spps) + len(settings.mem_onepass_spps)


def summary(mem, doc):
    """Summary bullet: peak memory in passes and in one pass."""
    renders = mem.get("renders", [])
    if not renders:
        return []
    ps = mem["pass_samples"]
    split = [r for r in renders if r["pass_samples"] == ps]
    whole = [r for r in renders if r["pass_samples"] != ps]
    return [f"- Peak memory of {mem['res']} x {mem['res']} CLI renders "
            "in passes: " + ", ".join(f"{r['spp']} spp {r['peak_rss_mib']:.0f} MiB" for r in split)
            + (" (max / min " + f"{max(r['peak_rss_mib'] for r in split) / min(r['peak_rss_mib'] for r in split):.2f}); "
               if split else "; ")
            + ("in one pass: " + ", ".join(f"{r['spp']} spp {r['peak_rss_mib']:.0f} MiB" for r in whole)
               if whole else "") + "."]


def text(mem, doc):
    """The section's text under its heading."""
    out = [f"`python -m mitsuba_brdfs render {mem['scene']} -D res={mem['res']} --spp N` as a "
           "child process; peak resident set size from `os.wait4` (that child alone). The "
           f"command renders in passes of at most {mem['pass_samples']} samples; the rows with "
           "one pass render all their samples in one `mi.render` call, for contrast.", ""]
    out += doc.image("memory.png", "peak memory")
    rows = [[r["spp"], r["passes"], f"{r['samples']:,}", f"{r['peak_rss_mib']:.0f}", sec(r["seconds"]),
             "ok" if r["status"] == 0 else f"exit {r['status']}: {r['error']}"]
            for r in mem["renders"]]
    out += table(["spp", "passes", "samples", "peak RSS (MiB)", "wall time", "status"], rows) + [""]
    return out


def plot(mem, path):
    """Peak resident memory of each render."""
    rs = mem.get("renders", [])
    if not rs:
        return False
    fig, ax = plt().subplots(figsize=(6, 3.2))
    labels = [f"{r['spp']} spp\n{r['passes']} pass{'es' if r['passes'] > 1 else ''}" for r in rs]
    ax.bar(range(len(rs)), [r["peak_rss_mib"] for r in rs],
           color=["#6a8caf" if r["passes"] > 1 else "#c9734f" for r in rs])
    ax.set_xticks(range(len(rs)))
    ax.set_xticklabels(labels, fontsize=8)
    ax.set_ylabel("peak resident memory (MiB)")
    ax.set_title(f"{mem['res']} x {mem['res']} render through the CLI", fontsize=9)
    return save(fig, path)
