"""Fitting a BSDF to measured samples: (wi, wo, f) triples, whatever file they came from.

``fit(bsdf, wi, wo, f, weights=..., albedo=...)`` moves the parameters that
``mi.traverse`` exposes so that the BSDF's ``eval`` (f cos theta) matches the measured
f cos theta at the given direction pairs, by Dr.Jit's automatic differentiation, no
rendering; ``albedo_quadrature`` builds the directions of the energy term. A file format
only chooses the samples and their weights (``data.prepare``); ``quality`` says how close
a fit came.

The loss: a shape term and an energy term, and a constraint on the albedo.

- Shape. ``l2cos`` (the default; Ngan et al. 2005's): ((f_model - f_measured) cos)^2 per
  channel, averaged over the pairs with the given weights; ``cos`` is ``eval``'s, theta of
  Mitsuba's ``wo``. With weights proportional to the measure of the direction pairs each
  sample stands for (a MERL bin's cell, ``merl.measure``), it is the integral of the
  squared error over the pairs of directions, which bounds the error of the directional
  albedo; with equal weights (as Ngan et al. and the BRDF benchmark count MERL's bins) the
  highlight, where MERL's bins are the densest, outweighs the rest (docs/presets.md).
  ``log`` (Low et al. 2012) and ``cbrt`` (Fores et al. 2012) compare g(f cos) instead,
  g = log(1 + x) or the cube root, which weigh a lobe's tails and the diffuse base more
  (``losses``: what each is for). Each channel is divided by a black model's (the weighted
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
- The albedo constraint (``albedo_tolerance``, ``ALBEDO_TOLERANCE`` by default; None: off).
  Where the fit leaves the data's directional albedo by more than ``ALBEDO_GOAL`` (10%)
  at some row and channel, the model's albedo (by its own quadrature, ``albedo['model']``,
  against the data's, ``albedo['reference']``) is constrained: an energy-first fit (the
  energy term weighted ``ENERGY_FIRST``) finds whether the model can reach the data's
  albedo; where it can, a penalty on the squared excess beyond the tolerance (8%: inside
  it the loss, the shape first, decides) brings the fit back to the best shape within it.
  Where it cannot, or only with a channel further from the data than a black model, the
  unconstrained fit is kept and ``constraint['status']`` says "cannot reach" (``_constrain``).

The variables: each parameter moves in a box, never outside its range, and ends on its
bound when the data push it there; parameters that only scale one another move as what
they make (``variables``: Cook-Torrance's k, m_D, m_S and ``specular_scale`` as the two
colours k m_D and (1 - k) s m_S, written back with s = 1 where the lecture's model holds
them). The optimiser (``optimizers``): ``lbfgs`` (the default), SciPy's L-BFGS-B in the box
with the loss and its gradient from Dr.Jit (one ``eval`` and one backward pass per
evaluation) from several starts (the given parameters and ``START_WIDTHS``: a short run
from each, then the best on to convergence), or ``adam``. Either way the fit returns the
best parameters it met, never worse than the start.

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

from ..collector import paused
from .losses import LOSSES, mapped, mapped_np, scaled
from .optimizers import adam, lbfgs
from .variables import SCALE_GROUPS, blocks, free_keys, read, write

__all__ = ["LOSSES", "OPTIMIZERS", "EVALUATIONS", "MIN_COS", "START_WIDTHS", "SCALE_GROUPS",
           "ALBEDO_THETAS", "ALBEDO_WEIGHT", "ALBEDO_TOLERANCE", "ALBEDO_GOAL", "select",
           "free_keys", "albedo_quadrature", "albedo_of", "fit", "most_evaluations"]

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
#: the albedo constraint: where the fit leaves the data's directional albedo by more than
#: ``ALBEDO_GOAL`` at some row and channel, it is fitted again keeping within this
#: fraction (a margin below the goal, so that the shape decides within it) wherever the
#: model can (None: the shape and the energy term alone)
ALBEDO_TOLERANCE = 0.08
ALBEDO_GOAL = 0.10
#: a channel's albedo counts as at least this fraction of the data's largest albedo: a
#: channel near 0 (or a negative one, an out-of-gamut colour) is held to a fraction of that
ALBEDO_FLOOR = 0.01
#: the weight of the energy term in the energy-first fit, which finds whether the model
#: can reach the data's albedo at all
ENERGY_FIRST = 1000.0
#: weights of the squared excess beyond the tolerance, in turn until it is reached
PENALTIES = (1e4, 1e6)
#: each stage of the constraint's fits may take this share of the budget
STAGE_BUDGET = 0.5
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

class _Joint:
    """The direction pairs of a loss's terms (the shape term's, the energy term's rows,
    the model's own albedo rows), joined so that one ``eval`` serves the first ``n`` of
    them: ``eval(bsdf, ctx, n)`` returns each one's values (``dr.gather`` of its lanes)."""

    def __init__(self, sites, si, wo):
        """``sites``: [(wi, wo)] (NumPy, (n, 3) each); ``si``, ``wo``: the first one's, as
        Dr.Jit arrays already."""
        import drjit as dr
        import mitsuba as mi

        from ..validate.probe import interaction, vec
        self.sizes = [len(wi) for wi, _ in sites]
        self.si, self.wo = {1: si}, {1: wo}
        for n in range(2, len(sites) + 1):
            self.si[n] = interaction(np.concatenate([wi for wi, _ in sites[:n]]))
            self.wo[n] = vec(np.concatenate([wo for _, wo in sites[:n]]))
        start = np.concatenate([[0], np.cumsum(self.sizes)])
        self.index = [dr.arange(mi.UInt32, int(a), int(a + n))
                      for a, n in zip(start, self.sizes)]

    def eval(self, bsdf, ctx, n):
        import drjit as dr
        if n == 1:
            return [bsdf.eval(ctx, self.si[1], self.wo[1])]
        value = bsdf.eval(ctx, self.si[n], self.wo[n])
        return [dr.gather(type(value), value, index) for index in self.index[:n]]


