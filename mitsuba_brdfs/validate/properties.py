"""The measurements of the property table (``python -m mitsuba_brdfs properties``) and of
the plugin pages (``manual``): per BSDF and incidence, the directional albedo as the mean
sampled weight (white furnace), the relative variance of the weight, the share of samples
drawn below the horizon; the largest reciprocity error over random pairs; eval in the plane
of incidence. ``draw_albedo`` and ``draw_lobes`` draw them on Matplotlib axes.
"""
import math

import numpy as np

from .directions import sph
from .probe import eval_np, load_bsdf, rows, sample_bsdf
from .reciprocity import reciprocity_error

__all__ = ["THETAS_DEG", "sample_stats", "largest_reciprocity_error", "lobe_curve", "measure",
           "draw_albedo", "draw_lobes"]

THETAS_DEG = np.array([0, 10, 20, 30, 40, 50, 60, 70, 75, 80, 85, 89], dtype=float)


def sample_stats(bsdf, theta, n, seed=0):
    """(albedo, relative variance of the weight, fraction of samples below the horizon) of n
    samples at the incidence theta (radians), the weight's channels averaged."""
    _, (bs, weight) = sample_bsdf(bsdf, sph(theta, 0.0), n, seed=seed)
    w = rows(weight, n, channels=True).mean(axis=1)
    below = rows(bs.wo, n)[:, 2] <= 0
    mean = float(w.mean())
    var = float(w.var())
    return mean, (var / mean ** 2 if mean > 0 else math.nan), float(below.mean())


def largest_reciprocity_error(bsdf, n=20000, seed=1):
    """max |f(a, b) - f(b, a)| / max f (f = eval / cos) over n random pairs of directions
    with cos theta >= 0.05 (``reciprocity.reciprocity_error``)."""
    rng = np.random.default_rng(seed)
    ta, tb = np.arccos(rng.uniform(0.05, 1, n)), np.arccos(rng.uniform(0.05, 1, n))
    pa, pb = rng.uniform(0, 2 * np.pi, (2, n))
    return reciprocity_error(bsdf, sph(ta, pa), sph(tb, pb))["max_rel"]


def lobe_curve(bsdf, theta_i, m=361):
    """eval (f cos) in the plane of incidence, channels averaged: outgoing angle in
    [-90, 90] deg -> value, the mirror direction at +theta_i."""
    to = np.linspace(-np.pi / 2, np.pi / 2, m)
    wi = sph(np.full(m, theta_i), 0.0)
    wo = sph(np.abs(to), np.where(to >= 0, np.pi, 0.0))  # the mirror side: phi = pi
    return to, eval_np(bsdf, wi, wo).reshape(m, -1).mean(axis=1)


def measure(samples, configs, progress=True):
    """Run every measurement of ``configs`` ((plugin, label, parameters) each, as
    ``properties.CONFIGS``); returns a list of dicts (one per configuration)."""
    from ..progress import advance, progress_bar
    rows = []
    with progress_bar(len(configs), "properties", enabled=progress) as bar:
        for plugin, label, params in configs:
            bsdf = load_bsdf(plugin, **params)
            stats = [sample_stats(bsdf, math.radians(t), samples, seed=k)
                     for k, t in enumerate(THETAS_DEG)]
            alb = np.array([s[0] for s in stats])
            rows.append({
                "plugin": plugin, "label": label, "params": params,
                "albedo": alb.tolist(),
                "albedo_max": float(alb.max()),
                "rel_var_45": sample_stats(bsdf, math.radians(45), samples, seed=99)[1],
                "below_horizon": {int(t): s[2] for t, s in zip(THETAS_DEG, stats) if t in (0, 60, 85)},
                "reciprocity": largest_reciprocity_error(bsdf),
            })
            advance(bar, 1, label)
    return rows


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
