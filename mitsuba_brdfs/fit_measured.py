"""``python -m mitsuba_brdfs fit-measured FILE --model M``: fit a BSDF to measured data.

FILE is a measured isotropic BRDF in MERL's binary format (``.binary``, recognised by its
size) or an RGL material file (``*.bsdf``, recognised by its ``tensor_file`` header: RGB
files as they are, spectral ones turned into linear sRGB); ``--target SPEC [-p KEY=VALUE
...]`` instead fits any BSDF that ``check`` takes (a plugin, an XML file's ``<bsdf>``, a
``--load FILE.py`` plugin): converting one model into another. M is one of this package's
plugins, one of the ``ngan2005`` preset models (``ward_duer`` is ``ward`` with ``form =
duer``), or one of Mitsuba's BSDFs with a lobe that ``eval`` sees (``MITSUBA_PLUGINS``);
``-p KEY=VALUE`` after ``--model`` sets its options and start values, ``--init MATERIAL``
starts from that material's Ngan et al. 2005 fit (a preset model). With ``--target``,
each ``-p`` belongs to the ``--target`` or ``--model`` before it. ``--model
lambert,ward,...`` fits each model and ranks them (``--rank-by``) by how far their renders
look from the measurement's (``image``, the default) or by their loss on held-out pairs
(``holdout``).

What is fitted (``measured.data`` reads the data, ``measured.fitting`` fits, whatever the
data): the shape, on a random subset (``--samples``, fixed by ``--seed``) of the measured
pairs with both directions within 80 deg of the normal, each weighted by the measure of
the direction pairs it stands for (``--weights bins``: every sample alike); the energy
(``--albedo-weight``, 1 by default), the directional albedo at incidence 0, 15, ..., 75
deg; and a constraint on that albedo (``--albedo-tolerance``, 8% by default): wherever
the model can, the fit reflects within 10% of the data's light at every incidence and
channel, the shape deciding within the tolerance, and says what that cost in shape
(``--shape-only``: the shape alone, no energy term, no constraint). Other pairs
(``data.HOLDOUT``) are held out: the loss there (``holdout_loss``; ``holdout_losses``
under each of ``l2cos``, ``log`` and ``cbrt``, ``--loss`` choosing the fit's, see
``measured.losses``). On isotropic data an anisotropic model's two widths are fitted as
one (``nu`` = ``nv``, ``alpha_u`` = ``alpha_v``) unless ``--anisotropic``.

The image judge (``measured.judge``; ``--image-res``, ``--image-spp``, 0: off): each fit
and the measurement (an RGL file through Mitsuba's ``measured``, a MERL file through its
RGL conversion, a ``--target`` as itself) rendered on one sphere under the ``ngan2005``
figure's environment and a lamp, from three sides, compared by Delta E ITP: the fit's
``image_error`` (mean, 95th percentile). ``--select image`` fits each model from a
candidate per loss and start (``measured.select``) and keeps the closest-looking.

The optimiser (``--optimizer``): L-BFGS-B from several starts (the default), or Adam
(``--lr``); ``--evaluations`` is its budget per stage (default 1500; 300 for Mitsuba's own
plugins, whose parameter updates are slow: ``roughplastic`` recomputes its transmittance
tables at every change of ``alpha`` or ``eta``, about 0.1 s, and those tables carry no
gradient). ``--params`` chooses which ``mi.traverse`` keys move (default: every
differentiable float or colour); reflectances given as one number are fitted as RGB
colours.

How good the fit is: the table and the summary give the loss and its two terms, the
held-out loss, the relative RMS error of f cos per channel (scale-free: 0 is exact, 1 as
far off as a black model), the albedo of the data and of the fit at 0, 45 and 75 deg, and
warnings: parameters on an end of their range (``at_bounds`` in the JSON), the albedo
constraint's cost or why the model cannot meet it, few samples, negative values.
docs/presets.md says how to judge a fit and what each model can represent.

Refused before any fit, in one line (exit status 2): a folder, a missing, truncated or
foreign file, data with fewer samples within 80 deg than the model has values to fit,
black data (nothing to fit), data that reflects more than 3 times the light it receives
at some incidence (a wrong scale, not a material), a plugin without a lobe that ``eval``
sees (``conductor``: a mirror), an output that may not be replaced.

Writes, into ``--out`` (default: ``mitsuba_brdfs-out/fit-measured/`` in the current
directory), for each model the fitted ``<bsdf version="3.0.0" ...>`` as ``STEM_MODEL.xml``
(a file that ``check`` and ``mi.load_file`` load; Mitsuba's dielectric interfaces get
``int_ior``, ``ext_ior``) and its summary as ``STEM_MODEL.json``; a plot of the measured
slices (f against theta_h at three theta_d, phi_d = 90 deg) with the fits over them,
``STEM_MODEL.png`` for one model, ``STEM_fits.png`` (each fit labelled with its image
error and held-out loss; and the ranked summaries, ``STEM_fits.json``) for several; the
judge's renders, ``STEM_images.png``. STEM is FILE's name with its extension
(``gold-paint.binary_ward.xml``; the RGL file ``gold-paint.bsdf`` made from it gets
``gold-paint.bsdf_ward.xml``), or the target's (``ward``, ``nickel.xml``); a run on the same
STEM replaces its files. Prints the table, the warnings and, for one model, the XML
(``--json``: the summary, or ``{"fits": [...]}`` in ranked order). Each file is written
whole (``mitsuba_brdfs.output``). Progress goes to stderr, at most one line per 5 s where
stderr is not a terminal: the evaluations done and the objective of the stage running (the
loss, then in the albedo constraint's stages the energy weighted 1000 times or a penalty
added: larger than the loss); once a model is done, its loss as the table gives it.
"""
import argparse
import json
import os
import re
import time