class _Problem:
    """The loss of a BSDF's parameters against measured samples, and its gradient in the
    blocks' variables."""

    def __init__(self, bsdf, wi, wo, f, loss, keys, weights, albedo, albedo_weight,
                 shape_weight=1.0, tolerance=None, isotropic=False):
        import mitsuba as mi
        from ..validate.probe import floats, interaction, vec
        if loss not in LOSSES:
            raise ValueError(f"--loss must be one of {', '.join(LOSSES)} (got {loss!r})")
        self.bsdf, self.kind, self.shape_weight = bsdf, loss, float(shape_weight)
        self.params = mi.traverse(bsdf)
        self.blocks = blocks(bsdf, self.params, free_keys(self.params, keys), isotropic)
        self.only = None          # the index of the one start to run from (None: all)
        self.keys = [k for b in self.blocks for k in b.keys]
        self.bounds = [bd for b in self.blocks for bd in b.bounds]
        self.ctx = mi.BSDFContext()
        self.evaluations = 0
        # the shape term, on values in units of the largest measured one for l2cos (float32
        # sums of squares of values of 1e8 or 1e-8 stay finite and accurate)
        self.si, self.wo = interaction(wi), vec(wo)
        sites = [(np.asarray(wi, float).reshape(-1, 3), np.asarray(wo, float).reshape(-1, 3))]
        fcos = np.asarray(f, float) * np.asarray(wo, float)[:, 2:3]
        self.scale = float(np.float32(max(np.abs(fcos).max(), 1e-30))) if scaled(loss) \
            else 1.0
        ref = mapped_np(fcos / self.scale, loss)
        self.ref = mi.Color3f(*(floats(c) for c in ref.T))
        w = np.ones(len(fcos)) if weights is None else np.asarray(weights, float)
        w = w / w.mean()
        self.weights = floats(w)
        # each channel in units of its black model's loss: the shape term is the mean of
        # the channels' squared relative RMS errors, a dim channel counting as a bright one
        unit = np.mean(w[:, None] * ref * ref, axis=0)
        self.inv_unit = mi.Color3f(*(float(1 / u) if u > 1e-30 else 0.0 for u in unit))
        # the energy term
        self.albedo_weight = float(albedo_weight) if albedo is not None else 0.0
        self.penalty, self.tolerance = 0.0, tolerance
        if albedo is not None and not albedo_of(albedo).max() > 0:
            # a black measurement: no energy to match
            self.albedo_weight, self.tolerance = 0.0, None
        if albedo is None:
            self.tolerance = None
        if albedo is not None:
            awi, awo = (np.asarray(albedo[k], float).reshape(-1, 3) for k in ("wi", "wo"))
            af = np.asarray(albedo["f"], float)
            weight = np.where(np.isfinite(af).all(-1), albedo["weight"], 0.0).ravel()
            # eval gives f cos(theta_o) at the evaluation directions
            weight = np.where(awo[:, 2] > 1e-6, weight / np.maximum(awo[:, 2], 1e-6), 0.0)
            self.albedo_data = albedo_of(albedo)
            self.albedo_k = af.shape[1]
            self.albedo_dw = floats(weight)
            # a negative albedo (an out-of-gamut colour's channel) counts as 0
            data = np.maximum(self.albedo_data, 0)
            inv = 1 / (data + 0.02 * max(data.max(), 1e-30))
            self.albedo_target = mi.Color3f(*(floats(c) for c in (self.albedo_data * inv).T))
            self.albedo_inv = mi.Color3f(*(floats(c) for c in inv.T))
            # the constraint and the report: the model's own albedo, by its quadrature
            # (``albedo['model']``; by default the rows'), against the data's; the error
            # relative to the data's albedo, or to ALBEDO_FLOOR of its largest
            model = albedo.get("model", albedo)
            mwo = np.asarray(model["wo"], float).reshape(-1, 3)
            mw = np.asarray(model["weight"], float).ravel()
            mw = np.where(mwo[:, 2] > 1e-6, mw / np.maximum(mwo[:, 2], 1e-6), 0.0)
            self.model_k = np.shape(model["weight"])[1]
            self.model_si = interaction(np.asarray(model["wi"], float).reshape(-1, 3))
            self.model_wo, self.model_dw = vec(mwo), floats(mw)
            self.reference = np.asarray(albedo.get("reference", self.albedo_data), float)
            ref = np.maximum(self.reference, 0)
            self.error_scale = 1 / np.maximum(ref, ALBEDO_FLOOR * max(ref.max(), 1e-30))
            c3 = lambda a: mi.Color3f(*(floats(c) for c in np.asarray(a, np.float32).T))
            self.c_data, self.c_scale = c3(self.reference), c3(self.error_scale)
            sites += [(awi, awo), (np.asarray(model["wi"], float).reshape(-1, 3), mwo)]
        self._joint = _Joint(sites, self.si, self.wo)

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
        """The given start and one per ``START_WIDTHS`` (where the model has a width);
        only the one of index ``only`` where set."""
        out = [y0]
        for alpha in START_WIDTHS:
            parts = [b.width_start(alpha) for b in self.blocks]
            if any(w is not None for w in parts):
                out.append(np.concatenate([yb if w is None else w
                                           for w, yb in zip(parts, self._split(y0))]))
        return out if self.only is None else [out[min(self.only, len(out) - 1)]]

    # -- the loss
    def _own_albedo(self):
        """The model's albedo by its own quadrature (Color3f, one per row); the loss's
        albedos come from ``_terms``."""
        import drjit as dr
        a = self.bsdf.eval(self.ctx, self.model_si, self.model_wo) * self.model_dw
        return type(a)(*(dr.block_sum(a[c], self.model_k) for c in range(3)))

    def _residual(self, value):
        """The model's values at the shape term's pairs, mapped (``losses.mapped``), less
        the data's (``ref``, mapped)."""
        if self.scale != 1.0:
            value = value * (1 / self.scale)
        return mapped(value, self.kind) - self.ref

    def _shape_term(self):
        """The shape term of each channel (Color3f): its squared relative RMS error for
        ``l2cos`` (1: as far off as black)."""
        import drjit as dr
        d = self._residual(self.bsdf.eval(self.ctx, self.si, self.wo))
        return type(d)(*(dr.mean(self.weights * d[c] * d[c], axis=None) for c in range(3))) \
            * self.inv_unit

    def _terms(self):
        """(shape, energy, excess) terms of the loss (Dr.Jit scalars; energy 0 without
        it, excess 0 while the constraint's penalty is off): excess is the mean over rows
        of the channels' squared excess beyond the allowed albedo difference.

        The model is evaluated once, at the directions of every term the loss has
        (``_Joint``): its parameters then reach the values through one evaluation, and
        the backward pass reduces each parameter's gradient once rather than once a term
        (each reduction a kernel launch: most of an evaluation's time on small fits)."""
        import drjit as dr
        sites = 1 + (2 if self.penalty else 1 if self.albedo_weight else 0)
        shape_value, *rows = self._joint.eval(self.bsdf, self.ctx, sites)
        d = self._residual(shape_value)
        iu = self.inv_unit
        integrand = self.weights * (d.x * d.x * iu.x + d.y * d.y * iu.y + d.z * d.z * iu.z)
        parts = [integrand]
        if self.albedo_weight:
            a = rows[0] * self.albedo_dw
            parts += [a.x, a.y, a.z]
        if self.penalty:
            b = rows[1] * self.model_dw
            parts += [b.x, b.y, b.z]
        dr.eval(*parts)   # one kernel for what the reductions below read
        shape = dr.mean(integrand, axis=None) / 3
        energy = excess = 0.0
        if self.albedo_weight:
            albedo = type(a)(*(dr.block_sum(c, self.albedo_k) for c in parts[1:4]))
            d = albedo * self.albedo_inv - self.albedo_target
            energy = dr.mean(d.x * d.x + d.y * d.y + d.z * d.z, axis=None) / 3
        if self.penalty:
            own = type(b)(*(dr.block_sum(c, self.model_k) for c in parts[-3:]))
            e = dr.abs(own - self.c_data) * self.c_scale
            e = dr.maximum(e - self.tolerance, 0)
            excess = dr.mean(e.x * e.x + e.y * e.y + e.z * e.z, axis=None) / 3
        return shape, energy, excess

    def _total(self, shape, energy, excess):
        total = self.shape_weight * shape
        if self.albedo_weight:
            total = total + self.albedo_weight * energy
        if self.penalty:
            total = total + self.penalty * excess
        return total

    def loss(self):
        """(loss, shape term, energy term) of the BSDF's current parameters: the loss
        without the constraint's penalty."""
        import drjit as dr
        with dr.suspend_grad():
            shape, energy, _ = self._terms()
            shape, energy = float(shape[0]), float(energy[0]) if self.albedo_weight else 0.0
        return self.shape_weight * shape + self.albedo_weight * energy, shape, energy

    def albedo_errors(self):
        """(the model's albedo by its own quadrature (m, 3), its relative error against the
        data's, ``ALBEDO_FLOOR`` applied) at the BSDF's current parameters, float64."""
        import drjit as dr

        from ..validate.probe import to_np
        with dr.suspend_grad():
            a = to_np(self._own_albedo()).astype(np.float64)
        return a, (a - self.reference) * self.error_scale

    def loss_and_grad(self, y):
        """(loss, dloss/dy) at y, float64."""
        import drjit as dr
        values = self.set(y)
        for key in self.keys:
            dr.enable_grad(self.params[key])
        self.params.update()
        total = self._total(*self._terms())
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
        lr=0.05, progress=None, albedo_tolerance=ALBEDO_TOLERANCE, isotropic=False,
        start=None):
    """Fit ``bsdf`` (loaded in a JIT AD RGB variant) to the measured f (n, 3; the BRDF
    without cosine, finite) at the direction pairs (wi, wo) (n, 3 each, local frame;
    Mitsuba's ``wo`` carries the cosine).

    ``weights`` (n,): what each sample stands for (default: equal); ``albedo``: the energy
    term's rows, {'wi', 'wo' (m, k, 3), 'weight' (m, k), 'f' (m, k, 3): the measured BRDF
    at (wi, wo), NaN where not measured} (``albedo_quadrature``; a row's albedo is the sum
    of weight times f, of the data and of the model at the same directions), weighted by
    ``albedo_weight`` (``shape_weight`` weighs the shape term: 0 and ``albedo_weight`` 1
    fit the energy alone); ``albedo_tolerance``: the constraint on the rows' albedo (None:
    none); ``keys``: the traverse keys to move (default: every differentiable float and
    colour); ``optimizer``: ``OPTIMIZERS``; ``evaluations``: the budget of each stage
    (default ``EVALUATIONS``; 0 evaluates the start); ``lr``: Adam's learning rate, in the
    optimised variables; ``progress(loss)`` is called after each evaluation;
    ``isotropic``: an anisotropic model's two widths held equal (``variables.tied_pairs``);
    ``start``: L-BFGS-B from that start alone (its index among the given parameters and
    the lobe widths, ``START_WIDTHS``; None: from each, the best on).

    Returns {'loss' (of the best parameters met, without the constraint's penalty; 1 is a
    black model's), 'shape' and 'energy' (its two terms), 'start_loss', 'params' {key:
    list of values}, 'evaluations', 'seconds', 'seconds_per_evaluation', 'samples',
    'loss_kind', 'optimizer', 'albedo_weight', 'starts', 'start', 'tied' (the pairs held
    equal, "nu=nv"), 'at_bounds' [{'parameter', 'value',
    'end'}], 'lr_cuts' (Adam), 'albedo' {'measured', 'fitted'}: per row and channel,
    'constraint' (with ``albedo``: see ``_constrain``)}; ``bsdf`` is left at the best
    parameters."""
    if optimizer not in OPTIMIZERS:
        raise ValueError(f"--optimizer must be one of {', '.join(OPTIMIZERS)} (got "
                         f"{optimizer!r})")
    evaluations = EVALUATIONS if evaluations is None else int(evaluations)
    # Python's garbage collected first and none during the fit: its result then depends on
    # its inputs alone, not on what the process did before (``collector``)
    with paused(collect=True):
        t0 = time.perf_counter()
        problem = _Problem(bsdf, wi, wo, f, loss, keys, weights, albedo, albedo_weight,
                           shape_weight, albedo_tolerance, isotropic)
        problem.lr_cuts, only = 0, start
        starts = len(problem.starts(problem.y()))
        start = {k: read(problem.params, k) for k in problem.keys}
        start_loss = problem.loss()[0]
        tick = progress or (lambda value: None)
        run = lbfgs if optimizer == "lbfgs" else (lambda p, y, n, t: adam(p, y, n, t, lr))
        best = (math.inf, None)
        if evaluations > 0:
            problem.only = only
            try:
                best = run(problem, problem.y(), evaluations, tick)
            finally:
                problem.only = None
        if best[1] is None or not best[0] <= start_loss:
            for key, v in start.items():    # never worse than the start, as given
                write(problem.params, key, v)
            problem.params.update()
            y = problem.y()
        else:
            y = best[1]
            problem.set(y)
            problem.params.update()
        constraint = None
        if problem.tolerance is not None:
            y, constraint = _constrain(problem, y, run, evaluations, tick)
        ends = problem.ends(y) if best[1] is not None else []
        total, shape, energy = problem.loss()
        seconds = time.perf_counter() - t0
        out = {"loss": total, "shape": shape, "energy": energy, "start_loss": start_loss,
               "params": {k: read(problem.params, k).tolist() for k in problem.keys},
               "evaluations": problem.evaluations, "seconds": seconds,
               "seconds_per_evaluation": seconds / max(problem.evaluations, 1),
               "samples": len(wi), "loss_kind": loss, "optimizer": optimizer,
               "albedo_weight": problem.albedo_weight, "starts": starts, "start": only,
               "tied": [b.labels[0] for b in problem.blocks if len(b.keys) == 2],
               "at_bounds": [{"parameter": label, "value": v, "end": end}
                             for label, v, end in ends],
               "lr_cuts": problem.lr_cuts}
        if albedo is not None:
            out["albedo"] = {"measured": problem.reference.tolist(),
                             "fitted": problem.albedo_errors()[0].tolist()}
            out["constraint"] = constraint
        return out


