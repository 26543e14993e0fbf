"""``python -m mitsuba_brdfs fit-measured FILE --model M``: fit a BSDF to a measured BRDF.

FILE is an isotropic BRDF in MERL's binary format (``mitsuba_brdfs.merl``). M is one of
this package's plugins, one of the ``ngan2005`` preset models (``ward_duer`` is ``ward``
with ``form = duer``), or one of Mitsuba's BSDFs with a lobe that ``eval`` sees
(``MITSUBA_PLUGINS``: ``diffuse``, ``plastic``, ``roughplastic``, ``roughconductor``,
``roughdielectric``, ``principled``, ``principledthin``); ``-p KEY=VALUE`` sets its options
and start values, ``--init MATERIAL`` starts from that material's Ngan et al. 2005 fit (a
preset model).

What is fitted (``mitsuba_brdfs.measured_fit`` does the fitting, whatever the file):

- the shape: a random subset (``--samples``, fixed by ``--seed``) of the measured bins
  with both directions within 80 deg of the normal, each at the centre of its cell (what
  its value stands for, ``merl.directions``), turned by a random phi_h (an isotropic BRDF
  does not see it; an anisotropic model sees both tangent directions); each weighted by
  the measure of the direction pairs its cell covers (``merl.measure``; ``--weights bins``:
  every bin alike, as Ngan et al. count them);
- the energy (``--albedo-weight``, 1 by default): the directional albedo at incidence
  0, 15, ..., 75 deg, integrated over the outgoing directions where the file is measured
  (looked up as MERL's reader does, ``merl.lookup``), the model evaluated where those
  bins' values stand (so a file's own model has the file's albedo exactly).

The optimiser (``--optimizer``): L-BFGS-B from several starts (the default), or Adam
(``--lr``); ``--evaluations`` is its budget (default 1500; 300 for Mitsuba's own plugins,
whose parameter updates are slow: ``roughplastic`` recomputes its transmittance tables at
every change of ``alpha`` or ``eta``, about 0.1 s, and those tables carry no gradient).
``--params`` chooses which ``mi.traverse`` keys move (default: every differentiable float
or colour); reflectances given as one number are fitted as RGB colours.

How good the fit is: the summary gives the loss and its two terms, the relative RMS error
of f cos per channel (scale-free: 0 is exact, 1 as far off as a black model), the
albedo of the data and of the fit at 0, 45 and 75 deg, and warnings: parameters on an
end of their range (``at_bounds`` in the JSON), an albedo more than 10% off, a file of
few bins. docs/presets.md says how to judge a fit and what each model can represent.

Refused before any fit, in one line (exit status 2): a folder or a file that is not a
MERL BRDF (the expected and actual sizes), a file with fewer measured bins within 80 deg
than the model has values to fit, a black file (nothing to fit), a file that reflects
more than 3 times the light it receives at some incidence (values far beyond a BRDF's: a
wrong scale, not a material), a plugin without a lobe that ``eval`` sees (``conductor``:
a mirror), a target that may not be replaced.

Writes, into ``--out`` (default: ``mitsuba_brdfs-out/fit-measured/`` in the current
directory), the fitted ``<bsdf version="3.0.0" ...>`` as ``STEM_MODEL.xml`` (a file that
``check`` and ``mi.load_file`` load, or ``<include filename="..."/>`` inside a
``<shape>``; Mitsuba's dielectric interfaces get ``int_ior``, ``ext_ior``), a plot of
measured against fitted slices (f against theta_h at three theta_d, phi_d = 90 deg) as
``STEM_MODEL.png``, and the summary as ``STEM_MODEL.json``; prints the table of the fit,
its warnings and the XML (``--json``: the summary). Each file is written whole
(``mitsuba_brdfs.output``); a target that may not be replaced (read-only, immutable) or a
folder that cannot be written is refused before the fit. Progress goes to stderr, at most
one line per 5 s where stderr is not a terminal (``progress.progress_bar``).
"""
import json
import os

import numpy as np

