"""``python -m mitsuba_brdfs check SPEC``: the validation suite of this package on any BSDF.

SPEC is a plugin name (one of Mitsuba's, one of this package's, or one that a Python file
given with ``--load`` registers) or an XML file holding a ``<bsdf>`` (or a scene: then
every BSDF of its shapes is checked). The checks are those of
``mitsuba_brdfs.validate.suite``; each is printed with its numbers and PASS, FAIL, NOTE (a
property the BSDF lacks that was not asked for) or SKIP (what was not checked, and why).

Exit status: 0 when no check fails, 1 when one does, 2 for a usage error (an unknown
plugin, a bad ``-p``, a file that does not load). Nothing is written unless ``--report DIR``
asks for a Markdown page with plots.

    python -m mitsuba_brdfs check roughplastic -p alpha=0.3
    python -m mitsuba_brdfs check mybsdf --load mybsdf.py --json
    python -m mitsuba_brdfs check scene.xml --quick --report check-report
"""
import dataclasses
import json
import math
import os
import shutil
import sys
import textwrap
import time

from .output import save_figure, write_text
from .variant import check_variant, run_file, set_variant

__all__ = ["parse_value", "parse_params", "run_file", "load_bsdfs", "write_report",
           "add_arguments", "run"]


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


def _check_jit(variant):
    """Refuse a variant the checks cannot run in (they need an unpolarized JIT one)."""
    check_variant(variant)  # built into this Mitsuba, and its backend here
    if not variant.startswith(("llvm_", "cuda_")) or "polarized" in variant:
        raise ValueError(f"check needs an unpolarized JIT variant (llvm_ad_rgb, "
                         f"llvm_ad_spectral, cuda_ad_rgb, ...), not {variant!r}")


def _last_line(e):
    lines = [ln.strip() for ln in str(e).splitlines() if ln.strip()]
    return lines[-1] if lines else ""


def _name(bsdf, fallback):
    return bsdf.id() or fallback


def load_bsdfs(spec, params):
    """The BSDFs SPEC names, as (name, BSDF) pairs: the plugin with params (raw strings,
    read with ``parse_value``), or those of an XML file (params fill its ``$name``
    defaults)."""
    import mitsuba as mi
    if spec.lower().endswith(".xml") or os.path.isfile(spec):
        if not os.path.isfile(spec):
            raise FileNotFoundError(f"{spec}: no such file")
        try:
            obj = mi.load_file(spec, **params)
        except Exception as e:
            raise ValueError(f"{spec} does not load: {_last_line(e)}") from None
        if isinstance(obj, mi.BSDF):
            return [(_name(obj, os.path.basename(spec)), obj)]
        if not isinstance(obj, mi.Scene):
            raise ValueError(f"{spec} holds a {type(obj).__name__}, not a <bsdf> or a scene")
        found = []
        for k, shape in enumerate(obj.shapes()):
            b = shape.bsdf()
            if b is not None and not any(b is f for _, f in found):
                found.append((_name(b, shape.id() or f"shape {k}"), b))
        if not found:
            raise ValueError(f"{spec}: the scene has no BSDF")
        return found
    try:
        obj = mi.load_dict({"type": spec, **{k: parse_value(v) for k, v in params.items()}})
    except Exception as e:
        message = str(e)
        if "not found" in message and "Plugin" in message:
            raise ValueError(f"unknown plugin {spec!r}: neither Mitsuba's nor this package's "
                             f"(a plugin of your own: --load FILE.py registers it)") from None
        raise ValueError(f"{spec}: {_last_line(e)}") from None
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
                   help="Mitsuba variant (default: llvm_ad_rgb)")
    level = p.add_mutually_exclusive_group()
    level.add_argument("--quick", action="store_true",
                       help="fewer incidences and samples (about a second a BSDF)")
    level.add_argument("--thorough", action="store_true",
                       help="more incidences and samples, finer chi-square tests (about 10 s)")
    p.add_argument("--allow-gain", action="store_true",
                   help="an albedo above 1 is reported (NOTE), not a failure")
    p.add_argument("--reciprocal", action="store_true",
                   help="a BSDF that is not reciprocal fails (by default it is reported)")
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
    _check_jit(args.variant)
    set_variant(args.variant)
    for path in args.load:
        run_file(path)
    bsdfs = load_bsdfs(args.spec, params)
    level, settings = _settings(args)
    width = max(60, min(shutil.get_terminal_size((110, 24)).columns, 120))
    out = []
    t_all = time.perf_counter()
    for name, bsdf in bsdfs:
        if not args.json:
            print(f"{name}: {bsdf.component_count()} component(s); variant {args.variant}, "
                  f"{level} settings", flush=True)
        t0 = time.perf_counter()
        results = suite.run(bsdf, settings, name, only=args.only,
                            on_result=None if args.json else (lambda r: _print_result(r, width)))
        seconds = time.perf_counter() - t0
        failed = [r.name for r in results if not r.passed]
        out.append({"name": name, "passed": not failed, "seconds": round(seconds, 2),
                    "checks": results})
        if not args.json:
            verdict = (f"FAIL ({len(failed)} of {len(results)} checks failed: "
                       f"{', '.join(failed)})" if failed else
                       f"PASS ({len(results)} checks)")
            print(f"{name}: {verdict} in {seconds:.1f} s", flush=True)
    passed = all(b["passed"] for b in out)
    if args.report:
        path = write_report(args, level, out)
        if not args.json:
            print(f"report: {path}")
    if args.json:
        doc = {"spec": args.spec, "variant": args.variant, "settings": level,
               "params": params, "passed": passed,
               "seconds": round(time.perf_counter() - t_all, 2),
               "bsdfs": [{**b, "checks": [r.as_dict() for r in b["checks"]]} for b in out]}
        print(json.dumps(_jsonable(doc), indent=2, allow_nan=False))
    return 0 if passed else 1


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
        verdict = "PASS" if b["passed"] else "FAIL"
        lines += [f"## {b['name']}: {verdict}", "", "| status | check | what it measured |",
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