__all__ = ["stem", "outputs", "add_arguments", "run"]

#: every file is written whole (``output.atomic``): an interruption can say what was written
WRITES_ATOMICALLY = True


def stem(args):
    """The outputs' stem: FILE's name with its extension, or the target's (its file's name
    with its extension, or the plugin), so that ``gold-paint.binary`` and the RGL file
    ``gold-paint.bsdf`` made from it have outputs of their own."""
    name = args.file if args.file is not None else args.target
    base = os.path.basename(os.path.normpath(name))
    return re.sub(r"[^\w.+-]", "_", base).strip(".") or "target"


def outputs(file_stem, models, out, images=False):
    """The files the command writes: ``out/STEM_MODEL`` .xml and .json for each model;
    the plot ``STEM_MODEL.png`` for one, ``STEM_fits.png`` and ``STEM_fits.json`` for
    several; with the image judge (``images``), its renders ``STEM_images.png`` last."""
    base = lambda name: os.path.join(out, f"{file_stem}_{name}")
    extra = [base("images") + ".png"] if images else []
    if len(models) == 1:
        return [base(models[0]) + ext for ext in (".xml", ".png", ".json")] + extra
    return ([base(m) + ext for m in models for ext in (".xml", ".json")]
            + [base("fits") + ".png", base("fits") + ".json"] + extra)


# -- the command line --------------------------------------------------------------------

