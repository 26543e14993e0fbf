"""Fitting a BSDF to measured samples: (wi, wo, f) triples, whatever file they came from.

``fit(bsdf, wi, wo, f, weights=..., albedo=...)`` moves the parameters that
``mi.traverse`` exposes so that the BSDF's ``eval`` (f cos theta) matches the measured
f cos theta at the given direction pairs, by Dr.Jit's automatic differentiation, no
rendering. ``quality`` says how close the result is, ``bound_warnings`` which parameters
their ranges stopped, ``albedo_quadrature`` builds the directions of the energy term. A
file format only chooses the samples and their weights (``mitsuba_brdfs.merl`` and the
command ``fit_measured`` for MERL's files).

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
  where its values stand, as ``fit_measured.prepare`` does at MERL's bin centres). Models
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
#: a start's share of the budget before the best one runs on to convergence
_SCOUT = 0.08
#: Adam: the learning rate falls geometrically to this fraction; beta_2 (a short memory)
_DECAY, _BETA2 = 0.3, 0.9
#: names of positive slope-like parameters (widths, roughnesses), optimised as logarithms
#: whatever their range: a step is a relative change, and a small value (nickel's Beckmann
#: m = 0.04) cannot be stepped through zero
_SLOPES = ("roughness", "alpha", "alpha_u", "alpha_v", "exponent", "nu", "nv")
_EXPONENTS = ("exponent", "nu", "nv")
_CHANNELS = "rgb"


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
    from .validate.directions import half_vector_sphere, sph
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


# -- ranges and parameters -----------------------------------------------------------------

def _name(key):
    """The parameter's name in a traverse key (``diffuse_reflectance.value``)."""
    return key.split(".")[0]


def _range(bsdf, key):
    """(lo, hi) of a traverse key: the plugin's declared range, else a guess by name."""
    name = _name(key)
    ranges = getattr(bsdf, "_ranges", None) or {}
    if name in ranges:
        return float(ranges[name].lo), float(ranges[name].hi)
    if name.startswith("alpha") or name == "roughness":
        return 1e-3, 1.0
    if any(w in name for w in ("reflectance", "albedo", "color", "colour")) or \
            name in _UNIT_WEIGHTS:
        return 0.0, 1.0
    if key == "eta":
        # a dielectric interface's relative index: above 1 (equal indices make no
        # interface, which roughplastic refuses), up to 3
        return 1.001, 3.0
    if name == "eta":   # a conductor's complex index (the texture ``eta.value``), real part
        return 0.01, 10.0
    if name == "k":     # and imaginary part
        return 0.0, 20.0
    return 0.0, math.inf


#: weights and blends in [0, 1] of Mitsuba's plugins (principled's)
_UNIT_WEIGHTS = ("weight", "metallic", "specular", "sheen", "sheen_tint", "spec_tint",
                 "clearcoat", "clearcoat_gloss", "anisotropic", "flatness", "spec_trans",
                 "diff_trans")



def _inward(lo, hi):
    """The float32 ends inside [lo, hi]: a float32 clipped to them is accepted."""
    lo32, hi32 = np.float32(lo), np.float32(hi)
    if lo32 < lo:
        lo32 = np.nextafter(lo32, np.float32(np.inf))
    if hi32 > hi:
        hi32 = np.nextafter(hi32, np.float32(-np.inf))
    return float(lo32), float(hi32)


def free_keys(params, chosen=None):
    """The traverse keys to fit: ``chosen`` (checked), or every differentiable float and
    colour. ValueError names a key that is not a float or colour parameter."""
    import mitsuba as mi
    keys = []
    for key in params.keys():
        value = params[key]
        differentiable = params.flags(key) & mi.ParamFlags.NonDifferentiable.value == 0
        is_float = isinstance(value, (mi.Float, mi.Color3f))
        if chosen is not None:
            if key in chosen:
                if not is_float:
                    raise ValueError(f"parameter '{key}' is not a float or colour (it is "
                                     f"{type(value).__name__})")
                keys.append(key)
        elif differentiable and is_float:
            keys.append(key)
    if chosen is not None:
        missing = sorted(set(chosen) - set(keys))
        if missing:
            raise ValueError(f"--params {', '.join(missing)}: not among the parameters of "
                             f"the model ({', '.join(params.keys())})")
    if not keys:
        raise ValueError("the model exposes no float or colour parameter through "
                         "mi.traverse")
    return keys