__all__ = ["SAMPLES", "BUILTIN_EVALUATIONS", "MITSUBA_PLUGINS", "MAX_ALBEDO", "Measured",
           "prepare", "fit_file", "model_spec", "colour_spec", "bsdf_xml", "plot_slices",
           "outputs", "summary_table", "add_arguments", "run"]

#: every file is written whole (``output.atomic``): an interruption can say what was written
WRITES_ATOMICALLY = True

#: default number of measured pairs of the shape term
SAMPLES = 20_000
#: default budget for Mitsuba's own plugins (their parameter updates are slow)
BUILTIN_EVALUATIONS = 300
#: Mitsuba's BSDFs with a lobe ``eval`` sees, and whose parameters ``mi.traverse`` exposes
MITSUBA_PLUGINS = ("diffuse", "plastic", "roughplastic", "roughconductor", "roughdielectric",
                   "principled", "principledthin")
#: Mitsuba's plugins that take a dielectric interface as int_ior / ext_ior (their traverse
#: exposes the relative index as ``eta``)
_IOR_PLUGINS = ("plastic", "roughplastic", "dielectric", "roughdielectric", "thindielectric")
#: a file whose directional albedo exceeds this somewhere is refused: not a BRDF's values
MAX_ALBEDO = 3.0
#: the incidence angles (deg) the summary and the table report the albedo at
REPORT_THETAS = (0, 45, 75)
#: albedo differences beyond this are warned about
ALBEDO_TOLERANCE = 0.10
#: a file with fewer measured bins than this many per fitted value is warned about
BINS_PER_VALUE = 20
WEIGHTS = ("solid-angle", "bins")


class Measured:
    """What a fit needs of a measured file: the shape term's samples (wi, wo, f, weights),
    the energy term's rows (``albedo``: wi, wo, weight, f; ``measured_fit.fit``), the measured
    bins within 80 deg (``bins``) and the file's ``dims``."""

    def __init__(self, wi, wo, f, weights, albedo, bins, dims):
        self.wi, self.wo, self.f, self.weights = wi, wo, f, weights
        self.albedo, self.bins, self.dims = albedo, bins, dims


# -- the data ----------------------------------------------------------------------------

def prepare(path, samples=SAMPLES, seed=0, weights="solid-angle", position="centre"):
    """The ``Measured`` samples of a MERL file: ``samples`` of its measured bins within
    80 deg (all of them if fewer), float64, with their weights (``WEIGHTS``), and the
    energy term's rows. ``position``: where a bin's sample is (``merl.POSITIONS``; the
    centre of its cell, what the value stands for)."""
    from . import merl
    from .measured_fit import ALBEDO_THETAS, MIN_COS, albedo_quadrature
    if weights not in WEIGHTS:
        raise ValueError(f"--weights must be one of {', '.join(WEIGHTS)} (got {weights!r})")
    dims, f = merl.read(path)
    rng = np.random.default_rng(seed)
    # the bins worth fitting: measured, both directions within 80 deg (a rotation about
    # the normal changes neither)
    wi, wo = merl.directions(dims, position=position)
    usable = np.nonzero(np.isfinite(f).all(1) & (wi[:, 2] > MIN_COS) & (wo[:, 2] > MIN_COS))[0]
    del wi, wo
    bins = len(usable)
    chosen = np.sort(rng.permutation(usable)[:samples])
    wi, wo = merl.directions(dims, rng.uniform(0, 2 * np.pi, len(chosen)), chosen, position)
    w = merl.measure(dims, chosen) if weights == "solid-angle" else np.ones(len(chosen))
    # the energy term: a quadrature of the outgoing directions, each looked up in its bin
    # as MERL's reader does, the model evaluated where the file's values stand (the bin's
    # centre, turned to the quadrature's phi_h), so that a file's own model has the file's
    # albedo exactly
    rows = albedo_quadrature(ALBEDO_THETAS)
    qwi, qwo = rows["wi"].reshape(-1, 3), rows["wo"].reshape(-1, 3)
    index = merl.lookup(qwi, qwo, dims)
    h = qwi + qwo
    cwi, cwo = merl.directions(dims, np.arctan2(h[:, 1], h[:, 0]), index, position)
    shape = rows["weight"].shape
    albedo = {"wi": cwi.reshape(shape + (3,)), "wo": cwo.reshape(shape + (3,)),
              "weight": rows["weight"], "f": f[index].reshape(shape + (3,))}
    return Measured(wi, wo, f[chosen], w, albedo, bins, dims)