class _Owner(argparse.Action):
    """``--model`` and ``--target``: stored, and the ``-p`` items after them are theirs."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        namespace._owner = self.dest


class _Param(argparse.Action):
    """``-p KEY=VALUE``: the target's after ``--target``, else the model's."""

    def __call__(self, parser, namespace, values, option_string=None):
        dest = "target_param" if getattr(namespace, "_owner", None) == "target" else "param"
        getattr(namespace, dest).append(values)


def _tolerance(text):
    if text.lower() == "none":
        return None
    value = _nonnegative_float(text)
    if not value < 1:
        raise argparse.ArgumentTypeError(f"must be in [0, 1) or none, got {text}")
    return value


def _nonnegative_float(text):
    from .arguments import finite_float
    value = finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text}")
    return value


def add_arguments(p):
    from .arguments import add_load, default_out, nonnegative_int, positive_int
    from .measured.data import SAMPLES, WEIGHTS
    from .measured.fitting import (ALBEDO_TOLERANCE, ALBEDO_WEIGHT, EVALUATIONS, LOSSES,
                                   OPTIMIZERS)
    from .measured.plugins import BUILTIN_EVALUATIONS, MITSUBA_PLUGINS
    from .measured.judge import RES as JUDGE_RES, SPP as JUDGE_SPP
    from .measured.select import RANK_BY, SELECT
    p.add_argument("file", metavar="FILE", nargs="?",
                   help="a measured BRDF: a MERL .binary file or an RGL .bsdf file")
    p.add_argument("--target", action=_Owner, metavar="SPEC",
                   help="fit this BSDF instead of a file: a plugin (with -p after it), an "
                        "XML file's <bsdf>, a --load plugin")
    add_load(p)
    p.add_argument("--model", required=True, action=_Owner,
                   help="a plugin (this package's, or one of Mitsuba's: "
                        f"{', '.join(MITSUBA_PLUGINS)}) or a preset model "
                        "(ashikhmin_shirley, blinn_phong, cook_torrance, ward, ward_duer); "
                        "several, comma-separated, are each fitted and ranked")
    p.add_argument("--init", metavar="MATERIAL",
                   help="start from this material's Ngan et al. 2005 fit (preset models only)")
    p.add_argument("-p", dest="param", action=_Param, default=[], metavar="KEY=VALUE",
                   help="an option or start value of the model, or after --target of the "
                        "target (repeatable)")
    p.set_defaults(target_param=[])
    p.add_argument("--params", help="comma-separated mi.traverse keys to fit (default: all "
                                    "differentiable floats and colours)")
    p.add_argument("--loss", choices=LOSSES, default="l2cos",
                   help="shape term: l2cos, Ngan et al.'s cosine-weighted L2 (default); "
                        "log: Low et al.'s log(1 + f cos); cbrt: Fores et al.'s cube root "
                        "(measured/losses.py says when each helps)")
    p.add_argument("--rank-by", choices=RANK_BY, default=None,
                   help="order of the fits: image, by the image judge's colour difference "
                        "(default); holdout, by the held-out loss (the default with "
                        "--image-spp 0)")
    p.add_argument("--select", choices=SELECT, default="loss",
                   help="each model's fit: loss, the one its loss finds best (default); "
                        "image, the candidate (each loss, each start) whose renders look "
                        "closest to the measurement's")
    p.add_argument("--anisotropic", action="store_true",
                   help="fit an anisotropic model's two widths (nu, nv; alpha_u, alpha_v) "
                        "apart on isotropic data too (default: held equal there)")
    p.add_argument("--image-res", type=positive_int, default=JUDGE_RES, metavar="N",
                   help="the image judge's renders: N x N pixels per view "
                        "(default: %(default)s)")
    p.add_argument("--image-spp", type=nonnegative_int, default=JUDGE_SPP, metavar="N",
                   help="the image judge's samples per pixel (default: %(default)s; 0: no "
                        "image judge)")
    p.add_argument("--weights", choices=WEIGHTS, default="solid-angle",
                   help="a sample's weight in the shape term: the measure of the direction "
                        "pairs it stands for (default), or 1 (as Ngan et al.)")
    p.add_argument("--albedo-weight", type=_nonnegative_float, default=ALBEDO_WEIGHT,
                   help="weight of the energy term, the directional albedo's relative "
                        "error (default: %(default)s; 0: none)")
    p.add_argument("--albedo-tolerance", type=_tolerance, default=ALBEDO_TOLERANCE,
                   metavar="FRACTION",
                   help="keep the fit's albedo within this fraction of the data's wherever "
                        "the model can, once it is more than 10%% off (default: "
                        "%(default)s; none: no constraint)")
    p.add_argument("--shape-only", action="store_true",
                   help="fit the shape alone: no energy term, no albedo constraint")
    p.add_argument("--optimizer", choices=OPTIMIZERS, default="lbfgs",
                   help="lbfgs: L-BFGS-B from several starts (default); adam")
    p.add_argument("--evaluations", "--iterations", dest="evaluations", type=nonnegative_int,
                   default=None,
                   help=f"budget of loss evaluations per stage (default: {EVALUATIONS}; "
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


def _models(args):
    """The models named by ``--model`` (comma-separated), refused in one line where empty,
    repeated, or given ``-p``, ``--params`` or a non-preset ``--init`` with several."""
    from .arguments import UsageError
    models = [m.strip() for m in args.model.split(",")]
    if not all(models):
        raise UsageError(f"fit-measured: --model {args.model}: an empty model name")
    if len(set(models)) != len(models):
        raise UsageError(f"fit-measured: --model {args.model}: a model named twice")
    if len(models) > 1 and (args.param or args.params):
        raise UsageError(f"fit-measured: -p and --params set one model's parameters: give "
                         f"one --model (got {len(models)})")
    return models


# -- the run -----------------------------------------------------------------------------

def run(args):
    from .arguments import UsageError
    from .measured.plugins import load_model, model_spec
    from .measured.reader import kind
    from .output import check_folder, check_target
    from .spec import locate, parse_params
    from .variant import run_file, set_variant
    if not 0 < args.lr < 10:
        raise UsageError(f"fit-measured: --lr must be in (0, 10), got {args.lr}")
    if (args.file is None) == (args.target is None):
        raise UsageError("fit-measured: give a measured FILE or --target SPEC (one of them)")
    if args.target_param and args.target is None:
        raise UsageError("fit-measured: -p before --model sets the target's parameters: "
                         "give --target SPEC")
    models = _models(args)
    target_params = parse_params(args.target_param)
    if args.file is not None:
        kind(locate(args.file))                 # a bad file is refused before any work
    else:
        locate(args.target)
    specs = {m: model_spec(m, args.init, args.param) for m in models}
    if args.select == "image" and not args.image_spp:
        raise UsageError("fit-measured: --select image judges the candidates by their "
                         "renders: give --image-spp above 0")
    if args.rank_by == "image" and not args.image_spp:
        raise UsageError("fit-measured: --rank-by image needs the image judge: give "
                         "--image-spp above 0, or --rank-by holdout")
    # outputs that cannot be written are refused before any work
    files = outputs(stem(args), models, args.out, images=bool(args.image_spp))
    check_folder(args.out, f"fit-measured: --out {args.out}")
    for path in files:
        check_target(path, f"fit-measured: {path}")
    set_variant("llvm_ad_rgb")
    for path in args.load:
        run_file(path)
    loaded = {m: load_model(specs[m], m) for m in models}
    keys = {m: _keys(args, m, loaded[m][1]) for m in models}
    data, name, target = _data(args, target_params)
    values = max(_values(loaded[m][1], keys[m]) for m in models)
    if data.bins < values:
        raise ValueError(f"{name}: {data.bins} measured sample{'s' * (data.bins != 1)} within "
                         f"80 deg of the normal{_dims(data)}, fewer than the {values} values "
                         f"{args.model} fits")
    from .measured.data import refuse_values
    refuse_values(name, data)
    judge = None
    if args.image_spp:
        from .measured import judge as J
        reference, how = J.reference(args.file, target)
        judge = J.Judge(reference, args.image_res, args.image_spp)
        judge.how = how
    fits = _fit_all(args, models, loaded, keys, data, judge)
    _write(args, name, data, models, loaded, fits, files, judge)
    return 0


def _keys(args, model, bsdf):
    import mitsuba as mi
    from .measured.variables import free_keys
    chosen = None if args.params is None else [k.strip() for k in args.params.split(",")
                                               if k.strip()]
    try:                                      # unknown --params are refused before reading
        return free_keys(mi.traverse(bsdf), chosen)
    except ValueError as e:
        raise ValueError(f"fit-measured: {e}") from None


def _values(bsdf, keys):
    import mitsuba as mi
    params = mi.traverse(bsdf)
    return sum(3 if isinstance(params[k], mi.Color3f) else 1 for k in keys)


def _dims(data):
    return (f" ({data.dims[0]} x {data.dims[1]} x {data.dims[2]} bins)"
            if data.dims is not None and data.kind == "merl" else "")


def _data(args, target_params):
    """(the ``Measured`` data, the name that messages give it, the ``--target`` BSDF or
    None)."""
    from .measured import data as D
    if args.file is not None:
        return D.prepare(args.file, args.samples, args.seed, args.weights), args.file, None
    from .spec import load_bsdfs
    bsdfs = load_bsdfs(args.target, target_params)
    if len(bsdfs) != 1:
        raise ValueError(f"fit-measured: --target {args.target} holds {len(bsdfs)} BSDFs "
                         f"({', '.join(n for n, _ in bsdfs)}): give an XML file with one <bsdf>")
    name = " ".join([args.target] + [f"{k}={v}" for k, v in target_params.items()])
    return (D.prepare_bsdf(bsdfs[0][1], name, args.samples, args.seed, args.weights), name,
            bsdfs[0][1])


def _fit_all(args, models, loaded, keys, data, judge=None):
    """{model: the result of ``select.select_fit`` (``report.fit_file``'s, with
    'holdout_loss', 'holdout_losses', 'image_error'), with 'seconds_total'}; ``loaded``
    gets each model's fitted BSDF."""
    import mitsuba as mi
    from .core.registry import models as package_models
    from .measured.fitting import EVALUATIONS
    from .measured.losses import LOSSES
    from .measured.plugins import BUILTIN_EVALUATIONS
    from .measured.select import select_fit
    from .progress import advance, progress_bar
    budget = {m: args.evaluations if args.evaluations is not None else
              EVALUATIONS if loaded[m][0]["type"] in package_models() else BUILTIN_EVALUATIONS
              for m in models}
    rounds = len(LOSSES) if args.select == "image" else 1
    weight = 0.0 if args.shape_only else args.albedo_weight
    tolerance = None if args.shape_only else args.albedo_tolerance
    out = {}
    with progress_bar(rounds * sum(budget.values()), "fit-measured", "evaluations",
                      enabled=not args.json) as bar:
        for m in models:
            def progress(objective, m=m):
                if bar.n >= bar.total:          # a constraint's stages: more to come
                    bar.total = bar.n + budget[m] // 2
                # the running stage's objective: the loss, or in the albedo constraint's
                # stages the energy weighted more or a penalty added (larger than the loss)
                advance(bar, 1, f"{m}: objective {objective:.4g}")
            t0 = time.perf_counter()
            spec = loaded[m][0]
            r, bsdf = select_fit(data, lambda spec=spec: mi.load_dict(spec), judge,
                                 args.select, args.loss, budget[m], progress, keys=keys[m],
                                 optimizer=args.optimizer, albedo_weight=weight, lr=args.lr,
                                 albedo_tolerance=tolerance,
                                 isotropic=False if args.anisotropic else None)
            r["seconds_total"] = time.perf_counter() - t0
            loaded[m] = (spec, bsdf)
            out[m] = r
            advance(bar, 0, f"{m}: loss {r['loss']:.4g}, as in the table")
        bar.total = bar.n                       # done: the bar ends full when it closes
    return out


