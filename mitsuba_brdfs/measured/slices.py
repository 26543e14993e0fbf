"""Measured against fitted slices of a BRDF: f against theta_h at three theta_d (MERL's
bins), the plot ``fit-measured`` writes."""
import numpy as np

from .acquire import LUMINANCE

__all__ = ["plot_slices"]


def plot_slices(path, fits, evaluate, title, theta_d=(10, 45, 75), dims=None):
    """Measured (dots) against fitted (lines) f against theta_h at three theta_d, phi_d =
    90 deg (MERL's bins along theta_h), log scale: R, G, B of one fit, or the luminance
    of several (one colour each, in the given order); ``fits`` [(label, bsdf)],
    ``evaluate(wi, wo)`` the data's f. Written whole to ``path`` (``output.save_figure``)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from . import merl
    from ..output import save_figure
    from ..validate.probe import eval_np
    nh, nd, nphi = dims or merl.DIMS
    fig, axes = plt.subplots(1, len(theta_d), figsize=(4 * len(theta_d), 3.6), sharey=True)
    one = len(fits) == 1
    colours = plt.get_cmap("tab10").colors
    for ax, td in zip(np.atleast_1d(axes), theta_d):
        j, k = min(int(td / 90 * nd), nd - 1), nphi // 2
        idx = (np.arange(nh) * nd + j) * nphi + k
        wi, wo = merl.directions((nh, nd, nphi), index=idx)
        th = np.degrees(((np.arange(nh) + 0.5) / nh) ** 2 * np.pi / 2)
        ok = (wi[:, 2] > 1e-4) & (wo[:, 2] > 1e-4)
        wi, wo, th = wi[ok], wo[ok], th[ok]
        f = np.asarray(evaluate(wi, wo), float)
        curves = [(label, np.asarray(eval_np(bsdf, wi, wo), float).reshape(len(wi), -1)
                   / wo[:, 2:3]) for label, bsdf in fits]
        floor = 1e-4 * max(np.nanmax(f), 1e-12)
        if one:
            for c, colour in enumerate("rgb"):
                ax.semilogy(th, np.maximum(f[:, c], floor), ".", color=colour, ms=3, alpha=0.6)
                ax.semilogy(th, np.maximum(curves[0][1][:, c], floor), "-", color=colour, lw=1)
        else:
            ax.semilogy(th, np.maximum(f @ LUMINANCE, floor), ".", color="k", ms=3,
                        alpha=0.6, label="measured")
            for i, (label, g) in enumerate(curves):
                ax.semilogy(th, np.maximum(g @ LUMINANCE, floor), "-", lw=1.2,
                            color=colours[i % len(colours)], label=label)
        ax.set_title(f"theta_d = {np.degrees((j + 0.5) / nd * np.pi / 2):.0f} deg, "
                     f"phi_d = {np.degrees((k + 0.5) / nphi * np.pi):.0f} deg", fontsize=9)
        ax.set_xlabel("theta_h (deg)")
    first = np.atleast_1d(axes)[0]
    first.set_ylabel("f (dots: measured, lines: fitted)" if one else
                     "luminance of f (dots: measured)")
    if not one:
        first.legend(fontsize=7, loc="best")
    fig.suptitle(title, fontsize=10)
    # the margins (inches) that tight_layout finds for this figure, whatever the data (a
    # log axis's tick labels, fixed titles): set directly, as tight_layout would draw the
    # figure once more to measure them (~40 % of the plot's time)
    width, height = fig.get_size_inches()
    fig.subplots_adjust(left=0.78 / width, right=1 - 0.15 / width, bottom=0.585 / height,
                        top=1 - 0.637 / height, wspace=0.056)
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)
