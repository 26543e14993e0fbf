"""Section "error against time" of the study's document: RMSE against render time for each
sampling strategy, and the BSDF alone (measured by ``bench.error``)."""
from .format import f, num, plt, save, sec, table

__all__ = ["steps", "text", "summary", "plot", "recompiled"]


def steps(settings):
    """Progress steps of the measurement."""
    from ..error import SCENES
    return len(SCENES) * (len(settings.err_spps) + 1) + 1


def recompiled(err):
    """Timed renders repeated because a kernel was compiled during them."""
    return sum(s.get("recompiled", 0) for sc in err.get("scenes", {}).values()
               for s in sc["strategies"].values())


def summary(err, doc):
    """Summary bullets, then the time-to-target table (placed after the bullets)."""
    out = []
    alone = err.get("bsdf_alone", {}).get("incidences", {})
    if alone:
        r = alone.get("45") or alone.get(45) or next(iter(alone.values()))
        out.append(f"- Importance sampling: at nu = nv = 1000, AS half-vector sampling of the BSDF "
                   f"alone is {num(f(r['efficiency_ratio']))} times as efficient "
                   f"(1 / (variance x time)) as cosine sampling at 45 degrees incidence.")
    scenes = err.get("scenes", {})
    if scenes:
        names = list(next(iter(scenes.values()))["strategies"])
        out.append(f"- Time each sampling strategy needs to reach a relative RMSE of "
                   f"{err['settings']['target']:g}: the table below (* extrapolated; section "
                   f"{doc.number('error')}).")
        rows = []
        for sc in scenes.values():
            st = sc["strategies"]
            rows.append([sc["title"]] + [sec(f(st[n]["time_to_target"]))
                                         + (" *" if st[n]["extrapolated"] else "")
                                         for n in names])
        out += [""] + table(["scene"] + names, rows)
    return out


def text(err, doc):
    """The section's text under its heading."""
    st = err["settings"]
    out = [f"The sphere of `scenes/as_sphere.xml` at {st['res']} x {st['res']}, "
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
    out += doc.image("error_vs_time.png", "RMSE against time")
    out += [f"Time to reach a relative RMSE of **{st['target']:g}** (interpolated between "
            "measured points, or extrapolated from the largest spp with RMSE^2 x time = const, "
            "marked *); *slope* is the fitted d log RMSE / d log time (-0.5 for Monte Carlo once "
            "the time grows with spp; steeper where a fixed per-render cost dominates); "
            "*efficiency* is 1 / (relative MSE x seconds) at the largest spp, relative to "
            "importance + MIS; *compile* is the warm-up's JIT time at the first spp.", ""]
    for sc in err.get("scenes", {}).values():
        out += [f"**{sc['title']}** (`{sc['plugin']}`; reference noise {sc['reference_rel_std']:.2g} "
                "per pixel, relative)", ""]
        base = f(sc["strategies"]["importance + MIS"]["efficiency"])
        rows = []
        for name, s in sc["strategies"].items():
            t = f(s["time_to_target"])
            rows.append([name, sec(t) + (" *" if s["extrapolated"] else ""),
                         num(f(s["slope"]), 2), num(f(s["efficiency"]) / base, 3),
                         num(s["rel_rmse"][-1], 3), sec(s["seconds"][-1]),
                         sec(s["compile_s"][0]), s["instructions"][-1]])
        out += table(["strategy", "time to target", "slope", "efficiency", "RMSE at max spp",
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
            rows.append([th, num(hv["albedo"]), num(cs["albedo"]), num(hv["variance"]),
                         num(cs["variance"]), num(hv["seconds_per_sample"] * 1e9, 3),
                         num(cs["seconds_per_sample"] * 1e9, 3), num(f(r["efficiency_ratio"]))])
        out += table(["incidence (deg)", "albedo half-vector", "albedo cosine",
                      "variance half-vector", "variance cosine", "ns/sample half-vector",
                      "ns/sample cosine", "efficiency half-vector / cosine"], rows) + [""]
    return out


def plot(err, path):
    """RMSE against time, one panel per scene."""
    from matplotlib.ticker import NullFormatter
    scenes = err.get("scenes", {})
    if not scenes:
        return False
    cols = 3
    rows = (len(scenes) + cols - 1) // cols
    fig, axes = plt().subplots(rows, cols, figsize=(4.6 * cols, 3.6 * rows), squeeze=False)
    target = err["settings"]["target"]
    for ax, sc in zip(axes.flat, scenes.values()):
        for name, s in sc["strategies"].items():
            pts = [(t, e) for t, e in zip(s["seconds"], s["rel_rmse"]) if f(e) > 0]
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
    return save(fig, path)