def _refuse_values(path, data):
    """ValueError (one line) where the file's albedo is beyond any BRDF's."""
    from .measured_fit import ALBEDO_THETAS, albedo_of
    if not np.any(data.f > 0):
        raise ValueError(f"{path}: every measured value within 80 deg is 0: a black "
                         f"material, nothing to fit")
    a = albedo_of(data.albedo)
    if np.nanmax(a) > MAX_ALBEDO:
        i, c = np.unravel_index(np.nanargmax(a), a.shape)
        fmax = np.nanmax(data.f)
        raise ValueError(
            f"{path}: reflects {a[i, c]:.3g} times the light it receives at "
            f"{ALBEDO_THETAS[i]} deg ({'RGB'[c]}; values up to {fmax:.3g}): a BRDF "
            f"reflects at most 1; a MERL file holds f times 1500 (red), 1500/1.15 (green), "
            f"1500/1.66 (blue)")


# -- the model ---------------------------------------------------------------------------

def model_spec(model, init=None, options=()):
    """The dict to load: a preset model's plugin (``ward_duer``: ``ward``, form duer), the
    material's preset with ``init``, the ``-p`` options on top."""
    from . import presets
    from .spec import parse_params, parse_value
    if init is not None:
        if model not in presets.MODELS:
            raise ValueError(f"fit-measured: --init needs a preset model "
                             f"({', '.join(presets.MODELS)}), got --model {model}")
        spec = presets.ngan2005(model, init)
    elif model == "ward_duer":
        spec = {"type": "ward", "form": "duer"}
    else:
        spec = {"type": model}
    spec.update({k: parse_value(v) for k, v in parse_params(options).items()})
    return spec


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


def _load_model(spec, model):
    """The BSDF of ``spec`` (its colours as RGB), or ValueError in one line: an unknown
    plugin (with a suggestion), not a BSDF, a Mitsuba plugin without a lobe to fit."""
    import mitsuba as mi
    from .core.registry import models
    try:
        bsdf = mi.load_dict(spec)
    except Exception as e:
        from .presets import suggest
        from .messages import last_line
        if "not found" in str(e):
            hint = suggest(model, list(models()) + list(MITSUBA_PLUGINS) + ["ward_duer"])
            raise ValueError(f"fit-measured: --model {model}: no such plugin{hint}") from None
        raise ValueError(f"fit-measured: --model {model}: {last_line(e)}") from None
    if not isinstance(bsdf, mi.BSDF):
        raise ValueError(f"fit-measured: --model {model} is not a BSDF plugin")
    if spec["type"] not in models() and spec["type"] not in MITSUBA_PLUGINS:
        flags = bsdf.flags()
        smooth = flags & (mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.GlossyReflection)
        why = ("it has no reflection that eval sees (none, or a delta lobe: a mirror)"
               if not smooth else "a plugin fit-measured does not know how to write back")
        raise ValueError(f"fit-measured: --model {spec['type']}: {why}; Mitsuba's plugins "
                         f"it fits: {', '.join(MITSUBA_PLUGINS)}")
    spec = colour_spec(spec, bsdf)
    return spec, mi.load_dict(spec)


# -- the fit -----------------------------------------------------------------------------

def fit_file(data, bsdf, loss="l2cos", keys=None, optimizer="lbfgs", evaluations=None,
             albedo_weight=None, lr=0.05, progress=None, shape_weight=1.0):
    """``measured_fit.fit`` of ``bsdf`` to a file's ``Measured`` data; the result with its
    ``quality`` ('relative_rms', 'relative_rms_max'), the albedo at ``REPORT_THETAS``
    ('albedo': {'thetas', 'measured', 'fitted'}) and 'warnings' (sentences)."""
    from .measured_fit import ALBEDO_THETAS, ALBEDO_WEIGHT, bound_warnings, fit, quality
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


# -- outputs ------------------------------------------------------------------------------------

