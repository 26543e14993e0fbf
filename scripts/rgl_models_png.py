"""The figure of docs/measured.md's "The models on real materials": each RGL material
rendered through Mitsuba's ``measured`` (top row) beside its two best fits (below), as
``rgl_models.py`` ranked them (by image error where the fits were judged, else by held-out
loss), all on one sphere under one area light and one environment (the ``ngan2005``
figure's: a sky gradient, a bright horizon band, a dark ground), each labelled with the
material, the model, its image error and its held-out loss. ``--disagree`` also draws the
materials whose best fit by image error is not their best by held-out loss, side by side.

Reads the fits that ``scripts/rgl_models.py`` wrote into FITS (its ``--out``:
``rgl_models.json`` and the fitted XML files), and the RGL files from the folder
``rgl_models.py`` read (recorded there; ``--folder`` overrides it).

    python scripts/rgl_models_png.py FITS docs/measured_models.png [--res 128] [--spp 256]
                                     [--disagree docs/measured_disagree.png]
"""
import argparse
import json
import os
import sys
import time

import numpy as np


def render(bsdf, res, spp):
    """The linear RGB image, and the counts of its pixels that are not finite, and of those
    with a negative channel (the tone mapping shows both as 0 in that channel)."""
    import mitsuba as mi
    from mitsuba_brdfs.figures.ngan2005 import scene
    img = np.array(mi.render(scene(bsdf, res, spp), seed=1))[..., :3]
    finite = np.all(np.isfinite(img), axis=-1)
    return img, (int(np.sum(~finite)), int(np.sum(finite & np.any(img < 0, axis=-1))))


def name(material):
    """A material's name without the RGL database's "_rgb" (every file here is RGB)."""
    return material[:-4] if material.endswith("_rgb") else material


def rgl_file(summary, material, folder=None):
    """The RGL file of ``material`` that ``rgl_models.py`` fitted (``summary``: its JSON),
    or the file of the same name in ``folder``."""
    saved = summary.get("files", {}).get(material) or os.path.join(summary["folder"],
                                                                   material + ".bsdf")
    return os.path.join(folder, os.path.basename(saved)) if folder else saved


def judged(fit):
    """A fit's image error (where judged) and held-out loss, for a label."""
    e = (fit.get("image_error") or {}).get("mean")
    return (f"Delta E {e:.2f}, " if e is not None else "") + \
        f"held-out {fit['holdout_loss']:.3g}"


def disagree(args, summary, rows):
    """The figure of ``--disagree``: for each material whose best fit by image error is
    not its best by held-out loss, the measurement (its render from ``rows``' first), the
    held-out loss's best and the image judge's best."""
    import mitsuba as mi
    from mitsuba_brdfs.figures.panels import compose
    from mitsuba_brdfs.output import tonemap, write_png
    tiles, labels = [], []
    for column, (material, fits) in enumerate(summary["materials"].items()):
        finite = [f for f in fits if f["holdout_loss"] == f["holdout_loss"]]
        by_held = min(finite, key=lambda f: f["holdout_loss"]) if finite else None
        if by_held is None or not fits[0].get("image_error") or by_held is fits[0] or \
                by_held["label"] == fits[0]["label"]:
            continue
        tiles.append(rows[0][column][0])
        labels.append(f"{name(material)}\nmeasured")
        for title, fit in (("best by held-out loss", by_held), ("best by image", fits[0])):
            img, _ = render(mi.load_file(os.path.join(args.fits, fit["xml"])), args.res,
                            args.spp)
            tiles.append(tonemap(img))
            labels.append(f"{title}: {fit['label']}\n{judged(fit)}")
    if not tiles:
        print("no material where the rankings disagree: no second figure")
        return
    canvas = compose(tiles, labels, columns=3,
                     title="Where the rankings disagree: each material (left), its best fit "
                           "by held-out loss (middle) and by image error (right)")
    write_png(args.disagree, canvas, already_tonemapped=True)
    print(f"wrote {args.disagree}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("fits", metavar="FITS", help="rgl_models.py's --out folder")
    p.add_argument("png", metavar="OUT.png")
    p.add_argument("--folder", help="the RGL files (default: the folder rgl_models.py read)")
    p.add_argument("--res", type=int, default=128, help="sphere size in pixels (default: 128)")
    p.add_argument("--spp", type=int, default=256, help="samples per pixel (default: 256)")
    p.add_argument("--fits-shown", type=int, default=2, help="fits per material (default: 2)")
    p.add_argument("--disagree", metavar="OUT2.png",
                   help="also a figure of the materials whose best fit by image error is "
                        "not the best by held-out loss: the measurement, the held-out "
                        "loss's best and the image judge's best side by side")
    args = p.parse_args(argv)
    with open(os.path.join(args.fits, "rgl_models.json")) as f:
        summary = json.load(f)
    import drjit as dr
    import mitsuba as mi
    dr.set_thread_count(min(2, os.cpu_count() or 1))
    from mitsuba_brdfs.variant import set_variant
    set_variant("llvm_ad_rgb")
    import mitsuba_brdfs  # noqa: F401  (registers the plugins)
    from mitsuba_brdfs.figures.panels import compose
    from mitsuba_brdfs.output import tonemap, write_png
    from mitsuba_brdfs.progress import advance, progress_bar
    materials = summary["materials"]
    shown = args.fits_shown
    rows = [[] for _ in range(shown + 1)]
    t0 = time.perf_counter()
    with progress_bar(len(materials) * (shown + 1), "rgl-models figure", "spheres") as bar:
        for material, fits in materials.items():
            path = rgl_file(summary, material, args.folder)
            img, bad = render({"type": "measured", "filename": path}, args.res, args.spp)
            rows[0].append((tonemap(img), f"{name(material)}\nmeasured", bad))
            advance(bar, 1, material)
            for k in range(len(fits[:shown]), shown):     # fewer fits than shown: blank
                rows[k + 1].append((np.full((args.res, args.res, 3), 255, np.uint8), "",
                                    (0, 0)))
                advance(bar, 1, material)
            for k, fit in enumerate(fits[:shown]):
                bsdf = mi.load_file(os.path.join(args.fits, fit["xml"]))
                img, bad = render(bsdf, args.res, args.spp)
                rows[k + 1].append((tonemap(img), f"{k + 1}. {fit['label']}\n{judged(fit)}",
                                    bad))
                advance(bar, 1, f"{material}: {fit['label']}")
    tiles = [t for row in rows for t, _, _ in row]
    labels = [lb for row in rows for _, lb, _ in row]
    by = "image error" if any(f.get("image_error") for fits in materials.values()
                              for f in fits) else "held-out loss"
    canvas = compose(tiles, labels, columns=len(materials),
                     title=f"RGL materials (RGB files) through Mitsuba's measured (top) and "
                           f"their {'two' if shown == 2 else shown} best fits by {by} "
                           f"(below); one light, one environment")
    write_png(args.png, canvas, already_tonemapped=True)
    if args.disagree:
        disagree(args, summary, rows)
    for row in rows:
        for _, label, (nan, negative) in row:
            if nan or negative:
                print(f"{label.replace(chr(10), ': ')}: of {args.res ** 2} pixels, {nan} not "
                      f"finite, {negative} with a negative channel (shown as 0)")
    print(f"wrote {args.png} ({os.path.getsize(args.png) / 1024:.0f} KiB, "
          f"{time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
