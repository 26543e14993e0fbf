"""Fitting a BSDF to measured samples: (wi, wo, f) triples, whatever file they came from.

``fit(bsdf, wi, wo, f, weights=..., albedo=...)`` moves the parameters that
``mi.traverse`` exposes so that the BSDF's ``eval`` (f cos theta) matches the measured
f cos theta at the given direction pairs, by Dr.Jit's automatic differentiation, no
rendering. ``quality`` says how close the result is, ``bound_warnings`` which parameters
their ranges stopped, ``albedo_quadrature`` builds the directions of the energy term. A
file format only chooses the samples and their weights (``data.prepare``).

The loss: a shape term and an energy term.

- Shape. ``l2cos`` (the default; Ngan et al. 2005's): ((f_model - f_measured) cos)^2 per
  channel, averaged over the pairs with the given weights; ``cos`` is ``eval``'s, theta of
  Mitsuba's ``wo``. With weights proportional to the measure of the direction pairs each
  sample stands for (a MERL bin's cell, ``merl.measure``), it is the integral of the
  squared error over the pairs of directions, which bounds the error of the directional
  albedo; with equal weights (as Ngan et al. and the BRDF benchmark count MERL's bins) the
  highlight, where MERL's bins are the densest, outweighs the rest (docs/presets.md).
  ``log`` (Low et al. 2012): (log(1 + f_model cos) - log(1 + f_measured cos))^2, which
  weighs a lobe's tails more. Each channel is divided by a black model's (the weighted
  mean of its measured terms squared), and the three averaged: the term is the mean of the
  channels' squared relative RMS errors, 1 is as far off as black, a dim channel counts as
  much as a bright one, and a file of values 1e8 fits as one of values 1.
- Energy (``albedo_weight`` times, ``ALBEDO_WEIGHT`` by default): the mean over the rows
  (incidence angles, ``ALBEDO_THETAS``) and channels of ((A_model - A_measured) /
  (A_measured + 2% of its largest value))^2, the directional albedo A a sum of weight
  times f over outgoing directions where the data are measured (``albedo_quadrature``: a
  quadrature fine around the half vector's normal; a file format may evaluate the model
  where its values stand, as ``data.prepare`` does at MERL's bin centres). Models
  whose lobes lose or gain energy towards grazing incidence differently from the data
  trade shape for energy there (docs/presets.md, "what each model can represent"); 0
  fits the shape alone.

The variables. Each parameter moves in a box, never outside its range, and ends on its
bound when the data push it there:

- slope-like parameters (roughnesses, ``alpha``s, exponents, ``nu``, ``nv``) and those
  spanning decades (an upper bound above 10, or a positive lower bound 100 times smaller
  than the upper one) as their logarithm (a step is a relative change); the box's lower
  end is the range's, or where the range starts at 0, 1e-6 (exponents, unbounded
  factors) or 1e-4 of a finite upper end;
- the others (reflectances, weights, ``f0``, a dielectric's ``eta``) in their range,
  scaled to [0, 1].

This package's plugins declare their ranges; for other plugins reflectances, colours and
principled's weights are kept in [0, 1], ``alpha``s and roughnesses in [1e-3, 1], a
dielectric interface's ``eta`` in [1.001, 3], a conductor's ``eta`` in [0.01, 10] and
``k`` in [0, 20], anything else >= 0.
Values reach the plugin as float32 rounded into the range (Ward's alpha bound 1e-4 is the
float32 9.9999997e-5; ``nu``'s 1e6 stays 1e6).

Parameters that only scale one another. In ``cook_torrance`` the diffuse term is k m_D and
the specular one (1 - k) s m_S F(f0) D G / (4 cos cos): k, m_D, m_S and ``specular_scale``
s give two colours, and between them lies a valley of equal losses in which an optimiser
wanders and lands on bounds. The fit moves the two colours instead (``SCALE_GROUPS``):
k m_D in [0, 0.999] and (1 - k) s m_S (as a logarithm, in [1e-6, 100]), with f0 and the
roughness; it writes them back with s = 1 and k = max(k m_D) / (max(k m_D) + max((1 - k) s
m_S)) whenever the lecture's model (s = 1) holds them, else with k = max(k m_D), the
largest channel of m_S 1 and s what remains.

The optimiser. ``lbfgs`` (the default): SciPy's L-BFGS-B in the box, with the loss and its
gradient from Dr.Jit (one ``eval`` and one backward pass per evaluation), from several
starts: the given parameters and ``START_WIDTHS`` (the lobe's width: slopes and
roughnesses at these values, exponents at the Beckmann-equivalent 2 / alpha^2 - 2); a
short run from each (``_SCOUT`` of the budget), then the best one on to convergence
within the budget. ``adam``: Adam (beta_2 = 0.9) from the given start in the same box,
its learning rate falling geometrically to 0.3 of ``lr``, each step projected back into
the box; a step that more than doubles the best loss sends it back to the best
parameters with half the learning rate (``lr_cuts``). Either way the fit returns the best
parameters it met, never worse than the start.

References: A. Ngan, F. Durand, W. Matusik, "Experimental Analysis of BRDF Models", EGSR
2005; J. Low, J. Kronander, A. Ynnerman, J. Unger, "BRDF Models for Accurate and Efficient
Rendering of Glossy Surfaces", ACM TOG 31(1), 2012; S. Rusinkiewicz, "A New Change of
Variables for Efficient BRDF Representation", EGWR 1998 (the measure); R. H. Byrd, P. Lu,
J. Nocedal, C. Zhu, "A Limited Memory Algorithm for Bound Constrained Optimization", SIAM
J. Sci. Comput. 16(5), 1995 (L-BFGS-B); D. P. Kingma, J. Ba, "Adam", ICLR 2015.
"""
import math
import time

