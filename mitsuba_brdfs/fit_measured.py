"""``python -m mitsuba_brdfs fit-measured FILE --model M``: fit a BSDF to a measured BRDF.

FILE is an isotropic BRDF in MERL's binary format (``mitsuba_brdfs.merl``). M is one of
this package's plugins, one of the ``ngan2005`` preset models (``ward_duer`` is ``ward``
with ``form = duer``), or any Mitsuba BSDF whose parameters ``mi.traverse`` exposes
(``roughplastic``, ``principled``, ...); ``-p KEY=VALUE`` sets its options and start values,
``--init MATERIAL`` starts from that material's Ngan et al. 2005 fit (a preset model).

The fit evaluates the BSDF directly on the measured direction pairs, no rendering: a
random subset (``--samples``, fixed for the fit) of the measured bins with both directions
within 80 deg of the normal, each pair turned by a random phi_h (which an isotropic BRDF
does not see, so that anisotropic models see both tangent directions); it minimises, by Dr.Jit's automatic differentiation and Adam
(``mi.ad.Adam`` with beta_2 = 0.9, its learning rate falling geometrically to 0.3
``--lr``), the loss of Ngan et al. 2005 as the BRDF benchmark writes it (``l2cos``,
the default): the mean over the pairs, summed over R, G, B, of ((f_model - f_measured)
cos theta)^2, with ``eval``'s cosine (theta of Mitsuba's ``wo``); or (``log``) Low et al.'s
(log(1 + f_model cos theta) - log(1 + f_measured cos theta))^2, which weighs the tails of
the lobe more. Parameters stay in range whatever the step: slope-like ones
(roughnesses, ``alpha``s, exponents, ``nu``, ``nv``) and those spanning decades (upper bound
above 10, or a positive lower bound 100 times smaller than the upper one) are optimised as
their logarithm (a step is a relative change), the other bounded ones (reflectances,
weights, ``k``, ``f0``, a dielectric's ``eta``) through a sigmoid onto their range (this
package's plugins declare their ranges; for other plugins reflectances are kept in
[0, 1], ``alpha``s in [1e-3, 1], a dielectric's ``eta`` in [1, 3], anything else >= 0).
The fit returns the best parameters it met (their loss evaluated again), never worse
than the start: a start at the answer stays there. A step that more than doubles the best
loss sends it back to the best parameters with half the learning rate (which grows back
by 5% at each new best) and Adam's moments reset (``lr_cuts`` in the summary counts those).
``--lr`` is a step in the optimised variables: for slopes and exponents a relative change. Reflectances given as one number are fitted as RGB colours.

Speed: an iteration evaluates the BSDF and its gradient on the pairs, a few ms for this
package's plugins (their parameters are opaque: the kernels are compiled once). Mitsuba's
own plugins cost what their ``parameters_changed`` costs: ``roughplastic``'s recomputes its
rough transmittance tables on the host whenever ``alpha`` or ``eta`` changes, about 95 ms
per update on this project's 2-core machine (measured; the kernels are not recompiled:
their cache hits after the first iterations), so they default to ``BUILTIN_ITERATIONS``
(300, about 30-60 s) instead of 1500. Those tables carry no gradient with respect to
``alpha`` and ``eta``. ``--params`` chooses which ``mi.traverse`` keys move (default:
every differentiable float or colour).

Writes, into ``--out`` (default: ``mitsuba_brdfs-out/fit-measured/`` in the current
directory), the fitted ``<bsdf version="3.0.0" ...>`` as ``STEM_MODEL.xml`` (a file that
``check`` and ``mi.load_file`` load, or ``<include filename="..."/>`` inside a ``<shape>``), a plot of measured against fitted slices (f against
theta_h at three theta_d, phi_d = 90 deg) as ``STEM_MODEL.png``, and the summary as
``STEM_MODEL.json``; prints the final loss and the XML (``--json``: the summary). Each file
is written whole (``mitsuba_brdfs.output``); a target that may not be replaced (read-only,
immutable) or a folder that cannot be written is refused before the fit.

References: A. Ngan, F. Durand, W. Matusik, "Experimental Analysis of BRDF Models", EGSR
2005; J. Low, J. Kronander, A. Ynnerman, J. Unger, "BRDF Models for Accurate and Efficient
Rendering of Glossy Surfaces", ACM TOG 31(1), 2012 (the log loss); D. P. Kingma, J. Ba,
"Adam", ICLR 2015.
"""
import json
import math
import os
import time

