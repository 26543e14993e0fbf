"""Section "the price of accuracy choices" of the study's document: stable against naive
formulas, tables against closed forms, visible-normal sampling, the chi-square test's power
(measured by ``bench.accuracy``)."""
from .format import f, num, plt, ratio, save, sec, table

__all__ = ["steps", "text", "summary", "plot", "recompiled"]


def steps(settings):
    """Progress steps of the measurement."""
    s = settings
    return 3 + len(s.naive_render_exponents) + len(s.onr_luts) + 2 + len(s.chi2_samples)


def recompiled(acc):
    """Timed renders repeated because a kernel was compiled during them."""
    n = sum(v.get("recompiled", 0) for group in ("render_naive", "oren_nayar_lut")
            for v in acc.get(group, {}).values())
    return n + sum(g["render"].get("recompiled", 0)
                   for g in acc.get("ggx_visible", {}).get("roughness", {}).values())


def summary(acc, doc):
    """Summary bullet: stable formulas against the printed ones."""
    rn = acc.get("render_naive", {})
    forms = acc.get("stable_vs_naive", {}).get("forms", {})
    if not (rn or forms):
        return []
    parts = [f"render time naive / stable {v['ratio']:.2f} at nu = nv = {n}" for n, v in rn.items()]
    for name, row in forms.items():
        top = list(row["error"])[-1]
        er = row["error"][top]
        parts.append(f"{name.split(',')[0]} at {top}: max error {num(f(er['stable']['max']), 2)} "
                     f"stable, {num(f(er['naive']['max']), 2)} naive "
                     f"({num(er['naive']['nonfinite'], 2)} non-finite), time naive / stable "
                     f"{row['ratio_naive_stable']:.2f}")
    return [f"- Stable formulas against the printed ones (section {doc.number('accuracy')}): "
            + "; ".join(parts) + "."]


def text(acc, doc):
    """The section's text under its heading."""
    out = []
    sv = acc.get("stable_vs_naive")
    if sv:
        out += ["### Stable exponent forms against the formulas as printed", "",
                "Inputs are drawn from each lobe itself (where a renderer evaluates it), "
                f"{sv['error_samples']} per exponent; errors are relative to a float64 "
                "evaluation of the same float32 inputs; *non-finite* is the fraction of NaN/inf "
                f"results. Time: {sv['samples']} evaluations per kernel, stable and naive "
                "interleaved, at exponent 1e4 (an opaque value: one kernel for every exponent). "
                "The naive forms are written in `mitsuba_brdfs/bench/plugins.py` only.", ""]
        out += doc.image("stable_vs_naive.png", "error of stable and naive forms")
        rows = []
        for name, row in sv["forms"].items():
            for e, er in row["error"].items():
                s, n = er["stable"], er["naive"]
                rows.append([name, e, f"{num(f(s['median']), 2)} / {num(f(n['median']), 2)}",
                             f"{num(f(s['max']), 2)} / {num(f(n['max']), 2)}",
                             f"{num(s['nonfinite'], 2)} / {num(n['nonfinite'], 2)}"])
        out += table(["form", "exponent", "median rel. error stable / naive",
                      "max rel. error stable / naive", "non-finite stable / naive"], rows) + [""]
        rows = [[name, num(row["ns_stable"], 3), num(row["ns_naive"], 3),
                 f"{row['ratio_naive_stable']:.3f} ({row['ratio_min']:.2f}-{row['ratio_max']:.2f})"]
                for name, row in sv["forms"].items()]
        out += table(["form", "ns / evaluation, stable", "naive", "time naive / stable"], rows) + [""]
    rn = acc.get("render_naive")
    if rn:
        out += ["Whole renders: `bench_as_naive` (eq. 4, 6, 9, 10 as printed) against "
                f"`ashikhmin_shirley` on the metal sphere (section {doc.number('cpp')}'s settings). *mean diff.* "
                "is (naive - stable) / stable of the image means (same seed).", ""]
        rows = [[n, ratio(v), f"{v['instr_a']} / {v['instr_b']}", v["nonfinite_pixels"],
                 num(v["mean_rel_diff"], 2)] for n, v in rn.items()]
        out += table(["nu = nv", "time naive / stable", "instr. naive / stable",
                      "non-finite pixels (naive)", "mean diff."], rows) + [""]
    on = acc.get("oren_nayar_lut")
    if on:
        out += ["### Oren-Nayar: analytic against the table", "",
                "`oren_nayar` (reflectance 0.8, sigma 0.5) with `lut_resolution` N against the "
                "analytic form (N = 0): render time ratio, and the eval error over 100000 random "
                "direction pairs relative to the largest analytic value.", ""]
        rows = [[n, ratio(v), num(v["max_abs_err_rel"], 2), num(v["mean_abs_err_rel"], 2),
                 f"{v['instr_a']} / {v['instr_b']}", sec(v["compile_a"])] for n, v in on.items()]
        out += table(["lut_resolution", "time table / analytic", "max error", "mean error",
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
                rows.append([rho, th, f"{num(r['visible']['rel_variance'])} / "
                             f"{num(r['plain']['rel_variance'])}",
                             f"{num(r['visible']['ns_per_sample'])} / {num(r['plain']['ns_per_sample'])}",
                             num(f(r["efficiency_ratio"]))])
        out += table(["roughness", "incidence", "rel. variance visible / plain",
                      "ns/sample visible / plain", "efficiency visible / plain"], rows) + [""]
        rows = [[rho, ratio(g["render"]), f"{g['render']['instr_a']} / {g['render']['instr_b']}",
                 f"{num(g['render']['pixel_variance_visible'])} / "
                 f"{num(g['render']['pixel_variance_plain'])}",
                 num(f(g["render"]["render_efficiency_ratio"]))]
                for rho, g in gv["roughness"].items()]
        out += table(["roughness", "render time visible / plain", "instr. visible / plain",
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
                         num(f(r["scale_threshold"])), num(f(r["tilt_threshold"])),
                         sec(r["median_seconds"]), sec(r["warmup_s"])])
        out += table(["samples", "clean", "scale, eps = " + " ".join(f"{e:g}" for e in eps),
                      "tilt, eps = same", "smallest scale error detected",
                      "smallest tilt error detected", "seconds per test", "warm-up"], rows) + [""]
    return out


def plot(acc, path):
    """Relative error of the stable and naive forms against the exponent."""
    forms = acc.get("stable_vs_naive", {}).get("forms", {})
    if not forms:
        return False
    fig, axes = plt().subplots(1, len(forms), figsize=(4.3 * len(forms), 3.3), squeeze=False)
    for ax, (name, row) in zip(axes.flat, forms.items()):
        ex = [float(e) for e in row["error"]]
        for kind, color in (("stable", "#2b6cb0"), ("naive", "#c05621")):
            med = [max(f(row["error"][k][kind]["median"]), 1e-9) for k in row["error"]]
            mx = [max(f(row["error"][k][kind]["max"]), 1e-9) for k in row["error"]]
            ax.loglog(ex, med, marker="o", color=color, label=f"{kind}: median")
            ax.loglog(ex, mx, marker="x", ls="--", color=color, alpha=0.7, label=f"{kind}: max")
        ax.set_title(name, fontsize=8)
        ax.set_xlabel("exponent")
        ax.set_ylabel("relative error vs float64")
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
    axes.flat[0].legend(fontsize=7)
    return save(fig, path)
