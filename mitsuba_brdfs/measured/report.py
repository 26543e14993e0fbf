"""How a fit went: ``fit_file`` fits a model to a file's ``data.Measured`` and adds what a
user judges it by (the relative RMS error, the albedo at ``REPORT_THETAS``, warnings);
``summary_table`` prints fits as a Markdown table, ``plot_slices`` draws measured against
fitted slices.
"""
import numpy as np

__all__ = ["REPORT_THETAS", "ALBEDO_TOLERANCE", "BINS_PER_VALUE", "fit_file", "summary_table",
           "plot_slices"]

#: the incidence angles (deg) the summary and the table report the albedo at
REPORT_THETAS = (0, 45, 75)
#: albedo differences beyond this are warned about
ALBEDO_TOLERANCE = 0.10
#: a file with fewer measured bins than this many per fitted value is warned about
BINS_PER_VALUE = 20


def fit_file(data, bsdf, loss="l2cos", keys=None, optimizer="lbfgs", evaluations=None,
             albedo_weight=None, lr=0.05, progress=None, shape_weight=1.0):
    """``fitting.fit`` of ``bsdf`` to a file's ``Measured`` data; the result with its
    ``quality`` ('relative_rms', 'relative_rms_max'), the albedo at ``REPORT_THETAS``
    ('albedo': {'thetas', 'measured', 'fitted'}) and 'warnings' (sentences)."""
    from .fitting import ALBEDO_THETAS, ALBEDO_WEIGHT, bound_warnings, fit, quality
    albedo_weight = ALBEDO_WEIGHT if albedo_weight is None else albedo_weight
    r = fit(bsdf, data.wi, data.wo, data.f, weights=data.weights, albedo=data.albedo,
            albedo_weight=albedo_weight, shape_weight=shape_weight, loss=loss, keys=keys,
            optimizer=optimizer,
            evaluations=evaluations, lr=lr, progress=progress)
    r.update(quality(bsdf, data.wi, data.wo, data.f, data.weights))
    rows = [ALBEDO_THETAS.index(t) for t in REPORT_THETAS]
    measured = np.array(r["albedo"]["measured"])[rows]
    fitted = np.array(r["albedo"]["fitted"])[rows]
    r["albedo"] = {"thetas": list(REPORT_THETAS), "measured": measured.tolist(),
                   "fitted": fitted.tolist()}
    warnings = []
    bounds = bound_warnings(r["at_bounds"])
    if bounds:
        warnings.append(bounds)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(measured > 0, fitted / measured - 1, 0.0)
    r["albedo"]["relative_difference"] = rel.tolist()
    worst = np.unravel_index(np.argmax(np.abs(rel)), rel.shape)
    if abs(rel[worst]) > ALBEDO_TOLERANCE:
        warnings.append(
            f"the fit reflects {abs(rel[worst]):.0%} {'more' if rel[worst] > 0 else 'less'} "
            f"light than the data at {REPORT_THETAS[worst[0]]} deg ({'RGB'[worst[1]]}): "
            f"the model's energy does not follow the data's there (see 'what each model "
            f"can represent' in docs/presets.md; --albedo-weight trades shape for energy)")
    values = sum(len(v) for v in r["params"].values())
    if data.bins < BINS_PER_VALUE * values:
        warnings.append(f"only {data.bins} measured bins within 80 deg for {values} fitted "
                        f"values: the parameters are poorly determined")
    r["warnings"] = warnings
    return r


def summary_table(rows):
    """The fits as a Markdown table, one row per (model, result): loss, relative RMS of
    f cos per channel, albedo of the fit / the data at ``REPORT_THETAS``, evaluations,
    seconds."""
    head = (["model", "loss (shape + energy)", "relative RMS R, G, B"]
            + [f"albedo at {t} deg: fit / data (G)" for t in REPORT_THETAS]
            + ["evaluations", "seconds"])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for model, r in rows:
        alb = [f"{r['albedo']['fitted'][i][1]:.3g} / {r['albedo']['measured'][i][1]:.3g}"
               for i in range(len(REPORT_THETAS))]
        cells = ([model, f"{r['loss']:.4g} ({r['shape']:.3g} + {r['albedo_weight']:g} x "
                         f"{r['energy']:.3g})",
                  ", ".join(f"{e:.3f}" for e in r["relative_rms"])] + alb
                 + [str(r["evaluations"]), f"{r['seconds']:.1f}"])
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def plot_slices(path, bsdf, measured_path, title, theta_d=(10, 45, 75)):
    """Measured (dots) against fitted (lines) f, R G B, against theta_h at three theta_d,
    phi_d = 90 deg, log scale; written whole to ``path`` (``output.save_figure``)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from . import merl
    from ..output import save_figure
    from ..validate.probe import eval_np
    dims, f = merl.read(measured_path)
    nh, nd, nphi = dims
    fig, axes = plt.subplots(1, len(theta_d), figsize=(4 * len(theta_d), 3.4), sharey=True)
    for ax, td in zip(np.atleast_1d(axes), theta_d):
        j, k = min(int(td / 90 * nd), nd - 1), nphi // 2
        idx = (np.arange(nh) * nd + j) * nphi + k
        wi, wo = merl.directions(dims, index=idx)
        th = np.degrees(((np.arange(nh) + 0.5) / nh) ** 2 * np.pi / 2)
        ok = (wi[:, 2] > 1e-4) & (wo[:, 2] > 1e-4)
        model = eval_np(bsdf, wi[ok], wo[ok]) / wo[ok][:, 2:3]
        for c, colour in enumerate("rgb"):
            ax.semilogy(th[ok], f[idx][ok][:, c], ".", color=colour, ms=3, alpha=0.6)
            ax.semilogy(th[ok], np.maximum(model[:, c], 1e-6), "-", color=colour, lw=1)
        ax.set_title(f"theta_d = {np.degrees((j + 0.5) / nd * np.pi / 2):.0f} deg, "
                     f"phi_d = {np.degrees((k + 0.5) / nphi * np.pi):.0f} deg", fontsize=9)
        ax.set_xlabel("theta_h (deg)")
    np.atleast_1d(axes)[0].set_ylabel("f (dots: measured, lines: fitted)")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)
