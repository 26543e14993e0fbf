"""How a fit went: ``fit_file`` fits a model to a file's ``data.Measured`` and adds what a
user judges it by (the relative RMS error, the albedo at ``REPORT_THETAS``, warnings);
``summary_table`` prints fits as a Markdown table (``slices.plot_slices`` draws measured
against fitted slices).
"""
import math

import numpy as np

from .fitting import ALBEDO_TOLERANCE as ALBEDO_CONSTRAINT
from ..output import jsonable

__all__ = ["REPORT_THETAS", "ALBEDO_TOLERANCE", "BINS_PER_VALUE", "fit_file", "fit_summary",
           "summary_table"]

#: the incidence angles (deg) the summary and the table report the albedo at
REPORT_THETAS = (0, 45, 75)
#: albedo differences beyond this are warned about
ALBEDO_TOLERANCE = 0.10
#: a file with fewer measured bins than this many per fitted value is warned about
BINS_PER_VALUE = 20


def fit_file(data, bsdf, loss="l2cos", keys=None, optimizer="lbfgs", evaluations=None,
             albedo_weight=None, lr=0.05, progress=None, shape_weight=1.0,
             albedo_tolerance=ALBEDO_CONSTRAINT, isotropic=None, start=None):
    """``fitting.fit`` of ``bsdf`` to a file's ``Measured`` data; the result with its
    ``quality`` ('relative_rms', 'relative_rms_max'), the albedo at the rows nearest
    ``REPORT_THETAS`` ('albedo': {'thetas', 'measured', 'fitted', 'relative_difference'}),
    the constraint's outcome ('constraint': ``fitting.fit``'s, with the relative RMS error
    per channel of its stages where the shape alone left the goal:
    'relative_rms_unconstrained', 'relative_rms_closest') and 'warnings' (sentences).
    ``isotropic``: an anisotropic model's two widths held equal (``fitting.fit``); None:
    where the data are isotropic (``data.isotropic``); 'isotropy' says which: {'data',
    'fit': "isotropic" or "anisotropic", 'tied': the widths held equal}. ``start``:
    ``fitting.fit``'s."""
    from .fitting import ALBEDO_WEIGHT, fit
    from .quality import bound_warnings, quality
    from .variables import tied_pairs
    albedo_weight = ALBEDO_WEIGHT if albedo_weight is None else albedo_weight
    r = fit(bsdf, data.wi, data.wo, data.f, weights=data.weights, albedo=data.albedo,
            albedo_weight=albedo_weight, shape_weight=shape_weight, loss=loss, keys=keys,
            optimizer=optimizer, evaluations=evaluations, lr=lr, progress=progress,
            albedo_tolerance=albedo_tolerance, start=start,
            isotropic=getattr(data, "isotropic", True) if isotropic is None else isotropic)
    free = tied_pairs(list(r["params"]))
    r["isotropy"] = {"data": "isotropic" if getattr(data, "isotropic", True) else
                     "anisotropic", "fit": "anisotropic" if free and not r["tied"] else
                     "isotropic", "tied": r["tied"]}
    r.update(quality(bsdf, data.wi, data.wo, data.f, data.weights))
    thetas = np.asarray(data.albedo.get("thetas", REPORT_THETAS), float)
    rows = sorted({int(np.argmin(np.abs(thetas - t))) for t in REPORT_THETAS})
    measured = np.array(r["albedo"]["measured"])[rows]
    fitted = np.array(r["albedo"]["fitted"])[rows]
    r["albedo"] = {"thetas": [float(thetas[i]) for i in rows], "measured": measured.tolist(),
                   "fitted": fitted.tolist()}
    warnings = []
    bounds = bound_warnings(r["at_bounds"])
    if bounds:
        warnings.append(bounds)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(measured > 0, fitted / measured - 1, 0.0)
    r["albedo"]["relative_difference"] = rel.tolist()
    c = r.get("constraint")
    for stage in ("unconstrained", "closest"):
        if c and stage in c:
            c[f"relative_rms_{stage}"] = _quality_at(bsdf, c[stage]["params"], data)
    worst = np.unravel_index(np.argmax(np.abs(rel)), rel.shape)
    where = (f"{abs(rel[worst]):.0%} {'more' if rel[worst] > 0 else 'less'} light than the "
             f"data at {r['albedo']['thetas'][worst[0]]:.0f} deg ({'RGB'[worst[1]]})")
    if c and c["status"] == "reached":
        warnings.append(
            f"fitted to reflect within {c['goal']:.0%} of the data's light at every angle "
            f"(the shape alone left it {c['unconstrained']['largest_error']:.0%} off), at a "
            f"cost in shape: relative RMS {r['relative_rms_max']:.3g}, "
            f"{max(c['relative_rms_unconstrained']):.3g} before "
            f"(--shape-only fits the shape alone)")
    elif c and c["status"] == "cannot reach":
        closest = c.get("closest", {"largest_error": math.nan, "shape": math.nan})
        why = (f"fitted for the energy first it still stays {closest['largest_error']:.0%} off"
               if not closest["largest_error"] <= c["goal"] else
               f"it gets there only further from the data than a black model (relative RMS "
               f"{max(c['relative_rms_closest']):.3g})")
        warnings.append(
            f"the model cannot reflect within {c['goal']:.0%} of the data's light at every "
            f"angle: the fit reflects {where}, and {why} (see 'what each model can "
            f"represent' in docs/presets.md)")
    elif c and c["status"] == "not tried":
        warnings.append(f"nothing fitted (0 evaluations): the start reflects {where}, "
                        f"beyond the albedo goal ({c['goal']:.0%})")
    elif abs(rel[worst]) > ALBEDO_TOLERANCE:
        warnings.append(
            f"the fit reflects {where}: the model's energy does not follow the data's there "
            f"(see 'what each model can represent' in docs/presets.md)")
    values = sum(len(v) for v in r["params"].values())
    if data.bins < BINS_PER_VALUE * values:
        warnings.append(f"only {data.bins} measured bins within 80 deg for {values} fitted "
                        f"values: the parameters are poorly determined")
    r["warnings"] = warnings
    return r


