"""Section "energy compensation: accuracy against time" of the study's document: each form of
``energy_compensation`` against ``none`` in render time, and the white furnace error each
leaves (measured by ``bench.energy.run``)."""
from .format import num, plt, ratio, save, sec, table

__all__ = ["TARGET_RATIO", "steps", "text", "summary", "plot", "recompiled"]

#: a compensated form should render within this factor of ``none``
TARGET_RATIO = 1.1


def steps(settings):
    """Progress steps of the measurement: two timed comparisons per case."""
    return 2 * len(settings.energy_cases)


def recompiled(data):
    """Timed renders repeated because a kernel was compiled during them."""
    return sum(f["against_none"].get("recompiled", 0) for c in data.get("cases", {}).values()
               for f in c["forms"].values() if "against_none" in f)


def _pairs(data):
    """(case, form, comparison) of every timed comparison."""
    return [(k, form, f["against_none"]) for k, c in data.get("cases", {}).items()
            for form, f in c["forms"].items() if "against_none" in f]


def summary(data, doc):
    """Summary bullet: the time ratios and the furnace errors."""
    pairs = _pairs(data)
    if not pairs:
        return []
    out = []
    for form in ("kulla_conty", "turquin"):
        rs = [v["ratio"] for _, f, v in pairs if f == form]
        errs = [c["forms"][form]["furnace_error"] for c in data["cases"].values()]
        out.append(f"`{form}` {min(rs):.2f}-{max(rs):.2f}x the render time of `none` "
                   f"(furnace error at most {num(max(errs), 2)})")
    none = max(c["forms"]["none"]["furnace_error"] for c in data["cases"].values())
    slow = [f"`{k}` {form}" for k, form, v in pairs if v["ratio"] > TARGET_RATIO]
    return [f"- Energy compensation (section {doc.number('energy')}, variant "
            f"`{data['settings'].get('variant', 'llvm_ad_rgb')}`): " + "; ".join(out)
            + f"; `none` loses up to {num(none, 2)} of the light at 0-80 degrees. Target "
            f"<= {TARGET_RATIO}x: " + ("met everywhere." if not slow else
                                        "missed by " + ", ".join(slow) + ".")]


def text(data, doc):
    """The section's text under its heading."""
    st = data["settings"]
    out = [f"The sphere at {st['res']} x {st['res']}, {st['spp']} spp, `{st['integrator']}` "
           f"integrator, variant `{st.get('variant', 'llvm_ad_rgb')}`; {st['runs']} paired "
           f"runs after a warm-up. Ratio = the compensated form / `none` (median of the "
           f"per-pair ratios, range); target <= {TARGET_RATIO}. *Furnace error*: the largest "
           f"|1 - albedo| of the case's lobe made white (F = 1, no diffuse part) at incidences "
           f"{', '.join(str(t) for t in st['thetas'])} degrees, by quadrature of `eval` over "
           "the hemisphere: what a form leaves of the light single scattering loses (the "
           "furnace at every roughness is tested in `tests/test_energy_compensation.py`). "
           "*instr.*: the BSDF's `sample` and `eval_pdf` traced alone.", ""]
    out += doc.image("energy_error_vs_time.png", "furnace error against render time")
    rows = []
    for key, c in data.get("cases", {}).items():
        for form, f in c["forms"].items():
            v = f.get("against_none")
            ins = f["instructions"]
            rows.append([f"`{key}`", f"`{form}`", num(f["furnace_error"], 2),
                         " ".join(f"{a:.3f}" for a in f["albedo"]),
                         sec(v["median_a"]) if v else "-", ratio(v) if v else "1",
                         (("ok" if v["ratio"] <= TARGET_RATIO else "**slower**") if v else ""),
                         f"{v['instr_a']} / {v['instr_b']}" if v else "-",
                         f"{ins['sample']} / {ins['eval_pdf']}"])
    out += table(["case", "form", "furnace error", "white albedo at the incidences", "time",
                  "ratio to none (range)", "", "instr. render / none", "instr. sample / eval_pdf"],
                 rows) + [""]
    out += ["Cases:", ""] + [f"- `{k}`: {c['what']}" for k, c in data.get("cases", {}).items()]
    out += [""] + [f"- skipped: {s}" for s in data.get("skipped", [])]
    out += ["What the time buys: `kulla_conty` looks up E twice per evaluation (at wi with "
            "E_avg, at wo), evaluates the multiple-scattering lobe and samples it as a lobe "
            "of its own (the pdf a mixture); `turquin` looks up E once and scales the lobe. "
            "Each lookup is one gather of a table cell's four corners and a bilinear "
            "interpolation; with `none` nothing of it is traced (the kernel is the one "
            "before the option existed).", ""]
    return out


def plot(data, path):
    """Furnace error against render time relative to ``none``, a line per case."""
    cases = data.get("cases", {})
    if not cases:
        return False
    fig, ax = plt().subplots(figsize=(7.0, 4.2))
    markers = {"none": "o", "kulla_conty": "s", "turquin": "^"}
    colours = plt().rcParams["axes.prop_cycle"].by_key()["color"]
    for n, (key, c) in enumerate(cases.items()):
        colour = colours[n % len(colours)]
        point = {form: (f["against_none"]["ratio"] if "against_none" in f else 1.0,
                        max(f["furnace_error"], 1e-4)) for form, f in c["forms"].items()}
        for form, (x, y) in point.items():
            ax.plot([x], [y], markers[form], color=colour, ms=6)
            if form != "none":  # from none to each compensated form
                ax.plot([point["none"][0], x], [point["none"][1], y], "-", lw=1, color=colour,
                        label=key if form == "kulla_conty" else None)
    ax.set_yscale("log")
    ax.axvline(1.0, color="k", lw=0.6)
    ax.axvline(TARGET_RATIO, color="k", lw=0.6, ls="--")
    ax.set_xlabel("render time / time with energy_compensation = none (median)")
    ax.set_ylabel("white furnace error, max over 0-80 deg")
    ax.set_title("none (o), kulla_conty (s), turquin (^): error against time", fontsize=9)
    ax.legend(fontsize=7)
    return save(fig, path)
