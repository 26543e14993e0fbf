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
import math
import os
import re
import shutil
import sys
import textwrap
import time

from .output import check_folder, save_figure, write_text
from .messages import explain_unknown, known_parameters, last_line, one_line, unknown_plugin
from .arguments import UsageError
from .variant import check_file, check_scene, check_variant, find_input, run_file, set_variant

__all__ = ["parse_value", "parse_params", "run_file", "load_bsdfs", "known_parameters",
           "explain_unknown", "write_report", "add_arguments", "run"]


def _number(text):
    """text as a float if it is a number written with digits (so "nan" and "inf" stay
    strings), else None."""
    try:
        x = float(text)
    except ValueError:
        return None
    return x if any(c.isdigit() for c in text) else None


def parse_value(text):
    """A ``-p`` value: a number is a float, ``r,g,b`` an RGB colour, ``true``/``false`` a
    bool, anything else a string."""
    x = _number(text)
    if x is not None:
        return x
    parts = [_number(p) for p in text.split(",")]
    if len(parts) == 3 and None not in parts:
        return {"type": "rgb", "value": parts}
    if text.lower() in ("true", "false"):
        return text.lower() == "true"
    return text


def parse_params(items):
    """``KEY=VALUE`` strings -> {key: raw string}; a malformed one is a ValueError."""
    out = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise ValueError(f"bad -p {item!r}: expected KEY=VALUE (e.g. -p alpha=0.2, "
                             f"-p reflectance=0.8,0.2,0.1, -p distribution=ggx)")
        out[key.strip()] = value.strip()
    return out


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


def _plugin_type(bsdf, types):
    """The plugin name of a BSDF: this package's ``NAME``, else the one of ``types`` (the
    plugin types named in the file) that builds an object of the same class."""
    import mitsuba as mi
    name = getattr(bsdf, "NAME", None)
    if name:
        return name
    for t in types:
        try:
            other = mi.load_dict({"type": t})
        except Exception:  # noqa: BLE001  (a plugin that needs parameters to load)
            continue
        if type(other) is type(bsdf) and other.class_name() == bsdf.class_name():
            return t
    return bsdf.class_name()


def _black_default(bsdf):
    """Whether ``bsdf`` is the black diffuse Mitsuba gives a light-emitting shape that has no
    BSDF of its own."""
    text = " ".join(str(bsdf).split())
    return bsdf.class_name() == "SmoothDiffuse" and "reflectance = UniformSpectrum[value=[0]]" in text


def _shapes(scene):
    """(where, shape) of the shapes of a scene: "shape 'id'", or "shape K" for the K-th of
    ``scene.shapes()``; then those of its shape groups ("shape K of group 'g'"), which
    ``scene.shapes()`` does not list, and without their instances: an instance's
    ``bsdf()`` is the grey diffuse Mitsuba gives every shape by default, not the user's."""
    import mitsuba as mi
    out = [(k, shape) for k, shape in enumerate(scene.shapes())
           if shape.class_name() != "Instance"]
    groups = []

    class Walk(mi.TraversalCallback):
        def __init__(self, into):
            super().__init__()
            self.into = into

        def put(self, name, value, *rest):
            if isinstance(value, mi.Shape) and value.class_name() == "ShapeGroupPlugin":
                members = []
                value.traverse(Walk(members))
                groups.append((value.id() or name, members))
            elif isinstance(value, mi.Shape) and self.into is not None:
                self.into.append(value)

    try:
        scene.traverse(Walk(None))
    except Exception:  # noqa: BLE001  (a traversal this Mitsuba refuses: the plain list)
        groups = []
    named = [(f"shape '{shape.id()}'" if shape.id() else f"shape {k}", shape) for k, shape in out]
    for group, members in groups:
        named += [(f"shape '{shape.id()}'" if shape.id() else f"shape {k} of group '{group}'",
                   shape) for k, shape in enumerate(members)]
    return named


def _name(bsdf, fallback, types=()):
    """How a BSDF is called in the output: its id, or its plugin type and ``fallback`` (the
    shape that holds it), e.g. "lambert (shape 0)"."""
    if bsdf.id():
        return bsdf.id()
    return f"{_plugin_type(bsdf, types)} ({fallback})"


