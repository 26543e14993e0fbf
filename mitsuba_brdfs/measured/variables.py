"""The variables of a fit: a BSDF's parameters, each moved in a box.

``blocks(bsdf, params, keys)`` turns the traverse keys a fit moves into optimised blocks:

- slope-like parameters (roughnesses, ``alpha``s, exponents, ``nu``, ``nv``) and those
  spanning decades (an upper bound above 10, or a positive lower bound 100 times smaller
  than the upper one) as their logarithm (a step is a relative change); the box's lower
  end is the range's, or where the range starts at 0, 1e-6 (exponents, unbounded
  factors) or 1e-4 of a finite upper end; a range without an upper end (Torrance-Sparrow's
  ``eta``) stays open to the optimiser, and a step beyond ``UNBOUNDED_TOP`` gives that
  value, not a float32 infinity, which the plugin refuses;
- the others (reflectances, weights, ``f0``, a dielectric's ``eta``) in their range,
  scaled to [0, 1];
- parameters that only scale one another as what they make (``SCALE_GROUPS``:
  Cook-Torrance's k, m_D, m_S and ``specular_scale``, see ``fitting``);
- for isotropic data, an anisotropic model's two widths (``ANISOTROPIC_PAIRS``: ``nu``
  and ``nv``, ``alpha_u`` and ``alpha_v``) as one variable, written to both.

Ranges: this package's plugins declare theirs; for other plugins ``param_range`` guesses by
name. ``colour_spec`` makes every colour held as one number an RGB colour, so that a fit
finds a colour. ``free_keys`` chooses the keys, ``read`` and ``write`` move values between a
``mi.traverse`` and float64 NumPy.
"""
import math

import numpy as np

__all__ = ["SLOPES", "EXPONENTS", "UNBOUNDED_TOP", "SCALE_GROUPS", "ANISOTROPIC_PAIRS",
           "param_range", "free_keys", "read", "write", "tied_pairs", "blocks", "colour_spec"]

#: names of positive slope-like parameters (widths, roughnesses), optimised as logarithms
#: whatever their range: a step is a relative change, and a small value (nickel's Beckmann
#: m = 0.04) cannot be stepped through zero
SLOPES = ("roughness", "alpha", "alpha_u", "alpha_v", "exponent", "nu", "nv")
EXPONENTS = ("exponent", "nu", "nv")
#: the largest value a fit gives a parameter whose range has no upper end: far beyond any
#: physical value (an ``eta`` of 1e30 is a mirror's Fresnel term), the value the models'
#: hard cases are checked at (``FACTS.edges``), and finite in float32, where exp() of a
#: long step is not
UNBOUNDED_TOP = 1e30
_CHANNELS = "rgb"


def _name(key):
    """The parameter's name in a traverse key (``diffuse_reflectance.value``)."""
    return key.split(".")[0]


def param_range(bsdf, key):
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


def read(params, key):
    """A parameter's value as float64 numpy (1 or 3 values)."""
    return np.array(params[key], dtype=np.float64).ravel()


def write(params, key, values):
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
        self.lo, self.hi = _inward(lo, min(hi, UNBOUNDED_TOP))
        self.log = (not math.isfinite(hi) or hi > 10 or (lo > 0 and hi / lo > 100)
                    or name in SLOPES) and hi > 0
        if self.log:
            floor = max(lo, 1e-6 if hi > 10 else 1e-4 * hi)
            self.lo = max(self.lo, _inward(floor, hi)[0])
            # no upper end: the optimiser's box stays open above (a bound there changes
            # L-BFGS-B's steps), and a step beyond UNBOUNDED_TOP decodes to it
            top = math.log(self.hi) if math.isfinite(hi) else None
            self.bounds = [(math.log(self.lo), top)] * size
        else:
            self.bounds = [(0.0, 1.0)] * size
        self.labels = _labels(name, size)
        self.slope, self.exponent = name in SLOPES, name in EXPONENTS

    def encode(self, params):
        x = np.clip(read(params, self.keys[0]), self.lo, self.hi)
        if self.log:
            return np.log(x)
        return (x - self.lo) / (self.hi - self.lo) if self.hi > self.lo else 0 * x

    def decode(self, y):
        """{key: float32 values} of y, clipped into the range."""
        if self.log:   # (a step beyond the box's end is that end, not an overflow)
            x = np.exp(np.minimum(y, math.log(self.hi)))
        else:
            x = self.lo + (self.hi - self.lo) * np.asarray(y)
        # lo and hi are float32 values (``_inward``): rounding keeps a value between them
        return {self.keys[0]: np.float32(np.clip(x, self.lo, self.hi))}

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


