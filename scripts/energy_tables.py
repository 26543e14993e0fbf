"""Write the energy-compensation tables the package ships (mitsuba_brdfs/core/energy_tables.json).

E(mu, r) of each white microfacet lobe, measured with the plugins' own sample() (F = 1) on a
regular grid of sample points per node (``mitsuba_brdfs.validate.energy_tables``), and
1 - E_avg(r) integrated from it. About a minute of CPU (3 minutes on a shared 2-core
machine) at the default 1024 x 1024 points per node; the shipped tables differ from a
measurement at 2048 x 2048 by at most 4.6e-4 in E.

    python scripts/energy_tables.py                 # write the shipped file
    python scripts/energy_tables.py --strata 64     # fewer points per node (a quick look)
    python scripts/energy_tables.py --compare 2048  # the shipped tables against a finer
                                                    # measurement: their sampling error
"""
import argparse
import json
import sys

import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")

import mitsuba_brdfs  # noqa: E402,F401  (registers the plugins)
from mitsuba_brdfs.core.energy import N_ROUGHNESS, TABLES_FILE, table_data, table_keys  # noqa: E402
from mitsuba_brdfs.progress import advance, progress_bar  # noqa: E402
from mitsuba_brdfs.validate.energy_tables import STRATA, build  # noqa: E402


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--strata", type=int, default=STRATA,
                   help="sample points per node along each axis (default: %(default)s)")
    p.add_argument("--out", default=TABLES_FILE, help="the file written (default: the package's)")
    p.add_argument("--compare", type=int, metavar="STRATA",
                   help="write nothing: measure at STRATA and print the largest difference "
                        "from the shipped tables, per table")
    p.add_argument("--threads", type=int, default=0, help="Dr.Jit threads (default: all)")
    args = p.parse_args(argv)
    if args.threads:
        dr.set_thread_count(args.threads)
    keys = table_keys()
    strata = args.compare or args.strata
    bar = progress_bar(len(keys) * N_ROUGHNESS, f"E tables, {strata}^2 points per node", "row")
    data = build(strata, progress=lambda n: advance(bar, n))
    bar.close()
    if args.compare:
        shipped = table_data()["tables"]
        for key in keys:
            a, b = shipped[key]["one_minus_e"], data["tables"][key]["one_minus_e"]
            diff = max(abs(x - y) for ra, rb in zip(a, b) for x, y in zip(ra, rb))
            print(f"{key:28s} largest |E difference| {diff:.2e}")
        return 0
    with open(args.out, "w") as f:
        json.dump(data, f, separators=(",", ":"))
        f.write("\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