def load_bsdfs(spec, params):
    """The BSDFs SPEC names, as (name, BSDF) pairs: the plugin with params (raw strings,
    read with ``parse_value``), or those of an XML file (params fill its ``$name``
    defaults). What cannot be loaded is a ValueError in one line: a folder, an empty or
    malformed file, an unknown plugin (with the closest name), a scene whose shapes lack a
    BSDF (Mitsuba would give them a default diffuse, which is not the user's)."""
    import mitsuba as mi
    if os.path.isdir(spec):
        raise UsageError(f"{spec}: is a folder, not a plugin name or an XML file")
    if spec.lower().endswith(".xml"):
        spec = find_input(spec)
    if spec.lower().endswith(".xml") or os.path.isfile(spec):
        check_file(spec, "")
        try:
            obj = mi.load_file(spec, **params)
        except Exception as e:
            # check's -p gives the file's $KEY defaults, as render's -D does
            reason = one_line(str(e)).replace("(a -D KEY=VALUE", "(a -p KEY=VALUE")
            raise ValueError(reason if reason.startswith((spec, os.path.basename(spec)))
                             else f"{spec} does not load: {reason}") from None
        if isinstance(obj, mi.BSDF):
            return [(_name(obj, os.path.basename(spec)), obj)]
        if not isinstance(obj, mi.Scene):
            raise ValueError(f"{spec} holds a {type(obj).__name__}, not a <bsdf> or a scene")
        check_scene(obj, spec, params, render=False)
        found = []
        with open(spec, errors="replace") as f:
            types = list(dict.fromkeys(re.findall(r'<bsdf\b[^>]*\btype="(\w+)"', f.read())))
        for where, shape in _shapes(obj):
            b = shape.bsdf()
            if shape.is_emitter() and _black_default(b):  # an area light's, not the user's
                continue
            if b is not None and not any(b is f for _, f in found):
                found.append((_name(b, where, types), b))
        if not found:
            raise ValueError(f"{spec}: the scene has no shape, so no BSDF to check")
        return found
    try:
        obj = mi.load_dict({"type": spec, **{k: parse_value(v) for k, v in params.items()}})
    except Exception as e:
        message = str(e)
        if "not found" in message and "Plugin" in message:
            raise ValueError(f"{unknown_plugin(spec, 'bsdf')}: neither Mitsuba's nor this "
                             f"package's (a plugin of your own: --load FILE.py registers it)"
                             ) from None
        reason = one_line(message)
        raise ValueError(reason if reason.startswith(f"{spec}:") else f"{spec}: {reason}"
                         ) from None
    if not isinstance(obj, mi.BSDF):
        raise ValueError(f"{spec!r} is a {type(obj).__name__} plugin, not a BSDF")
    return [(spec, obj)]


def add_arguments(p):
    from .validate.suite import CHECKS
    p.add_argument("spec", metavar="SPEC",
                   help="a BSDF plugin name (Mitsuba's, this package's, or one registered by "
                        "--load), or an XML file with a <bsdf> or a scene (every BSDF in it)")
    p.add_argument("-p", dest="params", action="append", default=[], metavar="KEY=VALUE",
                   help="a parameter of the plugin: a number is a float, r,g,b an rgb, "
                        "true/false a bool, anything else a string; for an XML file, the "
                        "value of a $KEY default (repeatable)")
    p.add_argument("--load", action="append", default=[], metavar="FILE.py",
                   help="run this Python file once the variant is set, e.g. to register a "
                        "plugin with mi.register_bsdf (repeatable)")
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


def _jsonable(x):
    """Numbers as JSON holds them: NumPy scalars and arrays as Python ones, non-finite
    floats as the strings "inf", "-inf", "nan"."""
    import numpy as np
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [_jsonable(v) for v in (x.tolist() if isinstance(x, np.ndarray) else x)]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else str(float(x))
    return x


def _print_result(r, width):
    head = f"  {r.status:4s}  {r.name:<12s}"
    print(textwrap.fill(r.message, width=width, initial_indent=head,
                        subsequent_indent=" " * len(head)), flush=True)


def run(args):
    from .validate import suite
    params = parse_params(args.params)
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
    for b in out:
        ok, verdict = suite.summary(b["checks"], strict=args.strict)
        b.update(passed=ok, verdict=verdict, seconds=round(b["seconds"], 2),
                 warnings=sum(len(r.warnings) for r in b["checks"]))
        if not args.json:
            print(f"{b['name']}: {verdict} in {b['seconds']:.1f} s", flush=True)
    passed = all(b["passed"] for b in out)
    if args.report:
        path = write_report(args, level, out)
        if not args.json:
            print(f"report: {path}")
    if args.json:
        doc = {"spec": args.spec, "variant": args.variant, "settings": level,
               "params": params, "strict": args.strict, "passed": passed,
               "seconds": round(time.perf_counter() - t_all, 2),
               "bsdfs": [{**b, "checks": [r.as_dict() for r in b["checks"]]} for b in out]}
        print(json.dumps(_jsonable(doc), indent=2, allow_nan=False))
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


# -- the report --------------------------------------------------------------------------------

def _slug(name):
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name) or "bsdf"


