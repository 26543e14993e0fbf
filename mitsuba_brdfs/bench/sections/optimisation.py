"""Section "optimisation loops, traced and frozen" of the study's document: seconds per
iteration with ``@dr.freeze`` and without, and whole ``fit`` runs (measured by
``bench.optimisation``)."""
import math

from .format import num, ratio, sec, table

__all__ = ["steps", "text", "summary", "fits"]


def steps(settings):
    """Progress steps of the measurement."""
    return settings.opt_runs * (len(settings.opt_pairs) + len(settings.fit_sizes))


def summary(op, doc):
    """Summary bullet: seconds per iteration, and fit at its defaults."""
    if not op.get("pairs"):
        return []
    parts = [f"`{v['plugin']}` {sec(v['python_plain']['seconds'])} traced, "
             f"{sec(v['python_frozen']['seconds'])} frozen (`{v['cpp_plugin']}` "
             f"{sec(v['cpp_plain']['seconds'])}, {sec(v['cpp_frozen']['seconds'])})"
             for v in op["pairs"].values()]
    fit = [row for row in fits(op) if row["default"]]
    return [f"- Seconds per optimisation iteration (section {doc.number('optimisation')}): "
            + "; ".join(parts) + "."
            + (f" `fit` at its defaults ({fit[0]['res']} x {fit[0]['res']}, "
               f"{fit[0]['spp']} spp): {sec(fit[0]['frozen'])} frozen against "
               f"{sec(fit[0]['plain'])} traced per iteration "
               f"(ratio {fit[0]['ratio']:.2f})." if fit else "")]


def text(op, doc):
    """The section's text under its heading."""
    c = op["settings"]
    out = [f"Each configuration recovers one colour parameter of the sphere's BSDF ({c['res']} x "
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
            rows.append([f"`{name}`", f"`{v['parameter']}`", sec(p["seconds"]),
                         sec(f["seconds"]), ratio(v[f"{side}_frozen_vs_plain"]),
                         f"{sec(p['update'])} / {sec(f['update'])}", f["recordings"],
                         f"{num(p['loss_first'], 2)} -> {num(p['loss_last'], 2)}"])
    out += table(["plugin", "parameter", "traced", "frozen", "frozen / traced",
                  "update traced / frozen", "recordings", "loss first -> last (traced)"],
                  rows) + [""]
    rows = [[f"`{v['plugin']}` / `{v['cpp_plugin']}`", ratio(v["python_vs_cpp_plain"]),
             ratio(v["python_vs_cpp_frozen"])] for v in op["pairs"].values()]
    out += table(["Python / C++", "traced", "frozen"], rows) + [""]
    rows_fit = fits(op)
    if rows_fit:
        from ... import image_fit as fit_module
        sizes = ("its default size and a larger one" if len(rows_fit) == 2 and rows_fit[0]["default"]
                 else " and ".join(f"{f['res']} x {f['res']}" for f in rows_fit))
        rounds = f"{c['runs']} round" + ("s" if c["runs"] != 1 else "")
        out += [f"**`fit`** (`python -m mitsuba_brdfs fit`) at {sizes}: a whole fit of "
                f"{c['fit_iterations']} iterations (fit's default: {fit_module.ITERATIONS}), the "
                f"first {c['warmup']} not timed, frozen (`@dr.freeze`) against traced "
                f"(`--no-freeze`), alternately, the median over {rounds}. *per iteration*: "
                "median of the timed iterations; *loop*: the whole optimisation loop; *off "
                "by*: the final values' relative errors against the truth (nu, nv, Rs), "
                "frozen and traced alike.", ""]
        rows = []
        for f in rows_fit:
            ef, ep = f["errors_frozen"], f["errors_plain"]
            same = all(math.isclose(f["final_frozen"][k], f["final_plain"][k], rel_tol=1e-4)
                       for k in f["final_frozen"])
            rows.append([f"{f['res']} x {f['res']}" + (" (default)" if f["default"] else ""),
                         f["spp"], sec(f["plain"]), sec(f["frozen"]), ratio(f),
                         f"{sec(f['loop_plain'])} / {sec(f['loop_frozen'])}",
                         f["recordings"],
                         ", ".join(f"{100 * ef[k]:.2f}%" for k in ef)
                         + ("" if same else " (traced: " + ", ".join(
                             f"{100 * ep[k]:.2f}%" for k in ep) + ")")])
        out += table(["image", "spp", "traced per iteration", "frozen per iteration",
                      "frozen / traced", "loop traced / frozen", "recordings", "off by"],
                      rows) + [""]
    return out


def fits(op):
    """The fit rows (none in results written before fit had sizes)."""
    rows = op.get("fit")
    return rows if isinstance(rows, list) else []