import numpy as np

__all__ = ["LOSSES", "prepare", "fit", "bsdf_xml", "plot_slices", "outputs", "add_arguments",
           "run"]

#: every file is written whole (``output.atomic``): an interruption can say what was written
WRITES_ATOMICALLY = True

LOSSES = ("l2cos", "log")
#: defaults: Adam steps, measured pairs used, learning rate (in the optimised variables)
ITERATIONS, SAMPLES, LR = 1500, 20_000, 0.05
#: default Adam steps for Mitsuba's own plugins (their parameter updates are slow)
BUILTIN_ITERATIONS = 300
#: the learning rate falls geometrically to this fraction of ``--lr`` over the fit: large
#: steps cross the valleys of correlated parameters, small ones settle the end
_DECAY = 0.3
#: Adam's second-moment decay: a short memory (Adam's default 0.999 remembers the first
#: iterations' gradients, 100 times larger, for a thousand steps, and crawls after them)
_BETA2 = 0.9
#: both directions within 80 deg of the normal: grazing bins are the least reliable
#: measurements, and would dominate the L2 loss (the original Ward lobe is singular there)
MIN_COS = math.cos(math.radians(80))


# -- the data ----------------------------------------------------------------------------

def prepare(path, samples=SAMPLES, seed=0):
    """(wi, wo, f) of ``samples`` measured bins of the file (all of them if fewer), float64:
    directions (n, 3) and the measured BRDF (n, 3)."""
    from . import merl
    dims, f = merl.read(path)
    rng = np.random.default_rng(seed)
    # bins in random order; the directions of four times as many as needed are computed
    # (about half of MERL's bins are measured and within 80 deg), all if that is not enough
    order = rng.permutation(len(f))
    for candidates in (order[:4 * samples], order):
        phi_h = rng.uniform(0, 2 * np.pi, len(candidates))
        wi, wo = merl.directions(dims, phi_h, candidates)
        keep = np.isfinite(f[candidates]).all(1) & (wi[:, 2] > MIN_COS) & (wo[:, 2] > MIN_COS)
        if keep.sum() >= samples or len(candidates) == len(f):
            break
    idx = np.nonzero(keep)[0][:samples]
    if len(idx) == 0:
        raise ValueError(f"fit-measured: {path} holds no measured bin within 80 deg of "
                         f"the normal")
    return wi[idx], wo[idx], f[candidates[idx]]


# -- the parameters ------------------------------------------------------------------------

def _range(bsdf, key):
    """(lo, hi) of a traverse key: the plugin's declared range, else a guess by name."""
    name = key.split(".")[0]
    ranges = getattr(bsdf, "_ranges", None) or {}
    if name in ranges:
        return float(ranges[name].lo), float(ranges[name].hi)
    if "reflectance" in name or "albedo" in name or name in ("weight", "metallic",
                                                             "specular", "sheen"):
        return 0.0, 1.0
    if name.startswith("alpha") or name == "roughness":
        return 1e-3, 1.0
    if key == "eta":  # a dielectric interface's relative index (roughplastic, dielectric)
        return 1.0, 3.0
    return 0.0, math.inf


#: names of positive slope-like parameters (widths, roughnesses), optimised as logarithms
#: whatever their range: a step is then a relative change, and a small value (nickel's
#: Beckmann m = 0.04) cannot be stepped through zero
_SLOPES = ("roughness", "alpha", "alpha_u", "alpha_v", "exponent", "nu", "nv")
#: a bounded parameter starts at least this fraction of its range inside it (its logit is
#: finite there: within +-9.2)
_EDGE = 1e-4
#: a bounded parameter's variable is its logit over this: at mid-range a step of lr moves
#: it by lr times its range, as a step in the parameter itself would
_SLOPE = 4.0


