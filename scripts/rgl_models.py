"""The models on real materials: every RGL file of FOLDER fitted by several models, ranked
by the image judge (docs/measured.md, "The models on real materials").

For each RGL file (``*.bsdf``, recognised by its ``tensor_file`` header) of FOLDER, the
command ``fit-measured FILE --model M1,M2,... --json`` is run as a user runs it (its own
code path, in this process), and once more for each extra fit that needs its own options
(``fit-measured`` takes ``-p`` for one model only): by default ``ashikhmin_shirley`` with
``-p diffuse_term=lambert``. Every fit of a file sees the same samples and the same
held-out pairs (the command's default ``--samples`` and ``--seed``), so the held-out
losses compare; ``--fit-args`` gives every call more options (``'--select image'``: each
fit chosen among candidates by the judge). Prints a Markdown table, one row per material
and one column per model: the image error (Delta E ITP of the fit's renders against the
file's through Mitsuba's ``measured``, the mean), the held-out loss and the held-out log
loss; the best model of each material by image error in bold, and the best by each
ranking in the last columns ("differs" where they do). Without the judge (``--fit-args
'--image-spp 0'``) the held-out loss and, at 0 / 45 / 75 deg, the albedo error of the fit
against the file's (the channel furthest off, signed, in % of that channel's albedo or
of a tenth of the brightest channel's, where that is larger), the lowest held-out loss in
bold.

Writes into ``--out`` (default ``mitsuba_brdfs-out/rgl-models/``): the command's outputs
(``STEM_MODEL.xml`` and ``.json``, ``STEM_fits.png`` and ``.json``; an extra fit's in the
subfolder named by its label), ``rgl_models.json`` (per material, the fits in ranked
order: label, model, options, image error, held-out loss and log loss, loss, albedo
error, XML file; the files' paths) and
``rgl_models.md`` (the table). ``scripts/rgl_models_png.py`` renders the figure from them.

    python scripts/rgl_models.py FOLDER [--out DIR] [--model M1,M2,...] [--extra SPEC ...]
                                 [--fit-args 'OPTIONS']

The RGL files: the RGL material database (https://rgl.epfl.ch/materials, the ``*_rgb.bsdf``
files) or the public repository adenine-dev/luminiferous (``assets/brdfs/``).
"""
import argparse
import contextlib
import glob
import io
import json
import math
import os
import sys
import time

MODELS = ("lambert", "oren_nayar", "ward", "blinn_phong", "cook_torrance", "ashikhmin_shirley")
#: the extra fits by default: MODEL:KEY=VALUE[,KEY=VALUE...]
EXTRA = ("ashikhmin_shirley:diffuse_term=lambert",)


def parse_extra(text):
    """``MODEL:KEY=VALUE[,KEY=VALUE...]`` -> (label, model, ["KEY=VALUE", ...]); the label
    is ``MODEL, KEY=VALUE, ...``."""
    model, _, options = text.partition(":")
    items = [o.strip() for o in options.split(",") if o.strip()]
    if not model.strip() or not items or not all("=" in o for o in items):
        raise argparse.ArgumentTypeError(f"expected MODEL:KEY=VALUE[,KEY=VALUE...], got {text!r}")
    return ", ".join([model.strip()] + items), model.strip(), items


def rgl_files(folder):
    """The RGL files of ``folder`` (by their header, not their name), sorted."""
    from mitsuba_brdfs.measured.tensor import is_tensor_file
    return [p for p in sorted(glob.glob(os.path.join(folder, "*")))
            if os.path.isfile(p) and is_tensor_file(p)]


def _command(argv):
    """Run ``python -m mitsuba_brdfs ARGV`` here; its standard output, or ``RuntimeError``
    with its error line where it fails."""
    from mitsuba_brdfs.__main__ import main
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(argv)
    if status != 0:
        lines = err.getvalue().strip().splitlines()
        raise RuntimeError(lines[-1].removeprefix("error: ") if lines
                           else f"exit status {status}")
    return out.getvalue()


def albedo_error(albedo):
    """The albedo error of a fit at each of its angles ({'measured', 'fitted'}: [angle]
    [channel]): (fit - file) over the file's channel, or over a tenth of its brightest
    channel where that is larger (a channel near 0 has no meaningful relative error, as
    docs/measured.md's round trip counts it); the channel furthest off, signed."""
    out = []
    for m, f in zip(albedo["measured"], albedo["fitted"]):
        scale = [max(x, 0.1 * max(m)) for x in m]
        out.append(max(((b - a) / s for a, b, s in zip(m, f, scale)), key=abs))
    return out


