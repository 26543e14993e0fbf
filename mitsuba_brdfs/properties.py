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

import numpy as np

__all__ = ["CONFIGS", "configs", "measure", "draw_albedo", "draw_lobes", "add_arguments", "run"]

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

THETAS_DEG = np.array([0, 10, 20, 30, 40, 50, 60, 70, 75, 80, 85, 89], dtype=float)


def _bsdf(plugin, params):
    import mitsuba as mi
    d = {"type": plugin}
    for k, v in params.items():
        d[k] = v
    return mi.load_dict(d)


def _interaction(wi):
    import drjit as dr
    import mitsuba as mi
    si = dr.zeros(mi.SurfaceInteraction3f, dr.width(wi))
    si.wi = wi
    si.uv = mi.Point2f(0.5, 0.5)
    return si


def _dirs(theta, phi):
    import mitsuba as mi
    st = np.sin(theta)
    return mi.Vector3f(st * np.cos(phi), st * np.sin(phi), np.cos(theta) + 0 * phi)


def sample_stats(bsdf, theta, n, seed=0):
    """(albedo, relative variance of the weight, fraction of samples below the horizon)."""
    import mitsuba as mi
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(seed, n)
    wi = _dirs(np.full(n, theta), np.zeros(n))
    bs, w = bsdf.sample(mi.BSDFContext(), _interaction(wi), sampler.next_1d(), sampler.next_2d())
    w = np.array(w).T.mean(axis=1)
    below = np.array(bs.wo.z) <= 0
    mean = float(w.mean())
    var = float(w.var())
    return mean, (var / mean ** 2 if mean > 0 else math.nan), float(below.mean())


def reciprocity_error(bsdf, n=20000, seed=1):
    """max |f(a, b) - f(b, a)| / max f over random direction pairs (f = eval / cos)."""
    import mitsuba as mi
    rng = np.random.default_rng(seed)
    ta, tb = np.arccos(rng.uniform(0.05, 1, n)), np.arccos(rng.uniform(0.05, 1, n))
    pa, pb = rng.uniform(0, 2 * np.pi, (2, n))
    a, b = _dirs(ta, pa), _dirs(tb, pb)
    ctx = mi.BSDFContext()
    fab = np.array(bsdf.eval(ctx, _interaction(a), b)).T.mean(axis=1) / np.cos(tb)
    fba = np.array(bsdf.eval(ctx, _interaction(b), a)).T.mean(axis=1) / np.cos(ta)
    scale = max(np.abs(fab).max(), 1e-30)
    return float(np.abs(fab - fba).max() / scale)


def lobe_curve(bsdf, theta_i, m=361):
    """eval (f cos) in the plane of incidence: outgoing angle in [-90, 90] deg -> value."""
    import mitsuba as mi
    to = np.linspace(-np.pi / 2, np.pi / 2, m)
    wi = _dirs(np.full(m, theta_i), np.zeros(m))
    # the viewer on the mirror side has phi = pi: signed angle, mirror at -theta_i... we put
    # the mirror direction at +theta_i (phi = pi for the outgoing side)
    wo = _dirs(np.abs(to), np.where(to >= 0, np.pi, 0.0))
    f = np.array(bsdf.eval(mi.BSDFContext(), _interaction(wi), wo)).T.mean(axis=1)
    return to, f


def measure(samples=1 << 18, configs=None, progress=True):
    """Run every measurement; returns a list of dicts (one per configuration)."""
    from .progress import advance, progress_bar
    configs = configs or CONFIGS
    rows = []
    with progress_bar(len(configs), "properties", enabled=progress) as bar:
        for plugin, label, params in configs:
            bsdf = _bsdf(plugin, params)
            stats = [sample_stats(bsdf, math.radians(t), samples, seed=k)
                     for k, t in enumerate(THETAS_DEG)]
            alb = np.array([s[0] for s in stats])
            rows.append({
                "plugin": plugin, "label": label, "params": params,
                "albedo": alb.tolist(),
                "albedo_max": float(alb.max()),
                "rel_var_45": sample_stats(bsdf, math.radians(45), samples, seed=99)[1],
                "below_horizon": {int(t): s[2] for t, s in zip(THETAS_DEG, stats) if t in (0, 60, 85)},
                "reciprocity": reciprocity_error(bsdf),
            })
            advance(bar, 1, label)
    return rows


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


def _styles(labels):
    """(colour, line style) per label: colour by its first word's first part (form,
    distribution), line style by the rest, so a dozen curves stay tellable apart."""
    heads = [lab.split(" ")[0].split("/")[0] if lab else "" for lab in labels]
    tails = [lab[len(h):] for lab, h in zip(labels, heads)]
    uh, ut = list(dict.fromkeys(heads)), list(dict.fromkeys(tails))
    if len(uh) == 1:  # one form: colours tell the settings apart
        uh, heads, ut, tails = ut, tails, [""], [""] * len(labels)
    colours = [f"C{uh.index(h) % 10}" for h in heads]
    dashes = ["-", "--", ":", "-."]
    return list(zip(colours, [dashes[ut.index(t) % 4] for t in tails]))


def draw_albedo(ax, rows, title):
    """Albedo against incidence of ``rows`` (one plugin's, from ``measure``) on ``ax``."""
    labels = [r["label"][len(r["plugin"]):].strip() for r in rows]
    for r, lab, (colour, dash) in zip(rows, labels, _styles(labels)):
        ax.plot(THETAS_DEG, r["albedo"], marker=".", color=colour, ls=dash,
                label=lab or r["plugin"])
    ax.axhline(1.0, color="k", lw=0.6, ls="--")
    ax.set_title(title)
    ax.set_ylim(bottom=0)
    ax.set_xlabel("incidence (deg)")
    ax.set_ylabel("albedo")
    # below the axes, so no curve is hidden
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16),
              ncol=2 if len(rows) > 3 else 1, frameon=False, handlelength=3.5)


def draw_lobes(ax, bsdf, title, incidences=(0, 30, 60)):
    """eval in the plane of incidence at a few incidences on the polar axes ``ax`` (each
    curve normalised to its maximum; the light direction dashed in the curve's colour)."""
    for ti in incidences:
        to, f = lobe_curve(bsdf, math.radians(ti))
        fmax = f.max() if f.max() > 0 else 1
        line, = ax.plot(to, f / fmax, label=f"{ti} deg")
        ax.plot([-math.radians(ti)] * 2, [0, 1.05], lw=0.8, ls="--", color=line.get_color())
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)  # positive angles (the mirror side) to the right
    ax.set_thetamin(-90)
    ax.set_thetamax(90)
    ax.set_yticklabels([])
    ax.set_ylim(0, 1.05)
    ax.set_title(title, fontsize=8)


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
            draw_lobes(ax, _bsdf(plugin, params), label[len(plugin):].strip() or label)
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
