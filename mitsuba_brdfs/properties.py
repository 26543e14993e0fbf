"""The property table: what every model does with energy, reciprocity and sampling, measured.

For every model and form at a few parameter settings this computes

- the directional albedo over the incidence angle (white furnace: the mean sampled weight,
  which is the integral of f cos over the hemisphere whatever the sampler);
- the largest relative reciprocity error |f(a, b) - f(b, a)| / max(f) over random pairs;
- the fraction of samples that the sampler wastes below the horizon (half-vector samplers
  reflect about h and may leave the hemisphere; those samples carry zero weight);
- the sampling efficiency: the relative variance var(w) / E[w]^2 of the sampled weight
  (0 = perfect importance sampling);

and writes ``properties.md``, ``albedo.png`` (albedo vs incidence, all models) and
``lobes/<plugin>.png`` (eval in the plane of incidence, polar, at 3 incidences) into
``--out`` (default ``mitsuba_brdfs-out/properties/``; ``make docs`` writes the repository's
``docs/``).

    python -m mitsuba_brdfs properties [--samples N] [--out DIR]
"""
import math
import os

from .validate.probe import load_bsdf
from .validate.properties import THETAS_DEG, draw_albedo, draw_lobes, measure

__all__ = ["CONFIGS", "configs", "add_arguments", "run"]

#: every file is written whole (``output.atomic``): an interruption can say what was written
WRITES_ATOMICALLY = True


def configs():
    """(plugin, label, parameters) of every model's ``properties`` (``core.facts``): 2-3
    settings per model and form, white colours so that the albedo is the model's own (a
    reflectance of 1 where the model allows it)."""
    from .core.facts import in_folder, label
    from .models import facts
    from .paths import SCENES
    return [(plugin, label(plugin, suffix), in_folder(params, SCENES))
            for plugin, f in facts().items() for suffix, params in f.properties]


#: every row of the table
CONFIGS = configs()


def _fmt(x, digits=3):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if x != 0 and (abs(x) < 1e-3 or abs(x) >= 1e4):
        return f"{x:.1e}"
    return f"{x:.{digits}f}"


