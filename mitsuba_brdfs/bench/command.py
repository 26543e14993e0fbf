"""The ``bench`` command: run the performance study (``study``) and write its report
(``report``)::

    python -m mitsuba_brdfs bench [--quick] [--out DIR] [--sections SECTION ...]

Writes ``performance.md`` and ``perf/`` into ``--out`` (default
``mitsuba_brdfs-out/bench/``; ``make docs-bench`` writes the repository's ``docs/``).
"""
import os

from ..arguments import default_out, nonnegative_int
from .study import FULL, QUICK, SECTIONS

__all__ = ["add_arguments", "run"]


def add_arguments(p):
    """The ``bench`` command's options."""
    p.add_argument("--quick", action="store_true",
                   help="a reduced run that checks the study works (about a minute of "
                        "CPU time: 2.5 min on 2 busy cores); its numbers are not the study's")
    p.add_argument("--out", default=default_out("bench"),
                   help="directory of performance.md; plots and results.json go to OUT/perf "
                        "(default: %(default)s/ in the current directory)")
    p.add_argument("--sections", nargs="+", choices=SECTIONS, default=list(SECTIONS),
                   metavar="SECTION", help="only these parts (they replace the same parts of "
                   "an earlier study of the same mode in OUT): " + ", ".join(SECTIONS))
    p.add_argument("--threads", type=nonnegative_int, default=0,
                   help="Dr.Jit threads (default: 0, all cores)")
    p.add_argument("-m", "--mode", "--variant", dest="variant", default="llvm_ad_rgb",
                   metavar="VARIANT", help="Mitsuba variant every section runs in, a JIT one "
                   "(default: %(default)s; cuda_ad_rgb on a GPU). fit-measured, which section "
                   "10 runs as a command, has no variant option and runs in llvm_ad_rgb")


def run(args):
    """Run the study (or some sections), merge, write the results and the document."""
    import drjit as dr

    from ..output import check_folder
    from ..variant import set_variant
    from . import report
    from .study import measure, merge, read_results, write_results
    check_folder(args.out)
    if not args.variant.startswith(("llvm_", "cuda_")):
        from ..arguments import UsageError
        raise UsageError(f"bench needs a JIT variant (llvm_* or cuda_*), not {args.variant!r}")
    set_variant(args.variant)
    if args.threads:
        dr.set_thread_count(args.threads)
    settings = QUICK if args.quick else FULL
    perf = os.path.join(args.out, "perf")
    path = os.path.join(perf, "results.json")
    new = measure(settings, tuple(args.sections))
    results = merge(read_results(path), new)
    write_results(results, path)
    report.write(results, args.out)
    print(report.console_summary(results))
    print(f"wrote {os.path.join(args.out, 'performance.md')} and {perf}/ "
          f"({new['total_seconds']:.0f} s)")
    return 0