class _Param:
    """One optimised parameter: its key, its range, and the variable Adam sees.

    ``log``: positive parameters spanning decades (exponents; upper bound above 10, or a
    positive lower bound 100 times smaller than the upper one) and slope-like ones
    (``_SLOPES``): y = log x, clamped to the range's logarithms (the lower bound at least
    1e-4 of a finite upper one). ``logit``: other parameters with a finite range (weights,
    reflectances, a dielectric's eta): x = lo + (hi - lo) sigmoid(4 y), inside the range
    whatever the step; a step changes x by at most lr times the range (at mid-range), less
    near a bound (there relative changes, as for a logarithm). ``clamp``: the rest (a lower bound only): y = x, clamped."""

    def __init__(self, key, lo, hi):
        self.key = key
        name = key.split(".")[0]
        self.lo, self.hi = lo, hi
        if (hi > 10 or (lo > 0 and hi / lo > 100) or name in _SLOPES) and hi > 0:
            self.kind = "log"
            floor = max(lo, 1e-6 if hi > 10 else 1e-4 * hi)
            self.bounds = (math.log(floor), math.log(hi))
        elif math.isfinite(hi) and hi > lo:
            self.kind, self.bounds = "logit", (-math.inf, math.inf)
        else:
            self.kind, self.bounds = "clamp", (lo, hi)

    def to_opt(self, x):
        import drjit as dr
        if self.kind == "log":
            return dr.clip(dr.log(dr.maximum(x, math.exp(self.bounds[0]))), *self.bounds)
        if self.kind == "logit":
            t = dr.clip((x - self.lo) / (self.hi - self.lo), _EDGE, 1 - _EDGE)
            return dr.log(t / (1 - t)) / _SLOPE
        return dr.clip(x, *self.bounds)

    def from_opt(self, y):
        import drjit as dr
        if self.kind == "log":
            return dr.exp(y)
        if self.kind == "logit":
            return self.lo + (self.hi - self.lo) / (1 + dr.exp(-_SLOPE * y))
        return y

    def clamp(self, y):
        import drjit as dr
        return dr.clip(y, *self.bounds)


def _free_keys(params, chosen=None):
    """The traverse keys to fit: ``chosen`` (checked), or every differentiable float and
    colour."""
    import mitsuba as mi
    keys = []
    for key in params.keys():
        value = params[key]
        differentiable = params.flags(key) & mi.ParamFlags.NonDifferentiable.value == 0
        is_float = isinstance(value, (mi.Float, mi.Color3f))
        if chosen is not None:
            if key in chosen:
                if not is_float:
                    raise ValueError(f"fit-measured: parameter '{key}' is not a float or "
                                     f"colour (it is {type(value).__name__})")
                keys.append(key)
        elif differentiable and is_float:
            keys.append(key)
    if chosen is not None:
        missing = sorted(set(chosen) - set(keys))
        if missing:
            raise ValueError(f"fit-measured: --params {', '.join(missing)}: not among the "
                             f"parameters of the model ({', '.join(params.keys())})")
    if not keys:
        raise ValueError("fit-measured: the model exposes no float or colour parameter "
                         "through mi.traverse")
    return keys


# -- the fit -----------------------------------------------------------------------------------

def _loss(value, ref, kind):
    import drjit as dr
    if kind == "log":
        d = dr.log(1 + dr.maximum(value, 0)) - dr.log(1 + ref)
    else:
        d = value - ref
    return dr.mean(d.x * d.x + d.y * d.y + d.z * d.z, axis=None)


def _snapshot(params, free):
    """{key: the parameter's current value as float32 numpy} (a copy that later steps leave)."""
    return {p.key: np.array(params[p.key], dtype=np.float32) for p in free}


def _restore(params, values):
    """Set the parameters to a ``_snapshot``."""
    import mitsuba as mi
    for key, v in values.items():
        params[key] = type(params[key])(*v) if v.ndim == 2 else mi.Float(v)
    params.update()


