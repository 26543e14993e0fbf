"""Speed of ``ashikhmin_shirley`` against Mitsuba's C++ ``roughconductor`` on the same scene.

The sphere of ``scenes/as_sphere.xml`` is rendered with a metallic Ashikhmin-Shirley lobe
(Rd = 0, Rs = 1, nu = nv = n) and with roughconductor (Beckmann, alpha = sqrt(2 / (n + 2)),
the comparable lobe, perfect conductor: F = 1), alternately, after a warm-up; the script
prints the medians and the median of the per-pair time ratios (target: <= 1.1).

    python benchmarks/bench_as_vs_roughconductor.py [--runs 9] [--res 512] [--spp 64]
"""
import argparse
import json
import sys

import drjit as dr
import mitsuba as mi


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=9)
    ap.add_argument("--res", type=int, default=512)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--exponent", type=float, default=100.0)
    ap.add_argument("--integrator", default="direct", choices=("direct", "path"))
    ap.add_argument("--threads", type=int, default=0, help="Dr.Jit threads (0: all cores)")
    ap.add_argument("--json", help="also write the results to this file")
    args = ap.parse_args(argv)

    mi.set_variant("llvm_ad_rgb")
    if args.threads:
        dr.set_thread_count(args.threads)
    import mitsuba_brdfs  # noqa: F401
    from mitsuba_brdfs.progress import Progress
    from mitsuba_brdfs.timing import (beckmann_alpha_for_phong, kernel_stats, paired_times,
                                      sphere_scene, summary)

    n = args.exponent
    alpha = beckmann_alpha_for_phong(n)
    bsdfs = {
        "ashikhmin_shirley": {"type": "ashikhmin_shirley", "nu": n, "nv": n,
                              "specular_reflectance": 1.0, "diffuse_reflectance": 0.0},
        "roughconductor": {"type": "roughconductor", "distribution": "beckmann", "alpha": alpha},
        "roughconductor_nonvisible": {"type": "roughconductor", "distribution": "beckmann",
                                      "alpha": alpha, "sample_visible": False},
    }
    scenes = {k: sphere_scene(b, args.res, args.spp, args.integrator) for k, b in bsdfs.items()}
    stats = {k: kernel_stats(s) for k, s in scenes.items()}
    bar = Progress(args.runs, "paired runs")
    times = paired_times(scenes, runs=args.runs, progress=bar)
    bar.close()

    res = {"settings": vars(args) | {"alpha": alpha}, "kernels": stats, "times": times,
           "vs_roughconductor": summary(times, "ashikhmin_shirley", "roughconductor"),
           "vs_roughconductor_nonvisible": summary(times, "ashikhmin_shirley",
                                                   "roughconductor_nonvisible")}
    print(f"{args.res}x{args.res}, {args.spp} spp, {args.integrator}, n = {n:g} "
          f"(Beckmann alpha = {alpha:.4f}), {args.runs} paired runs after a warm-up")
    for k in scenes:
        m = sorted(times[k])[len(times[k]) // 2]
        print(f"  {k:28s} render median {m:7.3f} s   JIT compile (first render) "
              f"{stats[k]['compile_s']:6.3f} s")
    for key in ("vs_roughconductor", "vs_roughconductor_nonvisible"):
        s = res[key]
        print(f"ashikhmin_shirley / {key[3:]}: {s['ratio']:.3f} "
              f"(range {s['ratio_min']:.3f}-{s['ratio_max']:.3f})")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=2, default=str)
    return 0


if __name__ == "__main__":
    sys.exit(main())