def _plot_chi2(result, path):
    """Observed and expected histograms and their difference, one row per incidence."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    data = result.data
    fig, axs = plt.subplots(len(data), 3, figsize=(11, 2.3 * len(data) + 0.4), squeeze=False)
    for row, (theta, d) in zip(axs, sorted(data.items())):
        h, e = d["histogram"], d["expected"]
        n = h.shape[0]  # rows: cos(theta_o) from 1 down to -1
        top = (n + 1) // 2  # the rows that reach above the horizon
        extent = [-180, 180, -1, 1]
        if not (h[top:].any() or e[top:].any()):  # nothing below the surface: show above
            h, e, extent = h[:top], e[:top], [-180, 180, 1 - 2 * top / n, 1]
        elif not (h[:n - top].any() or e[:n - top].any()):  # nothing above: show below
            h, e, extent = h[n - top:], e[n - top:], [-180, 180, -1, 2 * top / n - 1]
        vmax = max(float(h.max()), float(e.max()), 1e-9)
        diff = h - e
        lim = max(float(abs(diff).max()), 1e-9)
        for ax, img, title, kw in (
                (row[0], h, "sampled (histogram)", dict(vmin=0, vmax=vmax)),
                (row[1], e, "expected (pdf integrated)", dict(vmin=0, vmax=vmax)),
                (row[2], diff, "difference", dict(vmin=-lim, vmax=lim, cmap="coolwarm"))):
            im = ax.imshow(img, extent=extent, aspect="auto", interpolation="nearest", **kw)
            ax.set_title(f"theta_i = {theta:g} deg: {title}"
                         + (f", p = {d['p_value']:.2g}" if ax is row[2] else ""), fontsize=8)
            ax.set_xlabel("phi (deg)", fontsize=7)
            ax.set_ylabel("cos(theta_o)", fontsize=7)
            ax.tick_params(labelsize=6)
            fig.colorbar(im, ax=ax, fraction=0.046, pad=0.02).ax.tick_params(labelsize=6)
    fig.tight_layout()
    save_figure(fig, path, dpi=90)
    plt.close(fig)


def _plot_albedo(result, path):
    """Mean sample weight (with 4 standard errors) and quadrature against incidence."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    d = result.data
    order = np.argsort(d["theta"])  # a two-sided BSDF's incidences from below come last
    theta = np.asarray(d["theta"])[order]
    fig, ax = plt.subplots(figsize=(6, 3.6))
    a, err, q = d["albedo"][order], d["stderr"][order], d["quadrature"][order]
    grey = (a == a[:, :1]).all() and (q == q[:, :1]).all()
    channels = 1 if grey else a.shape[1]
    for c in range(channels):
        label = "" if grey else " (" + ("RGB"[c] if channels == 3 else f"channel {c}") + ")"
        color = "tab:blue" if grey or channels != 3 else ("tab:red", "tab:green", "tab:blue")[c]
        ax.errorbar(theta, a[:, c], yerr=4 * err[:, c], fmt="o", ms=3, color=color,
                    label=f"mean sample weight{label}")
        ax.plot(theta, q[:, c], "-", lw=1, color=color, alpha=0.6,
                label=f"quadrature of eval{label}")
    ax.axhline(1, color="k", lw=0.8, ls="--")
    ax.set_xlabel("theta_i (deg" + ("; above 90: lit from below)" if theta.max() > 90 else ")"))
    ax.set_ylabel("albedo")
    ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    save_figure(fig, path, dpi=100)
    plt.close(fig)


def write_report(args, level, out):
    """DIR/check.md: the results of every BSDF with its chi-square histograms and albedo
    curve (PNG files beside it). Returns the page's path."""
    os.makedirs(args.report, exist_ok=True)
    cmd = "python -m mitsuba_brdfs check " + " ".join(sys.argv[2:] if sys.argv[1:2] == ["check"]
                                                      else [args.spec])
    lines = [f"# check: {args.spec}", "", f"`{cmd}`", "",
             f"Variant {args.variant}, {level} settings.", ""]
    for b in out:
        slug = _slug(b["name"])
        lines += [f"## {b['name']}: {b['verdict']}", "", "| status | check | what it measured |",
                  "|---|---|---|"]
        for r in b["checks"]:
            lines.append(f"| {r.status} | {r.name} | {r.message.replace('|', chr(92) + '|')} |")
        lines.append("")
        by_name = {r.name: r for r in b["checks"]}
        if "furnace" in by_name and by_name["furnace"].data:
            _plot_albedo(by_name["furnace"], os.path.join(args.report, f"{slug}_albedo.png"))
            lines += ["Albedo against incidence: the mean sample weight (4 standard errors) "
                      "and the quadrature of eval.", "", f"![albedo]({slug}_albedo.png)", ""]
        if "chi2" in by_name and by_name["chi2"].data:
            _plot_chi2(by_name["chi2"], os.path.join(args.report, f"{slug}_chi2.png"))
            lines += ["Chi-square tests: the sampled directions, the pdf integrated over the "
                      "same cells, and their difference, over cos(theta_o) and phi_o.", "",
                      f"![chi-square]({slug}_chi2.png)", ""]
    path = os.path.join(args.report, "check.md")
    write_text(path, "\n".join(lines))
    return path