def _quality_at(bsdf, params, data):
    """The relative RMS error per channel of ``bsdf`` at other parameters ({traverse key:
    values}); the BSDF is left as it was."""
    import mitsuba as mi
    from .quality import quality
    from .variables import read, write
    p = mi.traverse(bsdf)
    kept = {k: read(p, k) for k in params}
    for k, v in params.items():
        write(p, k, v)
    p.update()
    try:
        return quality(bsdf, data.wi, data.wo, data.f, data.weights)["relative_rms"]
    finally:
        for k, v in kept.items():
            write(p, k, v)
        p.update()


def fit_summary(args, name, data, model, spec, r, xml, outputs, notes=()):
    """The JSON summary of one fit of the command (``args``: its arguments) to the data
    called ``name``."""
    keys = ("loss", "holdout_loss", "holdout_losses", "image_error", "shape", "energy",
            "start_loss", "loss_kind", "albedo_weight", "relative_rms", "relative_rms_max",
            "albedo", "constraint", "params", "isotropy", "at_bounds", "warnings",
            "optimizer", "evaluations", "seconds", "seconds_per_evaluation", "seconds_image",
            "seconds_total", "samples", "holdout_samples", "lr_cuts", "starts", "start",
            "selected_by", "candidates", "seconds_candidates")
    source = {"file": args.file} if args.file is not None else {"target": name}
    return jsonable({**source, "kind": data.kind, "dims": data.dims and list(data.dims),
                     "bins": data.bins, "negative_values": data.negative, "model": model,
                     "spec": spec, "weights": args.weights,
                     **{k: r.get(k) for k in keys if k in r},
                     "notes": list(notes), "xml": xml, "outputs": list(outputs)})


def _goal(r):
    """The albedo constraint's outcome in a few words."""
    c = r.get("constraint")
    if not c:
        return "off"
    if c["status"] == "reached":
        return f"reached (RMS {max(c['relative_rms_unconstrained']):.3g} before)"
    if c["status"] == "cannot reach":
        closest = c.get("closest", {}).get("largest_error", math.nan)
        return f"cannot reach (closest {closest:.0%})"
    if c["status"] == "not tried":
        return f"not tried (0 evaluations; {c['largest_error']:.0%} off)"
    return "met"


def summary_table(rows):
    """The fits as a Markdown table, one row per (model, result), in the given order: the
    loss (its two terms), the held-out loss, the image error (where judged: the mean and
    95th percentile of Delta E ITP, ``judge``), the relative RMS error of f cos per channel,
    the albedo's error against the data's at the rows nearest ``REPORT_THETAS`` (the
    largest channel's, signed), the albedo constraint's outcome, evaluations, seconds."""
    thetas = rows[0][1]["albedo"]["thetas"] if rows else REPORT_THETAS
    image = any(r.get("image_error") for _, r in rows)
    head = (["model", "loss (shape + energy)", "held-out loss"]
            + ["image error (Delta E ITP mean / p95)"] * image
            + ["relative RMS R, G, B",
               "albedo error at " + " / ".join(f"{t:.0f}" for t in thetas) + " deg",
               "albedo goal", "evaluations", "seconds"])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for model, r in rows:
        rel = np.asarray(r["albedo"]["relative_difference"], float)
        worst = rel[np.arange(len(rel)), np.argmax(np.abs(rel), axis=1)]
        held = r.get("holdout_loss", math.nan)
        ie = r.get("image_error")
        cells = [model, f"{r['loss']:.4g} ({r['shape']:.3g} + {r['albedo_weight']:g} x "
                        f"{r['energy']:.3g})",
                 f"{held:.4g}" if math.isfinite(held) else "-"]
        if image:
            cells.append(f"{ie['mean']:.2f} / {ie['p95']:.2f}" if ie else "-")
        cells += [", ".join(f"{e:.3f}" for e in r["relative_rms"]),
                 " / ".join(f"{100 * x:+.0f}%" for x in worst), _goal(r),
                 str(r["evaluations"]), f"{r.get('seconds_total', r['seconds']):.1f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


#: luminance weights of linear sRGB (Rec. 709)