def fit(bsdf, wi, wo, f, iterations=ITERATIONS, loss="l2cos", lr=LR, keys=None,
        progress=None):
    """Fit ``bsdf`` (loaded in a JIT AD RGB variant) to measured values f at (wi, wo).

    Returns the best parameters met: {'loss' (theirs, evaluated again), 'start_loss' (that
    of the start values, as given), 'history' (loss per iteration), 'params' {key: value},
    'lr_cuts' (times a step that doubled the best loss sent the fit back to the best
    parameters with half the learning rate), 'seconds', 'seconds_per_iteration',
    'samples'}; ``bsdf`` is left at the best parameters. ``progress(i, loss)`` is called
    after each step."""
    import drjit as dr
    import mitsuba as mi
    from .validate.probe import interaction, vec
    if loss not in LOSSES:
        raise ValueError(f"fit-measured: --loss must be one of {', '.join(LOSSES)} (got {loss!r})")
    t0 = time.perf_counter()
    params = mi.traverse(bsdf)
    keys = _free_keys(params, keys)
    free = [_Param(k, *_range(bsdf, k)) for k in keys]
    si, v = interaction(wi), vec(wo)
    cos = np.asarray(wo, float)[:, 2:3]
    ref = mi.Color3f(*(np.asarray(f, float) * cos).astype(np.float32).T)
    ctx = mi.BSDFContext()

    def evaluate():
        return _loss(bsdf.eval(ctx, si, v), ref, loss)

    # the start, as given (not through the optimised variables): the fit never ends worse
    with dr.suspend_grad():
        best_loss = start_loss = float(evaluate()[0])
    best = _snapshot(params, free)
    opt = mi.ad.Adam(lr=lr, beta_2=_BETA2)
    for p in free:
        opt[p.key] = p.to_opt(params[p.key])
    best_opt = {p.key: type(opt[p.key])(opt[p.key]) for p in free}
    history, scale, cuts = [], 1.0, 0
    for i in range(iterations):
        opt.set_learning_rate(scale * lr * _DECAY ** (i / iterations))
        for p in free:
            params[p.key] = p.from_opt(opt[p.key])
        params.update()
        lo = evaluate()
        dr.backward(lo)
        value = float(lo[0])
        history.append(value)
        if value < best_loss:
            best_loss, best = value, _snapshot(params, free)
            best_opt = {p.key: type(opt[p.key])(dr.detach(opt[p.key])) for p in free}
            scale = min(1.0, scale * 1.05)
            opt.step()
        elif not value <= 2 * best_loss:    # also NaN
            # the step overshot: back to the best parameters, Adam's moments forgotten,
            # half the step
            for p in free:
                opt[p.key] = type(best_opt[p.key])(best_opt[p.key])
            opt.reset()
            scale, cuts = scale / 2, cuts + 1
        else:
            opt.step()
        for p in free:
            opt[p.key] = p.clamp(opt[p.key])
        if progress:
            progress(i, value)
    _restore(params, best)
    with dr.suspend_grad():
        final = float(evaluate()[0])
    seconds = time.perf_counter() - t0
    values = {key: v.ravel().tolist() for key, v in best.items()}
    return {"loss": final, "start_loss": start_loss, "history": history, "params": values,
            "lr_cuts": cuts, "seconds": seconds,
            "seconds_per_iteration": seconds / max(iterations, 1), "samples": len(wi),
            "iterations": iterations, "loss_kind": loss}


# -- outputs ------------------------------------------------------------------------------------

def bsdf_xml(spec, values):
    """The fitted ``<bsdf version="3.0.0">`` (a file's root element): the model's options
    from ``spec`` (the dict it was loaded from), the fitted values of ``values`` ({traverse
    key: list})."""
    from .presets import to_xml
    out = dict(spec)
    for key, v in values.items():
        name = key[:-len(".value")] if key.endswith(".value") else key
        out[name] = v[0] if len(v) == 1 else {"type": "rgb", "value": v[:3]}
    return to_xml(out, version=True)