def _entry(label, options, summary, out):
    """A fit's row of ``rgl_models.json`` from the command's JSON summary."""
    xml = next(p for p in summary["outputs"] if p.endswith(".xml"))
    albedo = {k: summary["albedo"][k] for k in ("thetas", "measured", "fitted")}
    held = summary.get("holdout_losses") or {}
    return {"label": label, "model": summary["model"], "options": options,
            "holdout_loss": summary["holdout_loss"], "holdout_log": held.get("log"),
            "image_error": summary.get("image_error"), "loss": summary["loss"],
            "loss_kind": summary.get("loss_kind"), "selected_by": summary.get("selected_by"),
            "isotropy": summary.get("isotropy"),
            "albedo": albedo, "albedo_error": albedo_error(albedo),
            "relative_rms_max": summary["relative_rms_max"], "params": summary["params"],
            "warnings": summary["warnings"], "xml": os.path.relpath(xml, out)}


def fit_file(path, out, models=MODELS, extra=EXTRA, fit_args=()):
    """Fit ``models`` (one ``fit-measured`` call) and each ``extra`` (label, model, options)
    to the RGL file ``path``, with ``fit_args`` (more of the command's options); the fits'
    entries, unranked, and the seconds it took."""
    t0 = time.perf_counter()
    fits = []
    if models:
        text = _command(["fit-measured", path, "--model", ",".join(models), "--json",
                         "--out", out, *fit_args])
        summaries = json.loads(text)
        for s in summaries["fits"] if "fits" in summaries else [summaries]:
            fits.append(_entry(s["model"], [], s, out))
    for label, model, options in extra:
        folder = os.path.join(out, label.replace(", ", "_").replace("=", "-"))
        argv = ["fit-measured", path, "--model", model]
        for o in options:
            argv += ["-p", o]
        fits.append(_entry(label, options, json.loads(_command(
            argv + ["--json", "--out", folder, *fit_args])), out))
    return fits, time.perf_counter() - t0


def _finite(x):
    return x is not None and math.isfinite(x)


def ranked(fits, by="image"):
    """The fits as ``fit-measured`` ranks them: by image error (``image``; fits without one
    after), then held-out loss (a missing or NaN one last), then loss; ``holdout``: by
    held-out loss, then loss."""
    def key(f):
        h, e = f.get("holdout_loss"), (f.get("image_error") or {}).get("mean")
        held = (not _finite(h), h if _finite(h) else math.inf, f["loss"])
        return ((not _finite(e), e if _finite(e) else math.inf) if by == "image" else ()) + held
    return sorted(fits, key=key)


def _best(fits, by):
    order = ranked(fits, by)
    ok = order and (_finite((order[0].get("image_error") or {}).get("mean")) if by == "image"
                     else _finite(order[0]["holdout_loss"]))
    return order[0]["label"] if ok else None