def most_evaluations(evaluations=None):
    """The most evaluations ``fit`` takes with the budget ``evaluations`` a stage: the
    fit's own, then those of the albedo constraint's stages (``_constrain``: the
    energy-first fit and one a penalty, ``STAGE_BUDGET`` of the budget each)."""
    evaluations = EVALUATIONS if evaluations is None else int(evaluations)
    if evaluations <= 0:
        return 0
    return evaluations + (1 + len(PENALTIES)) * max(int(STAGE_BUDGET * evaluations), 1)


def _constrain(problem, y, run, evaluations, tick):
    """The albedo constraint after the unconstrained fit y (the BSDF at y). Where y leaves
    the data's albedo by more than ``ALBEDO_GOAL``: an energy-first fit (the energy term
    weighted ``ENERGY_FIRST``) from y and the lobe widths finds whether the model can reach
    it; if it can, the fit with the penalty on (``PENALTIES``) from there minimises the
    loss within ``tolerance``, and the first result within the goal is kept (that one, or
    the energy-first fit's); if it cannot (the strongest penalty from the energy-first fit
    does not get there either, or only with a channel's shape term 1 or more: further from
    the data than a black model), y is kept (forcing the model closer would only spoil the
    shape). Returns (the y kept, {'tolerance', 'goal', 'status': 'met' (y was within the
    goal), 'reached' (a constrained fit is kept), 'cannot reach' or 'not tried' (y left
    the goal, and a budget of 0 evaluations fitted nothing), 'largest_error'
    (relative, of the fit kept), 'unconstrained', 'energy_first' and 'closest': {'shape',
    'worst_channel' (the largest channel's shape term), 'largest_error', 'params'} (of y, of the energy-first fit and of the stage closest to
    the data's albedo, where y left the goal)})."""
    def state(params=False):
        import drjit as dr
        with dr.suspend_grad():
            worst = float(np.max(np.array(problem._shape_term(), dtype=np.float64)))
        out = {"shape": problem.loss()[1], "worst_channel": worst,
               "largest_error": float(np.abs(problem.albedo_errors()[1]).max())}
        if params:
            out["params"] = {k: read(problem.params, k).tolist() for k in problem.keys}
        return out

    def go(z):
        problem.set(z)
        problem.params.update()

    before = state()
    info = {"tolerance": problem.tolerance, "goal": ALBEDO_GOAL, "status": "met",
            "largest_error": before["largest_error"]}
    if before["largest_error"] <= ALBEDO_GOAL:
        return y, info
    if evaluations <= 0:                # nothing fitted: the goal was not tried
        info["status"] = "not tried"
        return y, info
    info["unconstrained"] = state(params=True)
    budget = max(int(STAGE_BUDGET * evaluations), 1)
    weight, problem.albedo_weight = problem.albedo_weight, ENERGY_FIRST
    try:
        first = run(problem, y, budget, tick)[1]
    finally:
        problem.albedo_weight = weight
    if first is None:
        info["status"] = "cannot reach"
        go(y)
        return y, info
    go(first)
    info["energy_first"] = info["closest"] = state(params=True)
    feasible = info["energy_first"]["largest_error"] <= ALBEDO_GOAL
    # within the goal: the loss decides within the tolerance; beyond it, the strongest
    # penalty (the largest errors first, where the energy term minimised their squares)
    kept = first if feasible and info["energy_first"]["worst_channel"] < 1 else None
    for penalty in PENALTIES if feasible else PENALTIES[-1:]:
        problem.penalty = penalty
        try:
            z = run(problem, first, budget, tick)[1]
        finally:
            problem.penalty = 0.0
        if z is None:
            continue
        go(z)
        closest = state(params=True)
        if closest["largest_error"] <= ALBEDO_GOAL and closest["worst_channel"] < 1:
            kept = z
            break
        if closest["largest_error"] < info["closest"]["largest_error"]:
            info["closest"] = closest
    if kept is None:
        info["status"] = "cannot reach"
        go(y)
        return y, info
    go(kept)
    info.update(status="reached", largest_error=state()["largest_error"])
    return kept, info