def plot_slices(path, bsdf, measured_path, title, theta_d=(10, 45, 75)):
    """Measured (dots) against fitted (lines) f, R G B, against theta_h at three theta_d,
    phi_d = 90 deg, log scale; written whole to ``path`` (``output.save_figure``)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from . import merl
    from .output import save_figure
    from .validate.probe import eval_np
    dims, f = merl.read(measured_path)
    wi, wo = merl.directions(dims)
    nh, nd, nphi = dims
    fig, axes = plt.subplots(1, len(theta_d), figsize=(4 * len(theta_d), 3.4), sharey=True)
    for ax, td in zip(np.atleast_1d(axes), theta_d):
        j, k = min(int(round(td / 90 * nd)), nd - 1), nphi // 2
        idx = (np.arange(nh) * nd + j) * nphi + k
        th = np.degrees((np.arange(nh) / nh) ** 2 * np.pi / 2)
        ok = (wi[idx, 2] > 1e-4) & (wo[idx, 2] > 1e-4)
        model = eval_np(bsdf, wi[idx][ok], wo[idx][ok]) / wo[idx][ok][:, 2:3]
        for c, colour in enumerate("rgb"):
            ax.semilogy(th[ok], f[idx][ok][:, c], ".", color=colour, ms=3, alpha=0.6)
            ax.semilogy(th[ok], np.maximum(model[:, c], 1e-6), "-", color=colour, lw=1)
        ax.set_title(f"theta_d = {np.degrees(j / nd * np.pi / 2):.0f} deg, phi_d = 90 deg",
                     fontsize=9)
        ax.set_xlabel("theta_h (deg)")
    np.atleast_1d(axes)[0].set_ylabel("f (dots: measured, lines: fitted)")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)


# -- the command -------------------------------------------------------------------------------

def add_arguments(p):
    from .arguments import default_out, positive_int
    p.add_argument("file", metavar="FILE", help="a measured isotropic BRDF, MERL's .binary format")
    p.add_argument("--model", required=True,
                   help="a plugin (this package's or Mitsuba's) or a preset model "
                        "(ashikhmin_shirley, blinn_phong, cook_torrance, ward, ward_duer)")
    p.add_argument("--init", metavar="MATERIAL",
                   help="start from this material's Ngan et al. 2005 fit (preset models only)")
    p.add_argument("-p", dest="param", action="append", default=[], metavar="KEY=VALUE",
                   help="a parameter or option of the model (repeatable)")
    p.add_argument("--params", help="comma-separated mi.traverse keys to fit (default: all "
                                    "differentiable floats and colours)")
    p.add_argument("--loss", choices=LOSSES, default="l2cos",
                   help="l2cos: Ngan et al.'s cosine-weighted L2 (default); log: Low et al.'s")
    p.add_argument("--iterations", type=positive_int, default=None,
                   help=f"Adam steps (default: {ITERATIONS}; {BUILTIN_ITERATIONS} for Mitsuba's "
                        f"own plugins)")
    p.add_argument("--samples", type=positive_int, default=SAMPLES,
                   help="measured direction pairs used (default: %(default)s)")
    p.add_argument("--lr", type=float, default=LR, help="Adam's learning rate, in the optimised variables (a relative change for "
                        "slopes and exponents; default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="seed of the subset (default: 0)")
    p.add_argument("--out", default=default_out("fit-measured"),
                   help="directory of the XML, plot and summary (default: %(default)s)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")


def model_spec(model, init=None, options=()):
    """The dict to load: a preset model's plugin (``ward_duer``: ``ward``, form duer), the
    material's preset with ``init``, the ``-p`` options on top."""
    from . import presets
    from .spec import parse_params, parse_value
    if init is not None:
        if model not in presets.MODELS:
            raise ValueError(f"fit-measured: --init needs a preset model ({', '.join(presets.MODELS)}), "
                             f"got --model {model}")
        spec = presets.ngan2005(model, init)
    elif model == "ward_duer":
        spec = {"type": "ward", "form": "duer"}
    else:
        spec = {"type": model}
    spec.update({k: parse_value(v) for k, v in parse_params(options).items()})
    return spec