import numpy as np

from .optimizers import adam, lbfgs
from .variables import SCALE_GROUPS, blocks, free_keys, read, write

__all__ = ["LOSSES", "OPTIMIZERS", "EVALUATIONS", "MIN_COS", "START_WIDTHS", "SCALE_GROUPS",
           "ALBEDO_THETAS", "ALBEDO_WEIGHT", "select", "free_keys", "albedo_quadrature",
           "albedo_of", "fit", "quality", "bound_warnings"]

LOSSES = ("l2cos", "log")
OPTIMIZERS = ("lbfgs", "adam")
#: default budget: evaluations of the loss and its gradient (L-BFGS-B), or Adam steps
EVALUATIONS = 1500
#: both directions within 80 deg of the normal: grazing bins are the least reliable
#: measurements, and would dominate the L2 loss (the original Ward lobe is singular there)
MIN_COS = math.cos(math.radians(80))
#: the lobe widths the L-BFGS-B fit also starts from (Beckmann-like slopes; exponents
#: start at 2 / alpha^2 - 2): a sharp, a glossy and a rough lobe
START_WIDTHS = (0.01, 0.06, 0.3)
#: incidence angles (deg) of the energy term, and its default weight
ALBEDO_THETAS = (0, 15, 30, 45, 60, 75)
ALBEDO_WEIGHT = 1.0
#: resolution of the energy term's quadrature (``validate.directions.half_vector_sphere``)
_ALBEDO_N = 16


def select(wi, wo, f, min_cos=MIN_COS):
    """The samples worth fitting: both directions more than ``min_cos`` above the horizon
    and f measured (finite) in every channel. Returns the boolean mask."""
    wi, wo, f = (np.asarray(a, float) for a in (wi, wo, f))
    return np.isfinite(f).all(1) & (wi[:, 2] > min_cos) & (wo[:, 2] > min_cos)


def albedo_quadrature(thetas=ALBEDO_THETAS, n=_ALBEDO_N, phi=0.7):
    """The energy term's rows where the data can be evaluated anywhere: for each incidence
    theta (deg, at azimuth phi) the outgoing directions of ``half_vector_sphere`` above the
    horizon, with weights cos(theta_o) dw. Returns {'wi', 'wo' (m, k, 3), 'weight' (m, k)},
    rows padded with weight 0; add 'f' (the data there) for ``fit``."""
    from ..validate.directions import half_vector_sphere, sph
    rows = []
    for t in thetas:
        w = sph(math.radians(t), phi)[0]
        d, dw = half_vector_sphere(n, w)
        up = d[:, 2] > 0
        rows.append((w, d[up], dw[up] * d[up, 2]))
    k = max(len(c) for _, _, c in rows)
    wi, wo = np.zeros((len(rows), k, 3)), np.zeros((len(rows), k, 3))
    wi[..., 2] = wo[..., 2] = 1
    weight = np.zeros((len(rows), k))
    for i, (w, d, c) in enumerate(rows):
        wi[i], wo[i, :len(c)], weight[i, :len(c)] = w, d, c
    return {"wi": wi, "wo": wo, "weight": weight}