def _fmt(x):
    """A fitted number with the digits that give back its float32."""
    return f"{float(x):.9g}"


def bsdf_xml(spec, values):
    """The fitted ``<bsdf version="3.0.0">`` (a file's root element): the model's options
    from ``spec`` (the dict it was loaded from), the fitted values of ``values`` ({traverse
    key: list}), under the names the plugin reads (``eta`` of Mitsuba's dielectric
    interfaces as ``int_ior`` over ``ext_ior``)."""
    from .presets import XML_VERSION
    out = {k: v for k, v in spec.items() if k != "type"}
    for key, v in values.items():
        name = key[:-len(".value")] if key.endswith(".value") else key
        out[name] = v[0] if len(v) == 1 else {"type": "rgb", "value": list(v[:3])}
    if spec["type"] in _IOR_PLUGINS and "eta" in out:
        ext = _ext_ior(spec)
        out.pop("int_ior", None)
        out["int_ior"] = float(out.pop("eta")) * ext
        out["ext_ior"] = ext
    lines = [f'<bsdf version="{XML_VERSION}" type="{spec["type"]}">']
    for key, value in out.items():
        if isinstance(value, dict):
            text = ", ".join(_fmt(v) for v in value["value"])
            lines.append(f'    <rgb name="{key}" value="{text}"/>')
        elif isinstance(value, bool):
            lines.append(f'    <boolean name="{key}" value="{str(value).lower()}"/>')
        elif isinstance(value, str):
            lines.append(f'    <string name="{key}" value="{value}"/>')
        elif isinstance(value, int):
            lines.append(f'    <integer name="{key}" value="{value}"/>')
        else:
            lines.append(f'    <float name="{key}" value="{_fmt(value)}"/>')
    return "\n".join(lines + ["</bsdf>"])


def _ext_ior(spec):
    """The exterior index of a dielectric interface as ``spec`` gives it (a number or one
    of Mitsuba's material names), 1 where it gives none."""
    ext = spec.get("ext_ior", 1.0)
    if isinstance(ext, str):  # a material name: Mitsuba's table, through a probe
        import mitsuba as mi
        probe = mi.traverse(mi.load_dict({"type": "roughplastic", "int_ior": 1.0,
                                          "ext_ior": ext}))
        ext = 1 / float(probe["eta"][0])
    return float(ext)


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


def outputs(file, model, out):
    """The files the command writes: ``out/STEM_MODEL`` .xml, .png and .json."""
    stem = os.path.splitext(os.path.basename(file))[0]
    base = os.path.join(out, f"{stem}_{model}")
    return [base + ext for ext in (".xml", ".png", ".json")]


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


# -- the command -------------------------------------------------------------------------------

def add_arguments(p):
    from .arguments import default_out, nonnegative_int, positive_int
    from .measured_fit import ALBEDO_WEIGHT, EVALUATIONS, LOSSES, OPTIMIZERS
    p.add_argument("file", metavar="FILE", help="a measured isotropic BRDF, MERL's .binary format")
    p.add_argument("--model", required=True,
                   help="a plugin (this package's, or one of Mitsuba's: "
                        f"{', '.join(MITSUBA_PLUGINS)}) or a preset model "
                        "(ashikhmin_shirley, blinn_phong, cook_torrance, ward, ward_duer)")
    p.add_argument("--init", metavar="MATERIAL",
                   help="start from this material's Ngan et al. 2005 fit (preset models only)")
    p.add_argument("-p", dest="param", action="append", default=[], metavar="KEY=VALUE",
                   help="a parameter or option of the model (repeatable)")
    p.add_argument("--params", help="comma-separated mi.traverse keys to fit (default: all "
                                    "differentiable floats and colours)")
    p.add_argument("--loss", choices=LOSSES, default="l2cos",
                   help="shape term: l2cos, Ngan et al.'s cosine-weighted L2 (default); "
                        "log: Low et al.'s")
    p.add_argument("--weights", choices=WEIGHTS, default="solid-angle",
                   help="a bin's weight in the shape term: the measure of the direction "
                        "pairs it covers (default), or 1 (as Ngan et al.)")
    p.add_argument("--albedo-weight", type=_nonnegative_float, default=ALBEDO_WEIGHT,
                   help="weight of the energy term, the directional albedo's relative "
                        "error (default: %(default)s; 0: the shape alone)")
    p.add_argument("--optimizer", choices=OPTIMIZERS, default="lbfgs",
                   help="lbfgs: L-BFGS-B from several starts (default); adam")
    p.add_argument("--evaluations", "--iterations", dest="evaluations", type=nonnegative_int,
                   default=None,
                   help=f"budget of loss evaluations (default: {EVALUATIONS}; "
                        f"{BUILTIN_EVALUATIONS} for Mitsuba's own plugins; 0: evaluate the "
                        f"start)")
    p.add_argument("--samples", type=positive_int, default=SAMPLES,
                   help="measured direction pairs of the shape term (default: %(default)s)")
    p.add_argument("--lr", type=float, default=0.05,
                   help="Adam's learning rate, in the optimised variables (a relative "
                        "change for slopes and exponents; default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="seed of the subset (default: 0)")
    p.add_argument("--out", default=default_out("fit-measured"),
                   help="directory of the XML, plot and summary (default: %(default)s)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")


def _nonnegative_float(text):
    import argparse
    from .arguments import finite_float
    value = finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text}")
    return value


