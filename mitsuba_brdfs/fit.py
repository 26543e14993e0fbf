"""``python -m mitsuba_brdfs fit``: recovering Ashikhmin-Shirley parameters from an image by
differentiable rendering (the fit itself: ``image_fit``)::

    python -m mitsuba_brdfs fit [--iterations 200] [--spp 8] [--res 64] [--out DIR]

Writes ``loss.png`` (loss and parameters per iteration) and ``before_target_after.png`` into
``--out`` (default ``mitsuba_brdfs-out/fit/``) and prints the values it ends with.
"""
import statistics

from .arguments import default_out
from .image_fit import ITERATIONS, RES, SPP, fit

__all__ = ["add_arguments", "run"]

#: every file is written whole (``output.atomic``): an interruption can say what was written
WRITES_ATOMICALLY = True


# -- command line -----------------------------------------------------------------------

def add_arguments(p):
    from .arguments import int_range, positive_int
    p.add_argument("--iterations", type=positive_int, default=ITERATIONS,
                   help="Adam steps (default: %(default)s)")
    p.add_argument("--spp", type=positive_int, default=SPP,
                   help="samples per pixel of each render during the fit (default: %(default)s)")
    p.add_argument("--res", type=int_range(2), default=RES,
                   help="image width and height (default: %(default)s)")
    p.add_argument("--out", default=default_out("fit"),
                   help="directory of loss.png and before_target_after.png "
                        "(default: %(default)s/ in the current directory)")
    p.add_argument("--variant", default="llvm_ad_rgb",
                   help="a differentiable Mitsuba variant (default: llvm_ad_rgb)")
    p.add_argument("--no-freeze", dest="freeze", action="store_false",
                   help="trace the render at every iteration instead of replaying the "
                        "recorded one (@dr.freeze); slower, for comparison")


def run(args):
    from .output import check_folder
    from .progress import advance, progress_bar
    from .variant import set_variant
    if "_ad_" not in args.variant:
        raise ValueError(f"fit needs a differentiable variant (*_ad_*), got {args.variant!r}")
    check_folder(args.out)
    set_variant(args.variant)
    with progress_bar(args.iterations, "fit") as bar:
        # fit() reports each iteration in a line: "iteration i/n  loss ...  nu ..."
        r = fit(args.iterations, args.spp, args.res, args.out, freeze=args.freeze,
                progress=lambda line: advance(bar, 1, line[line.find("loss"):]))
    f, t, e = r["final"], r["true"], r["errors"]
    per_it = 1e3 * statistics.median(r["history"]["seconds"])
    how = (f"frozen, recorded {r['recordings']} time{'s' if r['recordings'] != 1 else ''}"
           if r["frozen"] else "not frozen")
    print(f"after {r['iterations']} iterations ({r['seconds']:.1f} s, median "
          f"{per_it:.1f} ms per iteration, {how}): "
          f"nu {f['nu']:.3f} (true {t['nu']:g}, {100 * e['nu']:.2f}% off), "
          f"nv {f['nv']:.3f} (true {t['nv']:g}, {100 * e['nv']:.2f}% off), "
          f"Rs {f['rs']:.4f} (true {t['rs']:g}, {100 * e['rs']:.2f}% off)")
    print(f"loss against the target: {r['loss_before']:.4e} at the start, "
          f"{r['loss_after']:.4e} at the end")
    print("wrote " + " and ".join(r["outputs"]))
    return 0