def _read(params, key):
    """A parameter's value as float64 numpy (1 or 3 values)."""
    return np.array(params[key], dtype=np.float64).ravel()


def _write(params, key, values):
    """Set a parameter (its type kept) to float32 values."""
    import mitsuba as mi
    v = [float(x) for x in np.asarray(values, np.float32)]
    params[key] = mi.Color3f(*v) if isinstance(params[key], mi.Color3f) else mi.Float(v[0])


def _labels(name, size):
    return [name] if size == 1 else [f"{name}[{c}]" for c in _CHANNELS]


class _Param:
    """One parameter (1 or 3 values) optimised in a box: as its logarithm, or its range
    scaled to [0, 1]."""

    def __init__(self, key, size, lo, hi):
        self.keys, self.size = [key], size
        name = _name(key)
        self.lo, self.hi = _inward(lo, hi)
        self.log = (not math.isfinite(hi) or hi > 10 or (lo > 0 and hi / lo > 100)
                    or name in _SLOPES) and hi > 0
        if self.log:
            floor = max(lo, 1e-6 if hi > 10 else 1e-4 * hi)
            self.lo = max(self.lo, _inward(floor, hi)[0])
            top = math.log(self.hi) if math.isfinite(self.hi) else None
            self.bounds = [(math.log(self.lo), top)] * size
        else:
            self.bounds = [(0.0, 1.0)] * size
        self.labels = _labels(name, size)
        self.slope, self.exponent = name in _SLOPES, name in _EXPONENTS

    def encode(self, params):
        x = np.clip(_read(params, self.keys[0]), self.lo, self.hi)
        if self.log:
            return np.log(x)
        return (x - self.lo) / (self.hi - self.lo) if self.hi > self.lo else 0 * x

    def decode(self, y):
        """{key: float32 values} of y, clipped into the range."""
        x = np.exp(y) if self.log else self.lo + (self.hi - self.lo) * np.asarray(y)
        return {self.keys[0]: np.clip(np.float32(x), np.float32(self.lo),
                                      np.float32(self.hi))}

    def chain(self, y, values, grads):
        """dL/dy from {key: dL/dvalue}."""
        g = grads[self.keys[0]]
        return g * values[self.keys[0]] if self.log else g * (self.hi - self.lo)

    def ends(self, y):
        """(label, value, 'lower' or 'upper') of the values on an end of their range."""
        x = self.decode(y)[self.keys[0]]
        return [(label, float(v), "lower" if v <= self.lo else "upper")
                for label, v in zip(self.labels, x) if v <= self.lo or v >= self.hi]

    def width_start(self, alpha):
        """y with this parameter at a lobe width alpha (slopes: alpha; exponents:
        2 / alpha^2 - 2), or None where it is not a width."""
        if not self.slope:
            return None
        x = float(np.clip(2 / alpha ** 2 - 2 if self.exponent else alpha, self.lo, self.hi))
        return np.full(self.size, math.log(x) if self.log else
                       (x - self.lo) / (self.hi - self.lo))