def colour_spec(spec, bsdf):
    """``spec`` with every reflectance or base colour that ``bsdf`` holds as one number given as
    that grey in RGB, so that the fit finds a colour."""
    import drjit as dr
    import mitsuba as mi
    params = mi.traverse(bsdf)
    out = dict(spec)
    for key in params.keys():
        name = key[:-len(".value")] if key.endswith(".value") else None
        if name is None or not any(w in name for w in ("reflectance", "color", "colour")):
            continue
        value = params[key]
        if isinstance(value, mi.Float) and dr.width(value) == 1 and not isinstance(spec.get(name), dict):
            out[name] = {"type": "rgb", "value": [float(value[0])] * 3}
    return out


def outputs(file, model, out):
    """The files the command writes: ``out/STEM_MODEL`` .xml, .png and .json."""
    stem = os.path.splitext(os.path.basename(file))[0]
    base = os.path.join(out, f"{stem}_{model}")
    return [base + ext for ext in (".xml", ".png", ".json")]


def run(args):
    from . import merl
    from .arguments import UsageError
    from .output import check_folder, check_target, write_json, write_text
    from .variant import set_variant
    if not 0 < args.lr < 10:
        raise UsageError(f"fit-measured: --lr must be in (0, 10), got {args.lr}")
    dims = merl.check_file(args.file)        # a bad file is refused before any work
    spec = model_spec(args.model, args.init, args.param)
    # targets that cannot be written are refused before any work: a folder that cannot
    # be made or written into, a read-only or immutable file
    files = outputs(args.file, args.model, args.out)
    check_folder(args.out, f"fit-measured: --out {args.out}")
    for path in files:
        check_target(path, f"fit-measured: {path}")
    import mitsuba as mi
    from tqdm import tqdm
    set_variant("llvm_ad_rgb")
    try:
        bsdf = mi.load_dict(spec)
    except Exception as e:
        from .presets import suggest
        hint = ""
        if "unknown" in str(e).lower() or "plugin" in str(e).lower():
            from .core.registry import models
            hint = suggest(args.model, list(models()) + ["roughplastic", "roughconductor",
                                                         "principled", "diffuse", "plastic"])
        raise ValueError(f"fit-measured: --model {args.model}{hint}: {e}") from None
    if not isinstance(bsdf, mi.BSDF):
        raise ValueError(f"fit-measured: --model {args.model} is not a BSDF plugin")
    spec = colour_spec(spec, bsdf)
    bsdf = mi.load_dict(spec)
    keys = None if args.params is None else [k.strip() for k in args.params.split(",") if k.strip()]
    _free_keys(mi.traverse(bsdf), keys)      # unknown --params are refused before reading
    from .core.registry import models
    iterations = args.iterations or (ITERATIONS if spec["type"] in models() else BUILTIN_ITERATIONS)
    wi, wo, f = prepare(args.file, args.samples, args.seed)
    with tqdm(total=iterations, desc="fit-measured", unit="it", leave=False,
              disable=args.json) as bar:
        def progress(i, loss):
            bar.update(1)
            if i % 10 == 0:
                bar.set_postfix(loss=f"{loss:.4g}")
        r = fit(bsdf, wi, wo, f, iterations, args.loss, args.lr, keys, progress)
    stem = os.path.splitext(os.path.basename(args.file))[0]
    xml = bsdf_xml(spec, r["params"])
    write_text(files[0], xml + "\n")
    plot_slices(files[1], bsdf, args.file, f"{stem}: {args.model} ({args.loss} loss "
                f"{r['loss']:.3g})")
    summary = {"file": args.file, "dims": list(dims), "model": args.model, "spec": spec,
               **{k: r[k] for k in ("loss", "start_loss", "loss_kind", "params", "seconds",
                                     "seconds_per_iteration", "samples", "iterations", "lr_cuts")},
               "xml": xml, "outputs": files}
    write_json(files[2], summary, indent=1)
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        print(f"{stem}: {args.model}, {args.loss} loss {r['start_loss']:.4g} -> {r['loss']:.4g} "
              f"in {r['iterations']} iterations on {r['samples']} pairs, {r['seconds']:.1f} s "
              f"({1e3 * r['seconds_per_iteration']:.1f} ms per iteration)")
        print(xml)
        print(f"wrote {', '.join(files)}")
    return 0