def run(args):
    from . import merl
    from .arguments import UsageError
    from .output import check_folder, check_target, write_json, write_text
    from .progress import advance, progress_bar
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
    from .core.registry import models
    from .measured_fit import EVALUATIONS, free_keys
    set_variant("llvm_ad_rgb")
    spec, bsdf = _load_model(spec, args.model)
    keys = None if args.params is None else [k.strip() for k in args.params.split(",") if k.strip()]
    try:                                      # unknown --params are refused before reading
        keys = free_keys(mi.traverse(bsdf), keys)
    except ValueError as e:
        raise ValueError(f"fit-measured: {e}") from None
    values = sum(3 if isinstance(mi.traverse(bsdf)[k], mi.Color3f) else 1 for k in keys)
    data = prepare(args.file, args.samples, args.seed, args.weights)
    if data.bins < values:
        raise ValueError(f"{args.file}: {data.bins} measured bin{'s' * (data.bins != 1)} "
                         f"within 80 deg of the normal ({dims[0]} x {dims[1]} x {dims[2]} "
                         f"bins), fewer than the {values} values {args.model} fits")
    _refuse_values(args.file, data)
    evaluations = args.evaluations
    if evaluations is None:
        evaluations = EVALUATIONS if spec["type"] in models() else BUILTIN_EVALUATIONS
    with progress_bar(evaluations, "fit-measured", "evaluations",
                      enabled=not args.json) as bar:
        def progress(loss):
            advance(bar, 1, f"loss {loss:.4g}")
        r = fit_file(data, bsdf, args.loss, keys, args.optimizer, evaluations,
                     args.albedo_weight, args.lr, progress)
        bar.update(bar.total - bar.n)          # converged early: the bar ends full
    stem = os.path.splitext(os.path.basename(args.file))[0]
    xml = bsdf_xml(spec, r["params"])
    write_text(files[0], xml + "\n")
    plot_slices(files[1], bsdf, args.file, f"{stem}: {args.model} (relative RMS "
                f"{r['relative_rms_max']:.3g})")
    summary = {"file": args.file, "dims": list(dims), "bins": data.bins, "model": args.model,
               "spec": spec, "weights": args.weights,
               **{k: r[k] for k in ("loss", "shape", "energy", "start_loss", "loss_kind",
                                     "albedo_weight", "relative_rms", "relative_rms_max",
                                     "albedo", "params", "at_bounds", "warnings",
                                     "optimizer", "evaluations", "seconds",
                                     "seconds_per_evaluation", "samples", "lr_cuts")},
               "xml": xml, "outputs": files}
    write_json(files[2], summary, indent=1)
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        print(summary_table([(args.model, r)]))
        for w in r["warnings"]:
            print(f"warning: {w}")
        print(xml)
        print(f"wrote {', '.join(files)}")
    return 0