class _CookTorranceScales:
    """Cook-Torrance's k, m_D, m_S and specular_scale s, fitted as the two colours they
    make: D = k m_D and A = (1 - k) s m_S (see the module's docstring)."""

    KEYS = ("k.value", "diffuse_reflectance.value", "specular_reflectance.value",
            "specular_scale.value")
    _D_MAX, _A_MIN, _A_MAX, _K_MIN = 0.999, 1e-6, 100.0, 1e-3

    def __init__(self):
        self.keys, self.size = list(self.KEYS), 6
        self.bounds = ([(0.0, self._D_MAX)] * 3
                       + [(math.log(self._A_MIN), math.log(self._A_MAX))] * 3)
        self.labels = (_labels("k diffuse_reflectance", 3)
                       + _labels("(1 - k) specular_scale specular_reflectance", 3))
        self.slope = self.exponent = False

    def encode(self, params):
        k, md, ms, s = (_read(params, key) for key in self.KEYS)
        d = np.clip(k * md, 0, self._D_MAX)
        a = np.clip((1 - k) * s * ms, self._A_MIN, self._A_MAX)
        return np.concatenate([d, np.log(a)])

    def decode(self, y):
        d = np.clip(np.asarray(y[:3], float), 0, self._D_MAX)
        a = np.clip(np.exp(y[3:]), self._A_MIN, self._A_MAX)
        dmax, amax = d.max(), a.max()
        if dmax + amax <= 1:  # the lecture's model holds them: s = 1
            k, s = min(max(dmax / (dmax + amax), self._K_MIN), self._D_MAX), 1.0
        else:
            k = min(max(dmax, self._K_MIN), self._D_MAX)
            s = amax / (1 - k)
        f32 = np.float32
        return {"k.value": np.array([k], f32),
                "diffuse_reflectance.value": f32(np.clip(d / k, 0, 1)),
                "specular_reflectance.value": f32(np.clip(a / ((1 - k) * s), 0, 1)),
                "specular_scale.value": np.array([s], f32)}

    def chain(self, y, values, grads):
        k = float(values["k.value"][0])
        s = float(values["specular_scale.value"][0])
        gd = grads["diffuse_reflectance.value"] / k
        ga = grads["specular_reflectance.value"] / ((1 - k) * s) * np.exp(y[3:])
        return np.concatenate([gd, ga])

    def ends(self, y):
        out = [(label, float(v), "lower" if v <= 0 else "upper")
               for label, v in zip(self.labels[:3], y[:3]) if v <= 0 or v >= self._D_MAX]
        for label, v in zip(self.labels[3:], y[3:]):
            a = float(np.exp(v))
            if a <= self._A_MIN * (1 + 1e-9) or a >= self._A_MAX * (1 - 1e-9):
                out.append((label, a, "lower" if a < 1 else "upper"))
        return out

    def width_start(self, alpha):
        return None


#: {plugin: the group of its parameters that only scale one another, fitted as what
#: they make}: used when all its keys are free and its colours are RGB
SCALE_GROUPS = {"cook_torrance": _CookTorranceScales}


def _blocks(bsdf, params, keys):
    """The optimised blocks of the free keys: the plugin's scale group where it applies,
    else one ``_Param`` per key."""
    import drjit as dr
    import mitsuba as mi
    blocks, rest = [], list(keys)
    group = SCALE_GROUPS.get(getattr(bsdf, "NAME", None))
    if group is not None and set(group.KEYS) <= set(keys) and all(
            isinstance(params[k], mi.Color3f) for k in group.KEYS[1:3]):
        blocks.append(group())
        rest = [k for k in keys if k not in group.KEYS]
    for key in rest:
        if dr.width(params[key]) != 1:
            raise ValueError(f"parameter '{key}' holds {dr.width(params[key])} values (a "
                             f"texture): only constant parameters are fitted")
        size = 3 if isinstance(params[key], mi.Color3f) else 1
        blocks.append(_Param(key, size, *_range(bsdf, key)))
    return blocks


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
        from .validate.probe import interaction, vec
        if loss not in LOSSES:
            raise ValueError(f"--loss must be one of {', '.join(LOSSES)} (got {loss!r})")
        self.bsdf, self.kind, self.shape_weight = bsdf, loss, float(shape_weight)
        self.params = mi.traverse(bsdf)
        self.blocks = _blocks(bsdf, self.params, free_keys(self.params, keys))
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
            _write(self.params, key, v)
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


