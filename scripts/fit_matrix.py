"""fit-measured across models: the table of docs/presets.md ("what each model can represent").

MERL files written from materials of each model (presets of Ngan et al. 2005 and random
materials), fitted by every other model with ``fit-measured``'s defaults, each fit judged
by ``mitsuba_brdfs.measured.matrix.judge`` (the judge of ``tests/test_fit_matrix.py``):
``within`` 10% of the source's directional albedo at 0, 45 and 75 deg, or ``cannot reach``
(shown by an independent energy-first fit). Prints a Markdown table: per pair the verdict,
the constraint's status, the largest albedo error and the largest channel's relative RMS
error (for 'cannot reach', in brackets, the energy-first fit's), then the seconds per fit.

    python scripts/fit_matrix.py                 # MERL's resolution (about a minute on 2 cores)
    python scripts/fit_matrix.py --small         # 30 x 30 x 60 bins, as the quick tests
    python scripts/fit_matrix.py --json out.json # the judgements too
"""
import argparse
import json
import os
import sys
import tempfile

import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
dr.set_thread_count(2)

import mitsuba_brdfs  # noqa: E402,F401  (registers the plugins)
from mitsuba_brdfs.measured import matrix, merl  # noqa: E402
from mitsuba_brdfs.progress import advance, progress_bar  # noqa: E402

#: (source model, material) of the table's rows
ROWS = [("ward", "reported"), ("ward", "gold-paint"), ("cook_torrance", "random-2"),
        ("cook_torrance", "gold-paint"), ("ashikhmin_shirley", "random-2"),
        ("ashikhmin_shirley_lambert", "gold-paint"), ("blinn_phong", "random-3"),
        ("blinn_phong", "gold-paint")]
NAMES = {"ashikhmin_shirley_lambert": "ashikhmin_shirley (lambert)"}


def cell(j):
    """One judgement in a table cell."""
    if j["verdict"] == "cannot reach":
        return (f"cannot reach: {j['error']:.2f}; {j['rms']:.2f} (energy first: "
                f"{j['reach']:.2f}; {j['reach_rms']:.2f})")
    if j["status"] == "reached":
        return (f"{j['verdict']}, reached: {j['error']:.2f}; {j['rms']:.2f} "
                f"({j['rms_before']:.2f} before)")
    return f"{j['verdict']}, {j['status']}: {j['error']:.2f}; {j['rms']:.2f}"


def table(results):
    models = list(matrix.MODELS)
    head = ["source (material)"] + [NAMES.get(m, m) for m in models]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for (source, name), out in results:
        label = "the rho_d 0.22/0.30/0.40 material" if name == "reported" else \
            f"{name} preset" if not name.startswith("random") else f"random, seed {name[7:]}"
        cells = [f"{NAMES.get(source, source)} ({label})"] + [
            cell(out[m]) if m in out else "" for m in models]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--small", action="store_true",
                   help="30 x 30 x 60 bins, 3000 pairs, 400 evaluations (the quick tests')")
    p.add_argument("--json", help="also write the judgements to this file")
    args = p.parse_args(argv)
    dims, samples, evaluations = ((30, 30, 60), 3000, 400) if args.small else \
        (merl.DIMS, None, None)
    results = []
    with tempfile.TemporaryDirectory() as tmp, \
            progress_bar(len(ROWS) * (len(matrix.MODELS) - 1), "fit_matrix", "fits") as bar:
        for source, name in ROWS:
            def tick(model, j):
                advance(bar, 1, f"{source} {name}: {model} {j['verdict']}")
            out = matrix.write_and_judge(os.path.join(tmp, "m.binary"), source, name, dims,
                                         samples, evaluations, progress=tick)
            results.append(((source, name), out))
    if args.json:
        with open(args.json, "w") as f:
            json.dump([{"source": s, "material": n, "fits": out} for (s, n), out in results],
                      f, indent=1)
    print(table(results))
    seconds = [j["seconds"] for _, out in results for j in out.values()]
    print(f"\nseconds per fit (the default fit, its constraint included): {min(seconds):.1f} "
          f"to {max(seconds):.1f}, median {sorted(seconds)[len(seconds) // 2]:.1f}")
    fails = [(s, n, m) for (s, n), out in results for m, j in out.items()
             if j["verdict"] == "fails"]
    if fails:
        print(f"fails: {fails}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