def _write(args, name, data, models, loaded, fits, files, judge=None):
    from .measured.plugins import bsdf_xml
    from .measured.report import fit_summary, summary_table
    from .measured.slices import plot_slices
    from .measured.select import ranked as rank
    from .output import write_json, write_text
    notes = []
    if data.negative:
        notes.append(f"{data.negative} of the data's values are negative (out-of-gamut "
                     f"colours): kept, as Mitsuba's measured renders them (docs/measured.md)")
    if judge is not None:
        notes.append(f"image error: Delta E ITP of the fit's renders against the "
                     f"measurement's ({judge.how}), {judge.res} x {judge.res} pixels, "
                     f"{judge.spp} spp, three views (measured/judge.py)")
    images, files = (files[-1], files[:-1]) if judge is not None else (None, files)
    rank_by = args.rank_by or ("image" if judge is not None else "holdout")
    ranked = rank(fits, rank_by)
    summaries = {}
    for i, m in enumerate(models):
        spec, bsdf = loaded[m]
        xml = bsdf_xml(spec, fits[m]["params"])
        mine = files[2 * i:2 * i + 2] if len(models) > 1 else files[:3]
        write_text(mine[0], xml + "\n")
        summaries[m] = fit_summary(args, name, data, m, spec, fits[m], xml, mine, notes)
        summaries[m]["rank_by"] = rank_by
    file_stem = stem(args)
    title = (f"{file_stem}: {models[0]} (relative RMS {fits[models[0]]['relative_rms_max']:.3g})"
             if len(models) == 1 else f"{file_stem}: {len(models)} models, best first "
                                      f"(by {'image error' if rank_by == 'image' else 'held-out loss'})")
    labels = {m: m if len(models) == 1 else f"{m} ({_judged(fits[m])})" for m in ranked}
    plot_slices(files[1] if len(models) == 1 else files[-2],
                [(labels[m], loaded[m][1]) for m in ranked], data.evaluate, title,
                dims=data.dims if data.kind == "merl" else None)
    if images is not None:
        from .measured.judge import figure
        figure(images, [(f"measurement\n({judge.how})", judge.reference)]
               + [(f"{m}\n{_judged(fits[m])}", fits[m]["_images"]) for m in ranked],
               f"{file_stem}: the measurement and its fits, best first")
    for m in models:
        write_json(summaries[m]["outputs"][-1], summaries[m], indent=1)
    if len(models) > 1:
        write_json(files[-1], {"fits": [summaries[m] for m in ranked]}, indent=1)
    written = files + ([images] if images else [])
    if args.json:
        out = summaries[models[0]] if len(models) == 1 else \
            {"fits": [summaries[m] for m in ranked]}
        print(json.dumps(out, indent=1))
        return
    print(summary_table([(m, fits[m]) for m in ranked]))
    for note in notes:
        print(f"note: {note}")
    for m in ranked:
        for w in fits[m]["warnings"]:
            print(f"warning: {w}" if len(models) == 1 else f"warning: {m}: {w}")
    if len(models) == 1:
        print(summaries[models[0]]["xml"])
    print(f"wrote {', '.join(written)}")


def _judged(r):
    """A fit's image error and held-out loss in a few words."""
    e = r.get("image_error")
    image = f"Delta E {e['mean']:.2f}, " if e else ""
    return f"{image}held-out {r['holdout_loss']:.3g}"