def write_markdown(rows, path, samples):
    lines = [
        "# Model properties, measured",
        "",
        f"Written by `python -m mitsuba_brdfs properties` ({samples} samples per incidence; "
        "white or stated reflectances). Nothing here is asserted: each number comes from the "
        "plugins as they are.",
        "",
        "- **albedo**: directional albedo (white furnace, the mean sampled weight) at normal, "
        "60 deg and 85 deg incidence, and its maximum over incidence. Above 1 (beyond the "
        "Monte Carlo error of ~0.01) the model creates energy.",
        "- **reciprocity**: max |f(a,b) - f(b,a)| / max f over 20000 random pairs.",
        "- **below horizon**: fraction of samples drawn below the surface (zero weight, wasted) "
        "at 0 / 60 / 85 deg incidence.",
        "- **rel. variance**: var(w) / E[w]^2 of the sampled weight at 45 deg (0 = perfect "
        "importance sampling, lower is better).",
        "",
        "![albedo vs incidence](albedo.png)",
        "",
        "| model | albedo 0 | albedo 60 | albedo 85 | max albedo | energy | reciprocity | "
        "below horizon 0/60/85 | rel. variance |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    idx = {int(t): i for i, t in enumerate(THETAS_DEG)}
    for r in rows:
        a = r["albedo"]
        energy = "conserves" if r["albedo_max"] <= 1.01 else "**creates**"
        b = r["below_horizon"]
        lines.append(
            f"| `{r['label']}` | {_fmt(a[idx[0]])} | {_fmt(a[idx[60]])} | {_fmt(a[idx[85]])} | "
            f"{_fmt(r['albedo_max'])} | {energy} | {_fmt(r['reciprocity'])} | "
            f"{_fmt(b[0], 2)} / {_fmt(b[60], 2)} / {_fmt(b[85], 2)} | {_fmt(r['rel_var_45'])} |")
    lines += ["", "## Lobes", "",
              "eval = f cos(theta_o) in the plane of incidence (polar: the radius is the value, "
              "normalised per plot; the light comes from the left, the mirror direction is on the "
              "right), at 0, 30 and 60 deg incidence.", ""]
    for plugin in dict.fromkeys(r["plugin"] for r in rows):
        lines.append(f"![{plugin}](lobes/{plugin}.png)")
    from .output import write_text
    write_text(path, "\n".join(lines) + "\n")


def plot_albedo(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    families = list(dict.fromkeys(r["plugin"] for r in rows))
    cols = 3
    nrows = (len(families) + cols - 1) // cols
    fig, axes = plt.subplots(nrows, cols, figsize=(4.6 * cols, 4.4 * nrows), squeeze=False,
                             layout="constrained")
    for ax, fam in zip(axes.flat, families):
        draw_albedo(ax, [r for r in rows if r["plugin"] == fam], fam)
    for ax in list(axes.flat)[len(families):]:
        ax.axis("off")
    from .output import save_figure
    save_figure(fig, path, dpi=90, format="png")
    plt.close(fig)


def plot_lobes(rows, out_dir):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .output import save_figure
    by_plugin = {}
    for plugin, label, params in CONFIGS:
        if plugin in {r["plugin"] for r in rows}:
            by_plugin.setdefault(plugin, []).append((label, params))
    for plugin, cfgs in by_plugin.items():
        # at most 4 lobes in a row (the family forms / distributions wrap)
        cols = len(cfgs) if len(cfgs) <= 4 else (3 if len(cfgs) % 3 == 0 else 4)
        nrows = (len(cfgs) + cols - 1) // cols
        fig, axes = plt.subplots(nrows, cols, subplot_kw={"projection": "polar"},
                                 figsize=(3.3 * cols, 2.6 * nrows), squeeze=False)
        for ax in list(axes.flat)[len(cfgs):]:
            ax.axis("off")
        for ax, (label, params) in zip(axes.flat, cfgs):
            draw_lobes(ax, load_bsdf(plugin, **params), label[len(plugin):].strip() or label)
        axes.flat[0].legend(fontsize=7, loc="lower left")
        fig.suptitle(plugin, fontsize=10)
        fig.tight_layout()
        save_figure(fig, os.path.join(out_dir, f"{plugin}.png"), dpi=80, format="png")
        plt.close(fig)


def add_arguments(p):
    from .arguments import default_out, positive_int
    plugins = sorted({c[0] for c in CONFIGS})
    p.add_argument("--samples", type=positive_int, default=1 << 18,
                   help="samples per incidence angle (default: %(default)s)")
    p.add_argument("--out", default=default_out("properties"),
                   help="directory of properties.md, albedo.png and lobes/ "
                        "(default: %(default)s/ in the current directory)")
    p.add_argument("--only", nargs="+", metavar="PLUGIN", choices=plugins,
                   help="only these plugins: " + ", ".join(plugins))


def run(args):
    import mitsuba as mi
    from .output import check_folder
    from .variant import set_variant
    check_folder(args.out)
    set_variant("llvm_ad_rgb" if mi.variant() is None else mi.variant())
    configs = [c for c in CONFIGS if not args.only or c[0] in args.only]
    rows = measure(args.samples, configs)
    write_markdown(rows, os.path.join(args.out, "properties.md"), args.samples)
    plot_albedo(rows, os.path.join(args.out, "albedo.png"))
    plot_lobes(rows, os.path.join(args.out, "lobes"))
    for r in rows:
        print(f"{r['label']:45s} max albedo {r['albedo_max']:.3f}  reciprocity "
              f"{r['reciprocity']:.1e}  rel.var {r['rel_var_45']:.3g}")
    return 0
