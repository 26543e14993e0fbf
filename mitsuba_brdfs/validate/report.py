"""``check --report DIR``: a Markdown page of the results of every BSDF checked, with its
chi-square histograms and albedo curve as PNG files beside it (``write_report``).
"""
import os
import sys

from ..output import save_figure, write_text

__all__ = ["write_report"]


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
