"""``python -m mitsuba_brdfs fit-measured FILE --model M``: fit a BSDF to a measured BRDF.

FILE is an isotropic BRDF in MERL's binary format (``measured.merl``). M is one of
this package's plugins, one of the ``ngan2005`` preset models (``ward_duer`` is ``ward``
with ``form = duer``), or one of Mitsuba's BSDFs with a lobe that ``eval`` sees
(``MITSUBA_PLUGINS``: ``diffuse``, ``plastic``, ``roughplastic``, ``roughconductor``,
``roughdielectric``, ``principled``, ``principledthin``); ``-p KEY=VALUE`` sets its options
and start values, ``--init MATERIAL`` starts from that material's Ngan et al. 2005 fit (a
preset model).

What is fitted (``measured.data`` reads the file, ``measured.fitting`` fits, whatever the
file):

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

__all__ = ["outputs", "add_arguments", "run"]

#: every file is written whole (``output.atomic``): an interruption can say what was written
WRITES_ATOMICALLY = True


def outputs(file, model, out):
    """The files the command writes: ``out/STEM_MODEL`` .xml, .png and .json."""
    stem = os.path.splitext(os.path.basename(file))[0]
    base = os.path.join(out, f"{stem}_{model}")
    return [base + ext for ext in (".xml", ".png", ".json")]


# -- the command -------------------------------------------------------------------------------

def add_arguments(p):
    from .arguments import default_out, nonnegative_int, positive_int
    from .measured.data import SAMPLES, WEIGHTS
    from .measured.fitting import ALBEDO_WEIGHT, EVALUATIONS, LOSSES, OPTIMIZERS
    from .measured.plugins import BUILTIN_EVALUATIONS, MITSUBA_PLUGINS
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
    from .arguments import UsageError
    from .measured import merl
    from .measured.data import prepare, refuse_values
    from .measured.plugins import BUILTIN_EVALUATIONS, bsdf_xml, load_model, model_spec
    from .measured.report import fit_file, plot_slices, summary_table
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
    from .measured.fitting import EVALUATIONS, free_keys
    set_variant("llvm_ad_rgb")
    spec, bsdf = load_model(spec, args.model)
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
    refuse_values(args.file, data)
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