def albedo_of(rows):
    """The directional albedo of each row of the energy term, sum of weight times f (the
    BRDF, without cosine) where f is measured (finite): (m, 3)."""
    f = np.asarray(rows["f"], float)
    weight = np.where(np.isfinite(f).all(-1), rows["weight"], 0.0)
    return np.sum(np.nan_to_num(f) * weight[..., None], axis=1)


# -- the loss ------------------------------------------------------------------------------

def _shape(value, ref, kind, weights):
    """The mean over the pairs of weights times each channel's squared difference."""
    import drjit as dr
    if kind == "log":
        d = dr.log(1 + dr.maximum(value, 0)) - dr.log(1 + ref)
    else:
        d = value - ref
    return type(d)(*(dr.mean(weights * d[c] * d[c], axis=None) for c in range(3)))


class _Problem:
    """The loss of a BSDF's parameters against measured samples, and its gradient in the
    blocks' variables."""

    def __init__(self, bsdf, wi, wo, f, loss, keys, weights, albedo, albedo_weight,
                 shape_weight=1.0):
        import mitsuba as mi
        from ..validate.probe import interaction, vec
        if loss not in LOSSES:
            raise ValueError(f"--loss must be one of {', '.join(LOSSES)} (got {loss!r})")
        self.bsdf, self.kind, self.shape_weight = bsdf, loss, float(shape_weight)
        self.params = mi.traverse(bsdf)
        self.blocks = blocks(bsdf, self.params, free_keys(self.params, keys))
        self.keys = [k for b in self.blocks for k in b.keys]
        self.bounds = [bd for b in self.blocks for bd in b.bounds]
        self.ctx = mi.BSDFContext()
        self.evaluations = 0
        # the shape term, on values in units of the largest measured one for l2cos (float32
        # sums of squares of values of 1e8 or 1e-8 stay finite and accurate)
        self.si, self.wo = interaction(wi), vec(wo)
        fcos = np.asarray(f, float) * np.asarray(wo, float)[:, 2:3]
        self.scale = 1.0 if loss == "log" else float(np.float32(max(np.abs(fcos).max(),
                                                                     1e-30)))
        self.ref = mi.Color3f(*(fcos / self.scale).astype(np.float32).T)
        w = np.ones(len(fcos)) if weights is None else np.asarray(weights, float)
        w = w / w.mean()
        self.weights = mi.Float(w.astype(np.float32))
        ref = fcos / self.scale
        ref = np.log1p(ref) if loss == "log" else ref
        # each channel in units of its black model's loss: the shape term is the mean of
        # the channels' squared relative RMS errors, a dim channel counting as a bright one
        unit = np.mean(w[:, None] * ref * ref, axis=0)
        self.inv_unit = mi.Color3f(*(float(1 / u) if u > 1e-30 else 0.0 for u in unit))
        # the energy term
        self.albedo_weight = float(albedo_weight) if albedo is not None else 0.0
        if albedo is not None and not albedo_of(albedo).max() > 0:
            self.albedo_weight = 0.0   # a black measurement: no energy to match
        if albedo is not None:
            awi, awo = (np.asarray(albedo[k], float).reshape(-1, 3) for k in ("wi", "wo"))
            af = np.asarray(albedo["f"], float)
            weight = np.where(np.isfinite(af).all(-1), albedo["weight"], 0.0).ravel()
            # eval gives f cos(theta_o) at the evaluation directions
            weight = np.where(awo[:, 2] > 1e-6, weight / np.maximum(awo[:, 2], 1e-6), 0.0)
            self.albedo_data = albedo_of(albedo)
            self.albedo_k = af.shape[1]
            self.albedo_si, self.albedo_wo = interaction(awi), vec(awo)
            self.albedo_dw = mi.Float(weight.astype(np.float32))
            inv = 1 / (self.albedo_data + 0.02 * max(self.albedo_data.max(), 1e-30))
            self.albedo_target = mi.Color3f(*(self.albedo_data * inv).astype(np.float32).T)
            self.albedo_inv = mi.Color3f(*inv.astype(np.float32).T)

    # -- the variables
    def y(self):
        """The variables of the BSDF's current parameters."""
        return np.concatenate([b.encode(self.params) for b in self.blocks])

    def _split(self, y):
        out, i = [], 0
        for b in self.blocks:
            out.append(np.asarray(y[i:i + b.size], float))
            i += b.size
        return out

    def set(self, y):
        """Hand the parameters of y to the BSDF (not updated yet); returns {key: values}."""
        values = {}
        for b, yb in zip(self.blocks, self._split(y)):
            values.update(b.decode(yb))
        for key, v in values.items():
            write(self.params, key, v)
        return values

    def clip(self, y):
        lo = np.array([-np.inf if a is None else a for a, _ in self.bounds])
        hi = np.array([np.inf if b is None else b for _, b in self.bounds])
        return np.clip(y, lo, hi)

    def ends(self, y):
        return [e for b, yb in zip(self.blocks, self._split(y)) for e in b.ends(yb)]

    def starts(self, y0):
        """The given start and one per ``START_WIDTHS`` (where the model has a width)."""
        out = [y0]
        for alpha in START_WIDTHS:
            parts = [b.width_start(alpha) for b in self.blocks]
            if any(w is not None for w in parts):
                out.append(np.concatenate([yb if w is None else w
                                           for w, yb in zip(parts, self._split(y0))]))
        return out

    # -- the loss
    def _albedo(self):
        """The model's albedo on the energy term's rows (Color3f, one per row)."""
        import drjit as dr
        a = self.bsdf.eval(self.ctx, self.albedo_si, self.albedo_wo) * self.albedo_dw
        return type(a)(*(dr.block_sum(a[c], self.albedo_k) for c in range(3)))

    def _terms(self):
        """(shape, energy) terms of the loss (Dr.Jit scalars; energy 0 without it)."""
        import drjit as dr
        value = self.bsdf.eval(self.ctx, self.si, self.wo)
        if self.scale != 1.0:
            value = value * (1 / self.scale)
        s = _shape(value, self.ref, self.kind, self.weights) * self.inv_unit
        shape = (s.x + s.y + s.z) / 3
        if not self.albedo_weight:
            return shape, 0.0
        d = self._albedo() * self.albedo_inv - self.albedo_target
        return shape, dr.mean(d.x * d.x + d.y * d.y + d.z * d.z, axis=None) / 3

    def loss(self):
        """(loss, shape term, energy term) of the BSDF's current parameters."""
        import drjit as dr
        with dr.suspend_grad():
            shape, energy = self._terms()
            shape, energy = float(shape[0]), float(energy[0]) if self.albedo_weight else 0.0
        return self.shape_weight * shape + self.albedo_weight * energy, shape, energy

    def loss_and_grad(self, y):
        """(loss, dloss/dy) at y, float64."""
        import drjit as dr
        values = self.set(y)
        for key in self.keys:
            dr.enable_grad(self.params[key])
        self.params.update()
        shape, energy = self._terms()
        total = self.shape_weight * shape
        if self.albedo_weight:
            total = total + self.albedo_weight * energy
        dr.backward(total)
        grads = {key: np.array(dr.grad(self.params[key]), dtype=np.float64).ravel()
                 for key in self.keys}
        for key in self.keys:
            dr.disable_grad(self.params[key])
        self.evaluations += 1
        values = {k: np.asarray(v, float) for k, v in values.items()}
        g = np.concatenate([b.chain(yb, values, grads)
                            for b, yb in zip(self.blocks, self._split(y))])
        return float(total[0]), g


