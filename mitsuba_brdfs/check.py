"""``python -m mitsuba_brdfs check SPEC``: the validation suite of this package on any BSDF.

SPEC is a plugin name (one of Mitsuba's, one of this package's, or one that a Python file
given with ``--load`` registers) or an XML file holding a ``<bsdf>`` (or a scene: then
every BSDF of its shapes is checked). The checks are those of
``mitsuba_brdfs.validate.suite``; each is printed with its numbers and PASS, FAIL, NOTE (a
property the BSDF lacks that was not asked for), SKIP (what was not checked, and why) or
WARN (what Mitsuba's integrators mask, with a count and an example: see the docstring of
``mitsuba_brdfs.validate.suite``).

Every variant is checked: a polarized one on the unpolarized part (the Mueller matrix's
[0, 0] element), a scalar one in its JIT twin and then compared with it call by call
(``validate.variants``).

Exit status: 0 when no check fails (warnings allowed, unless ``--strict``), 1 when one
does, 2 for a usage error (an unknown plugin, a bad ``-p``, a file that does not load).
Nothing is written unless ``--report DIR`` asks for a Markdown page with plots.

    python -m mitsuba_brdfs check roughplastic -p alpha=0.3
    python -m mitsuba_brdfs check mybsdf --load mybsdf.py --json
    python -m mitsuba_brdfs check scene.xml --quick --report check-report
"""
import dataclasses
import json
import shutil
import textwrap
import time

from .arguments import add_load
from .messages import last_line
from .output import check_folder, jsonable
from .spec import load_bsdfs, locate, parse_params
from .validate.report import write_report
from .validate.results import bsdf_record
from .variant import check_variant, run_file, set_variant

__all__ = ["suite_variant", "add_arguments", "run"]


def suite_variant(variant):
    """The variant the suite runs in for ``--variant VARIANT``: the variant itself, or for a
    scalar one its JIT twin (``validate.variants``); a ValueError says why not."""
    import mitsuba as mi
    from .validate.variants import jit_twin
    check_variant(variant)  # built into this Mitsuba, and its backend here
    if not variant.startswith("scalar_"):
        return variant
    twin = jit_twin(variant, mi.variants())
    if twin is None:
        raise ValueError(f"check runs a scalar variant's suite in its JIT twin (llvm_ad_"
                         f"{variant.removeprefix('scalar_')}), which this Mitsuba lacks")
    return twin


def add_arguments(p):
    from .validate.suite import CHECKS
    p.add_argument("spec", metavar="SPEC",
                   help="a BSDF plugin name (Mitsuba's, this package's, or one registered by "
                        "--load), or an XML file with a <bsdf> or a scene (every BSDF in it)")
    p.add_argument("-p", dest="params", action="append", default=[], metavar="KEY=VALUE",
                   help="a parameter of the plugin: a number is a float, r,g,b an rgb, "
                        "true/false a bool, anything else a string; for an XML file, the "
                        "value of a $KEY default (repeatable)")
    add_load(p)
    p.add_argument("--variant", default="llvm_ad_rgb",
                   help="Mitsuba variant (default: llvm_ad_rgb); polarized ones are checked on "
                        "the unpolarized part (the Mueller matrix's [0, 0] element), scalar ones "
                        "in their JIT twin and then compared with it")
    level = p.add_mutually_exclusive_group()
    level.add_argument("--quick", action="store_true",
                       help="fewer incidences and samples (about a second a BSDF)")
    level.add_argument("--thorough", action="store_true",
                       help="more incidences and samples, finer chi-square tests (about 10 s)")
    p.add_argument("--allow-gain", action="store_true",
                   help="an albedo above 1 is reported (NOTE), not a failure")
    p.add_argument("--reciprocal", action="store_true",
                   help="a BSDF that is not reciprocal fails (by default it is reported)")
    p.add_argument("--strict", action="store_true",
                   help="a warning (what Mitsuba's integrators mask) fails too")
    p.add_argument("--only", action="append", metavar="CHECK", choices=[c[0] for c in CHECKS],
                   help="run only this check (repeatable): " + ", ".join(c[0] for c in CHECKS))
    p.add_argument("--json", action="store_true",
                   help="print the results as JSON (nothing else on stdout)")
    p.add_argument("--report", metavar="DIR",
                   help="write DIR/check.md with chi-square histograms and albedo plots")


def _settings(args):
    from .validate.suite import SETTINGS
    level = "quick" if args.quick else "thorough" if args.thorough else "default"
    return level, dataclasses.replace(SETTINGS[level], allow_gain=args.allow_gain,
                                      reciprocal=args.reciprocal)


def _print_result(r, width):
    head = f"  {r.status:4s}  {r.name:<12s}"
    print(textwrap.fill(r.message, width=width, initial_indent=head,
                        subsequent_indent=" " * len(head)), flush=True)


