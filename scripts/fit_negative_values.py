"""What a fit does with an RGL file's negative values (out-of-gamut colours): kept (as
``fit-measured`` does) or clipped at 0 before the fit.

For each RGL file in FOLDER that holds negative values, Ward and Cook-Torrance are fitted
to the file's samples twice, as they are and clipped at 0 (every sample, the energy term's
rows and the reference albedo), and the fitted models' directional albedo at 0, 45 and
75 deg is compared per channel with the file's as Mitsuba's ``measured`` renders it (the
raw values), in the channel that holds the most negative value: the albedos, and the
mean absolute difference from the file's over the three angles. Prints a Markdown table
(docs/measured.md, "Negative values").

    python scripts/fit_negative_values.py FOLDER
"""
import glob
import os
import sys

import numpy as np


def main(folder):
    import drjit as dr
    import mitsuba as mi
    dr.set_thread_count(2)
    from mitsuba_brdfs.variant import set_variant
    set_variant("llvm_ad_rgb")
    from mitsuba_brdfs.measured import data as D, report as R, variables as V
    from mitsuba_brdfs.measured.fitting import ALBEDO_THETAS, albedo_of
    from mitsuba_brdfs.measured.report import REPORT_THETAS
    rows = [list(ALBEDO_THETAS).index(t) for t in REPORT_THETAS]
    print("| file | channel | samples < 0 | model | albedo 0 / 45 / 75 deg: file "
          "| fit, values kept | fit, values clipped "
          "| mean difference from the file: kept / clipped |")
    print("|---|---|---|---|---|---|---|---|")
    for path in sorted(glob.glob(os.path.join(folder, "*.bsdf"))):
        data = D.prepare(path)
        if not data.negative:
            continue
        raw = np.asarray(data.albedo["reference"], float)[rows]
        worst = int(np.argmin(np.min(data.f, axis=0)))
        share = np.mean(data.f[:, worst] < 0)
        clipped = D.prepare(path)
        clipped.f = np.maximum(clipped.f, 0)
        clipped.albedo["f"] = np.maximum(clipped.albedo["f"], 0)
        fine = clipped.albedo["model"]
        f = clipped.evaluate(fine["wi"].reshape(-1, 3), fine["wo"].reshape(-1, 3))
        clipped.albedo["reference"] = albedo_of(dict(fine, f=np.maximum(
            np.nan_to_num(f), 0).reshape(fine["weight"].shape + (3,))))
        for model in ("ward", "cook_torrance"):
            out = []
            for d in (data, clipped):
                bsdf = mi.load_dict(V.colour_spec({"type": model}, mi.load_dict({"type": model})))
                r = R.fit_file(d, bsdf)
                out.append(np.asarray(r["albedo"]["fitted"], float)[:, worst])
            cell = lambda a: " / ".join(f"{x:.4f}" for x in a)
            off = [np.mean(np.abs(o - raw[:, worst])) for o in out]
            print(f"| `{os.path.basename(path)[:-5]}` | {'RGB'[worst]} | {share:.0%} | {model} "
                  f"| {cell(raw[:, worst])} | {cell(out[0])} | {cell(out[1])} "
                  f"| {cell(off)} |", flush=True)


if __name__ == "__main__":
    if len(sys.argv) != 2 or not os.path.isdir(sys.argv[1]):
        sys.exit(f"usage: python {sys.argv[0]} FOLDER (of RGL .bsdf files)")
    main(sys.argv[1])