class _Tied(_Param):
    """Two parameters held equal, one variable: an anisotropic model's two widths (``nu``
    and ``nv``, ``alpha_u`` and ``alpha_v``) fitted to isotropic data."""

    def __init__(self, keys, size, lo, hi):
        super().__init__(keys[0], size, lo, hi)
        self.keys = list(keys)
        self.labels = ["=".join(_name(k) for k in keys)]

    def encode(self, params):
        x = np.stack([np.clip(read(params, k), self.lo, self.hi) for k in self.keys])
        if self.log:
            return np.log(x).mean(0)               # the geometric mean
        return ((x.mean(0) - self.lo) / (self.hi - self.lo) if self.hi > self.lo
                else 0 * x[0])

    def decode(self, y):
        x = super().decode(y)[self.keys[0]]
        return {k: x for k in self.keys}

    def chain(self, y, values, grads):
        g = sum(grads[k] for k in self.keys)
        return g * values[self.keys[0]] if self.log else g * (self.hi - self.lo)


#: an anisotropic model's pairs of widths, tied for isotropic data
ANISOTROPIC_PAIRS = (("nu", "nv"), ("alpha_u", "alpha_v"))


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
        k, md, ms, s = (read(params, key) for key in self.KEYS)
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


def tied_pairs(keys):
    """The pairs of ``keys`` that an isotropic fit holds equal (``ANISOTROPIC_PAIRS``,
    both free)."""
    by_name = {_name(k): k for k in keys}
    return [(by_name[a], by_name[b]) for a, b in ANISOTROPIC_PAIRS
            if a in by_name and b in by_name]


def blocks(bsdf, params, keys, isotropic=False):
    """The optimised blocks of the free keys: the plugin's scale group where it applies,
    the anisotropic widths as one (``isotropic``: ``tied_pairs``), else one ``_Param``
    per key."""
    import drjit as dr
    import mitsuba as mi
    out, rest = [], list(keys)
    group = SCALE_GROUPS.get(getattr(bsdf, "NAME", None))
    if group is not None and set(group.KEYS) <= set(keys) and all(
            isinstance(params[k], mi.Color3f) for k in group.KEYS[1:3]):
        out.append(group())
        rest = [k for k in keys if k not in group.KEYS]
    for pair in tied_pairs(rest) if isotropic else ():
        lo, hi = param_range(bsdf, pair[0])
        out.append(_Tied(pair, 3 if isinstance(params[pair[0]], mi.Color3f) else 1, lo, hi))
        rest = [k for k in rest if k not in pair]
    for key in rest:
        if dr.width(params[key]) != 1:
            raise ValueError(f"parameter '{key}' holds {dr.width(params[key])} values (a "
                             f"texture): only constant parameters are fitted")
        size = 3 if isinstance(params[key], mi.Color3f) else 1
        out.append(_Param(key, size, *param_range(bsdf, key)))
    return out


def colour_spec(spec, bsdf):
    """``spec`` with every colour parameter that ``bsdf`` holds as one number given as that
    grey in RGB, so that the fit finds a colour: this package's plugins' colour textures
    (reflectances, ``f0``, ``specular_scale`` of ``ashikhmin_shirley``), other plugins'
    reflectances, base colours and a conductor's ``eta`` and ``k``."""
    import drjit as dr
    import mitsuba as mi
    params = mi.traverse(bsdf)
    ranges = getattr(bsdf, "_ranges", None) or {}
    out = dict(spec)
    for key in params.keys():
        if not key.endswith(".value"):
            continue
        name = key[:-len(".value")]
        colour = (not ranges[name].scalar if name in ranges else
                  any(w in name for w in ("reflectance", "color", "colour"))
                  or name in ("eta", "k"))   # a conductor's complex index, a spectrum
        value = params[key]
        if (colour and isinstance(value, mi.Float) and dr.width(value) == 1
                and not isinstance(spec.get(name), dict)):
            out[name] = {"type": "rgb", "value": [float(value[0])] * 3}
    return out