def table(results, labels):
    """The Markdown table of ``results`` ({material: [fit entry, ...]}): a row per material,
    a column per label (in ``labels``' order), each cell the image error (Delta E ITP, the
    mean), the held-out loss and the held-out log loss, the best by image error in bold;
    the last columns the best by image error and by held-out loss. Without image errors,
    each cell the held-out loss and the albedo error at fit-measured's ``REPORT_THETAS``
    (%, ``albedo_error``), the best by held-out loss in bold. A fit that is missing (it
    failed) is '-'."""
    judged = any(f.get("image_error") for fits in results.values() for f in fits)
    head = (["material"] + [f"`{lb}`" for lb in labels]
            + (["best by image", "best by held-out loss"] if judged else ["best"]))
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    num = lambda x: f"{x:.3g}" if _finite(x) else "-"
    for material, fits in results.items():
        best = _best(fits, "image" if judged else "holdout")
        by_label = {f["label"]: f for f in fits}
        cells = [f"`{material}`"]
        for lb in labels:
            f = by_label.get(lb)
            if f is None:
                cells.append("-")
                continue
            if judged:
                e = (f.get("image_error") or {}).get("mean")
                first = f"{e:.2f}" if _finite(e) else "-"
                rest = f"{num(f['holdout_loss'])} / {num(f.get('holdout_log'))}"
            else:
                first = num(f["holdout_loss"])
                rest = " / ".join(f"{100 * e:+.0f}" for e in f["albedo_error"]) + " %"
            cells.append(f"**{first}** ({rest})" if lb == best else f"{first} ({rest})")
        cells.append(f"`{best}`" if best else "-")
        if judged:
            held = _best(fits, "holdout")
            cells.append((f"`{held}`" if held else "-") + (" (differs)" if held != best else ""))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def run(folder, out, models=MODELS, extra=EXTRA, progress=True, fit_args=()):
    """Fit every RGL file of ``folder``; write ``rgl_models.json`` and ``.md`` into ``out``;
    returns (the results {material: ranked fits}, the table, seconds per material, the
    files that failed {material: the command's error})."""
    from mitsuba_brdfs.measured.report import REPORT_THETAS
    from mitsuba_brdfs.output import write_json, write_text
    from mitsuba_brdfs.progress import advance, progress_bar
    files = rgl_files(folder)
    if not files:
        raise SystemExit(f"error: {folder}: no RGL file (a file starting with 'tensor_file')")
    os.makedirs(out, exist_ok=True)
    per_file = len(models) + len(extra)
    results, seconds, failed, paths = {}, {}, {}, {}
    with progress_bar(len(files) * per_file, "rgl-models", "fits", enabled=progress) as bar:
        for path in files:
            material = os.path.splitext(os.path.basename(path))[0]
            paths[material] = os.path.abspath(path)
            bar.set_postfix_str(material)
            try:
                fits, seconds[material] = fit_file(path, out, models, extra, fit_args)
                results[material] = ranked(fits)
            except RuntimeError as e:        # said in one line; the other files go on
                failed[material] = str(e)
                bar.write(f"error: {material}: {e}", file=sys.stderr)
            advance(bar, per_file, material)
    labels = list(models) + [lb for lb, _, _ in extra]
    text = table(results, labels)
    write_json(os.path.join(out, "rgl_models.json"),
               {"folder": os.path.abspath(folder), "files": paths, "labels": labels,
                "fit_args": list(fit_args),
                "thetas": list(REPORT_THETAS), "seconds": seconds, "failed": failed,
                "materials": results}, indent=1)
    write_text(os.path.join(out, "rgl_models.md"), text + "\n")
    return results, text, seconds, failed


def retable(out):
    """The table of the fits in ``out`` (``rgl_models.json``), their albedo errors
    recomputed; written to ``rgl_models.md`` again."""
    from mitsuba_brdfs.output import write_text
    with open(os.path.join(out, "rgl_models.json")) as f:
        saved = json.load(f)
    for fits in saved["materials"].values():
        for fit in fits:
            fit["albedo_error"] = albedo_error(fit["albedo"])
    text = table(saved["materials"], saved["labels"])
    write_text(os.path.join(out, "rgl_models.md"), text + "\n")
    return text


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("folder", metavar="FOLDER", help="a folder of RGL .bsdf files")
    p.add_argument("--out", default=os.path.join("mitsuba_brdfs-out", "rgl-models"),
                   help="folder of the fits and the table (default: %(default)s)")
    p.add_argument("--model", default=",".join(MODELS),
                   help="models fitted in one fit-measured call (default: %(default)s)")
    p.add_argument("--extra", action="append", default=None,
                   metavar="MODEL:KEY=VALUE[,...]",
                   help=f"a fit with options, repeatable (default: {' '.join(EXTRA)}); "
                        f"--extra none: no extra fit")
    p.add_argument("--fit-args", default="", metavar="'OPTIONS'",
                   help="more options of every fit-measured call, e.g. '--select image' "
                        "(the figure's fits) or '--image-spp 0' (no image judge)")
    p.add_argument("--table", action="store_true",
                   help="print the table of the fits already in --out (its rgl_models.json) "
                        "again, without fitting")
    args = p.parse_args(argv)
    if args.table:
        print(retable(args.out))
        return 0
    if not os.path.isdir(args.folder):
        p.error(f"{args.folder}: not a folder")
    try:
        extra = [parse_extra(e) for e in (args.extra or EXTRA) if e != "none"]
    except argparse.ArgumentTypeError as e:
        p.error(f"--extra: {e}")
    models = [m.strip() for m in args.model.split(",") if m.strip()]
    import drjit as dr
    dr.set_thread_count(min(2, os.cpu_count() or 1))
    t0 = time.perf_counter()
    results, text, seconds, failed = run(args.folder, args.out, models, extra,
                                         fit_args=args.fit_args.split())
    print(text)
    each = ", ".join(f"{m} {s:.0f} s" for m, s in seconds.items())
    print(f"\n{len(results)} materials, {len(models) + len(extra)} fits each, "
          f"{time.perf_counter() - t0:.0f} s ({each}); fits in {args.out}")
    for material, error in failed.items():
        print(f"failed: {material}: {error}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