def fit(bsdf, wi, wo, f, *, weights=None, albedo=None, albedo_weight=ALBEDO_WEIGHT,
        shape_weight=1.0, loss="l2cos", keys=None, optimizer="lbfgs", evaluations=None,
        lr=0.05, progress=None):
    """Fit ``bsdf`` (loaded in a JIT AD RGB variant) to the measured f (n, 3; the BRDF
    without cosine, finite) at the direction pairs (wi, wo) (n, 3 each, local frame;
    Mitsuba's ``wo`` carries the cosine).

    ``weights`` (n,): what each sample stands for (default: equal); ``albedo``: the energy
    term's rows, {'wi', 'wo' (m, k, 3), 'weight' (m, k), 'f' (m, k, 3): the measured BRDF
    at (wi, wo), NaN where not measured} (``albedo_quadrature``; a row's albedo is the sum
    of weight times f, of the data and of the model at the same directions), weighted by
    ``albedo_weight`` (``shape_weight`` weighs the shape term: 0 and ``albedo_weight`` 1
    fit the energy alone); ``keys``: the traverse keys to move (default: every
    differentiable float and colour); ``optimizer``: ``OPTIMIZERS``; ``evaluations``: the
    budget (default ``EVALUATIONS``; 0 evaluates the start); ``lr``: Adam's learning
    rate, in the optimised variables; ``progress(loss)`` is called after each evaluation.

    Returns {'loss' (of the best parameters met; 1 is a black model's), 'shape' and
    'energy' (its two terms), 'start_loss', 'params' {key: list of values},
    'evaluations', 'seconds', 'seconds_per_evaluation', 'samples', 'loss_kind',
    'optimizer', 'albedo_weight', 'at_bounds' [{'parameter', 'value', 'end'}], 'lr_cuts'
    (Adam), 'albedo' {'measured', 'fitted'}: per row and channel (with ``albedo``)};
    ``bsdf`` is left at the best parameters."""
    if optimizer not in OPTIMIZERS:
        raise ValueError(f"--optimizer must be one of {', '.join(OPTIMIZERS)} (got "
                         f"{optimizer!r})")
    evaluations = EVALUATIONS if evaluations is None else int(evaluations)
    t0 = time.perf_counter()
    problem = _Problem(bsdf, wi, wo, f, loss, keys, weights, albedo, albedo_weight,
                       shape_weight)
    problem.lr_cuts = 0
    start = {k: read(problem.params, k) for k in problem.keys}
    start_loss = problem.loss()[0]
    tick = progress or (lambda value: None)
    best = (math.inf, None)
    if evaluations > 0:
        run = lbfgs if optimizer == "lbfgs" else \
            (lambda p, y, n, t: adam(p, y, n, t, lr))
        best = run(problem, problem.y(), evaluations, tick)
    if best[1] is None or not best[0] <= start_loss:
        for key, v in start.items():    # never worse than the start, as given
            write(problem.params, key, v)
        ends = []
    else:
        problem.set(best[1])
        ends = problem.ends(best[1])
    problem.params.update()
    total, shape, energy = problem.loss()
    seconds = time.perf_counter() - t0
    out = {"loss": total, "shape": shape, "energy": energy, "start_loss": start_loss,
           "params": {k: read(problem.params, k).tolist() for k in problem.keys},
           "evaluations": problem.evaluations, "seconds": seconds,
           "seconds_per_evaluation": seconds / max(problem.evaluations, 1),
           "samples": len(wi), "loss_kind": loss, "optimizer": optimizer,
           "albedo_weight": problem.albedo_weight,
           "at_bounds": [{"parameter": label, "value": v, "end": end}
                         for label, v, end in ends],
           "lr_cuts": problem.lr_cuts}
    if albedo is not None:
        import drjit as dr
        with dr.suspend_grad():
            fitted = np.array(problem._albedo()).reshape(3, -1).T
        out["albedo"] = {"measured": problem.albedo_data.tolist(), "fitted": fitted.tolist()}
    return out