# -- the optimisers ------------------------------------------------------------------------

class _Budget(Exception):
    """The budget of evaluations is spent."""


def _lbfgs(problem, y0, evaluations, tick):
    """L-BFGS-B from each start, then the best one on; returns (best loss, best y)."""
    from scipy.optimize import minimize
    state = {}

    def fun(y):
        if problem.evaluations >= state["limit"]:
            raise _Budget
        value, g = problem.loss_and_grad(y)
        tick(value)
        if not math.isfinite(value) or not np.isfinite(g).all():
            return 1e30, np.zeros_like(g)   # NaN from the model: the line search backs off
        if value < state["best"][0]:
            state["best"] = (value, np.array(y))
        return value, g

    def run(y, budget):
        """L-BFGS-B from y for at most ``budget`` evaluations: (its best loss, y)."""
        state.update(limit=min(problem.evaluations + budget, evaluations),
                     best=(math.inf, y))
        try:
            minimize(fun, y, jac=True, method="L-BFGS-B", bounds=problem.bounds,
                     options={"maxfun": budget, "maxiter": budget, "ftol": 1e-13,
                              "gtol": 1e-11, "maxcor": 20})
        except _Budget:
            pass
        return state["best"]

    starts = problem.starts(problem.clip(y0))
    scout = max(int(_SCOUT * evaluations), 10) if len(starts) > 1 else evaluations
    best = min((run(y, scout) for y in starts), key=lambda r: r[0])
    # the best start on to convergence, restarted while it gains (L-BFGS-B stops where
    # float32 noise fails its line search; a restart forgets a stale curvature)
    while problem.evaluations < evaluations:
        r = run(best[1], evaluations - problem.evaluations)
        if not r[0] < best[0] * (1 - 1e-7):
            break
        best = r
    return best


def _adam(problem, y0, evaluations, tick, lr):
    """Adam in the box (each step projected into it); returns (best loss, best y)."""
    y = problem.clip(y0)
    best = (math.inf, y)
    m, v = np.zeros_like(y), np.zeros_like(y)
    scale, t = 1.0, 0
    for i in range(evaluations):
        value, g = problem.loss_and_grad(y)
        tick(value)
        if value < best[0]:
            best = (value, y)
            scale = min(1.0, scale * 1.05)
        elif not value <= 2 * best[0]:  # also NaN: back to the best, half the step
            y, m, v, t = best[1], 0 * m, 0 * v, 0
            scale, problem.lr_cuts = scale / 2, problem.lr_cuts + 1
            continue
        t += 1
        m = 0.9 * m + 0.1 * g
        v = _BETA2 * v + (1 - _BETA2) * g * g
        step = scale * lr * _DECAY ** (i / evaluations)
        y = problem.clip(y - step * (m / (1 - 0.9 ** t))
                         / (np.sqrt(v / (1 - _BETA2 ** t)) + 1e-8))
    return best


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
    start = {k: _read(problem.params, k) for k in problem.keys}
    start_loss = problem.loss()[0]
    tick = progress or (lambda value: None)
    best = (math.inf, None)
    if evaluations > 0:
        run = _lbfgs if optimizer == "lbfgs" else \
            (lambda p, y, n, t: _adam(p, y, n, t, lr))
        best = run(problem, problem.y(), evaluations, tick)
    if best[1] is None or not best[0] <= start_loss:
        for key, v in start.items():    # never worse than the start, as given
            _write(problem.params, key, v)
        ends = []
    else:
        problem.set(best[1])
        ends = problem.ends(best[1])
    problem.params.update()
    total, shape, energy = problem.loss()
    seconds = time.perf_counter() - t0
    out = {"loss": total, "shape": shape, "energy": energy, "start_loss": start_loss,
           "params": {k: _read(problem.params, k).tolist() for k in problem.keys},
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
    from .validate.probe import eval_np
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