def run(args):
    from .validate import suite
    params = parse_params(args.params)
    locate(args.spec)  # a file that is not there: refused before any work
    if args.report:
        try:
            import matplotlib  # noqa: F401  (checked before the checks run)
        except ImportError:
            raise ValueError("--report needs matplotlib (pip install matplotlib)") from None
        check_folder(args.report, f"--report {args.report}")
    twin = suite_variant(args.variant)
    scalar = twin != args.variant
    set_variant(twin)
    for path in args.load:
        run_file(path)
    bsdfs = load_bsdfs(args.spec, params)
    level, settings = _settings(args)
    width = max(60, min(shutil.get_terminal_size((110, 24)).columns, 120))
    show = None if args.json else (lambda r: _print_result(r, width))
    out = []
    t_all = time.perf_counter()
    for name, bsdf in bsdfs:
        if not args.json:
            where = f" (the suite in {twin}, then compared)" if scalar else ""
            if "polarized" in args.variant:
                where += (" on the unpolarized part (Mueller element [0, 0]; the other 15 "
                          "are not checked)")
            print(f"{name}: {bsdf.component_count()} component(s); variant {args.variant}"
                  f"{where}, {level} settings", flush=True)
        t0 = time.perf_counter()
        results = suite.run(bsdf, settings, name, only=args.only, on_result=show)
        out.append({"name": name, "checks": results, "seconds": time.perf_counter() - t0})
    if scalar:
        _compare_scalar(args, params, twin, bsdfs, out, show)
    records = [bsdf_record(b["name"], b["checks"], b["seconds"], args.strict) for b in out]
    for b, record in zip(out, records):
        b.update(passed=record["passed"], verdict=record["verdict"], seconds=record["seconds"])
        if not args.json:
            print(f"{b['name']}: {b['verdict']} in {b['seconds']:.1f} s", flush=True)
    passed = all(b["passed"] for b in out)
    if args.report:
        path = write_report(args, level, out)
        if not args.json:
            print(f"report: {path}")
    if args.json:
        doc = {"spec": args.spec, "variant": args.variant, "settings": level,
               "params": params, "strict": args.strict, "passed": passed,
               "seconds": round(time.perf_counter() - t_all, 2),
               "bsdfs": records}
        print(json.dumps(jsonable(doc), indent=2, allow_nan=False))
    return 0 if passed else 1


def _compare_scalar(args, params, twin, bsdfs, out, show):
    """The 'scalar' check of each BSDF: its values in the scalar variant against those in
    its JIT twin (``validate.variants``), appended to its results."""
    from .validate.suite import Result
    from .validate.variants import ScalarError, compare, evaluate, probe_inputs
    inputs = probe_inputs()
    jit = []
    for _, bsdf in bsdfs:
        try:
            jit.append(evaluate(bsdf, inputs))
        except Exception as e:  # noqa: BLE001  (it raised in the suite too: said there)
            jit.append(f"{type(e).__name__}: {last_line(e)}")
    set_variant(args.variant)
    for path in args.load:
        run_file(path)  # a Python plugin's class belongs to the variant it was defined in
    scalar_bsdfs = load_bsdfs(args.spec, params)
    for b, values, (_, bsdf) in zip(out, jit, scalar_bsdfs):
        t0 = time.perf_counter()
        n, m = len(inputs["wi"]), len(inputs["u1"])
        if isinstance(values, str):  # nothing to compare the scalar values with
            r = Result("scalar", "SKIP", {}, f"nothing to compare the scalar values with: in "
                       f"{twin} the same calls raised {values}")
            b["checks"].append(r)
            if show:
                show(r)
            continue
        try:
            diff = compare(values, evaluate(bsdf, inputs))
        except ScalarError as e:  # a plugin that raises in scalar only (a division by 0)
            r = Result("scalar", "FAIL", {}, f"{args.variant}: raised {e} (in {twin} the same "
                       f"calls did not)")
            b["checks"].append(r)
            if show:
                show(r)
            continue
        msg = (f"{args.variant} against {twin} on {n} direction pairs and {m} samples: largest "
               f"relative difference " + ", ".join(f"{v[1]:.2g} ({k})" for k, v in diff.items())
               + " (tolerance 1e-4)")
        off = {k: v[0] for k, v in diff.items() if v[0]}
        r = Result("scalar", "FAIL" if off else "PASS",
                   {k: {"off": v[0], "max_rel": v[1]} for k, v in diff.items()},
                   msg + (f"; off: {off}" if off else ""))
        r.numbers["seconds"] = round(time.perf_counter() - t0, 3)
        b["checks"].append(r)
        b["seconds"] += r.numbers["seconds"]
        if show:
            show(r)