# -- how good is the fit -------------------------------------------------------------------

def quality(bsdf, wi, wo, f, weights=None):
    """The scale-free error of ``bsdf`` against the measured samples, per channel:
    'relative_rms' [R, G, B] = sqrt(sum w (f_model cos - f cos)^2 / sum w (f cos)^2) over
    the pairs, with the fit's weights w (0: exact; 1: as far off as a black model), and
    'relative_rms_max' its largest channel."""
    from ..validate.probe import eval_np
    wo = np.asarray(wo, float)
    w = np.ones(len(wo)) if weights is None else np.asarray(weights, float)
    fcos = np.asarray(f, float) * wo[:, 2:3]
    model = eval_np(bsdf, wi, wo).astype(float)
    err = np.sqrt(np.sum(w[:, None] * (model - fcos) ** 2, axis=0)
                  / np.maximum(np.sum(w[:, None] * fcos ** 2, axis=0), 1e-300))
    return {"relative_rms": err.tolist(), "relative_rms_max": float(err.max())}


def bound_warnings(at_bounds):
    """One sentence naming every parameter a fit left on an end of its range (``fit``'s
    'at_bounds'), or None."""
    if not at_bounds:
        return None
    items = ", ".join(f"{a['parameter']} = {a['value']:.7g} ({a['end']} bound)"
                      for a in at_bounds)
    return (f"on the end of its range: {items} (the data ask for more than the model "
            f"allows there, or the parameter does not matter)")
