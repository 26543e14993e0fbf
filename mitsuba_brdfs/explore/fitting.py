"""A model fitted to a measured entry in the page: ``fit-measured``'s fit, at a smaller budget.

The page's fit is ``fit-measured FILE --model MODEL --samples SAMPLES --evaluations
EVALUATIONS --seed 0 --image-spp 0`` made through the same calls, so that both report the
same parameters, errors and warnings (the page shows the fit's lobes and sphere itself: it
runs no image judge):

- ``data(info)``: ``measured.data.prepare`` of the measurement itself (a MERL entry's MERL
  file, not the RGL file drawn; ``measurement.rgl_file``'s ``info``), refused as the
  command refuses it (``measured.data.refuse_values``), read once per entry and kept on
  it;
- ``fit(model, data, label)``: the model loaded as the command loads it (from its
  defaults, colours as RGB: ``measured.variables.colour_spec``), fitted as the command
  fits it (``measured.select.select_fit``: ``measured.report.fit_file`` within the budget
  ``evaluations`` a stage, its losses on the held-out samples, an isotropic model's widths
  held equal on isotropic data), and summed up as the command's JSON summary
  (``measured.report.fit_summary``).

The budget (``budget``): ``SAMPLES`` samples for the shape term (the command's default is
20,000) and ``EVALUATIONS`` evaluations of the loss and its gradient a stage (its default,
1500): the fit's, then, where the fit leaves the data's albedo by more than 10 %, up to
three stages of the albedo constraint at half of it each (``measured.fitting.
most_evaluations``): the page announces that total, which no fit exceeds.
"""
import os
import time
from types import SimpleNamespace

__all__ = ["SAMPLES", "EVALUATIONS", "budget", "command", "data", "fit"]

#: samples of the shape term of a fit (``fit-measured --samples``)
SAMPLES = 4000
#: evaluations of the loss and its gradient a stage of a fit may take
#: (``fit-measured --evaluations``)
EVALUATIONS = 250


def budget(samples=SAMPLES, evaluations=EVALUATIONS):
    """{'samples', 'evaluations' (a stage's), 'most' (of every stage together)}."""
    from ..measured.fitting import most_evaluations
    return {"samples": int(samples), "evaluations": int(evaluations),
            "most": most_evaluations(evaluations)}


def command(path, model, samples=SAMPLES, evaluations=EVALUATIONS, seed=0):
    """The ``fit-measured`` command line that makes the same fit."""
    import shlex
    return (f"python -m mitsuba_brdfs fit-measured {shlex.quote(os.fspath(path))} --model "
            f"{shlex.quote(model)} --samples {samples} --evaluations {evaluations} "
            f"--seed {seed} --image-spp 0")


def data(info, samples=SAMPLES, seed=0):
    """What a fit to the measured entry ``info`` takes: {'measured': the
    ``measured.data.Measured`` data, as ``fit-measured`` prepares them, 'file', 'samples',
    'seed'}; ValueError (one line) for data nothing can be fitted to."""
    from ..measured.data import prepare, refuse_values
    d = prepare(info["file"], samples=samples, seed=seed)
    refuse_values(info["file"], d)
    return {"measured": d, "file": info["file"], "samples": samples, "seed": seed}


def _props(spec, params):
    """The ``load_dict`` dictionary of the fitted model: ``spec`` with the fitted values
    ({traverse key: list}) under the names the plugin reads."""
    out = dict(spec)
    for key, v in params.items():
        name = key[:-len(".value")] if key.endswith(".value") else key
        out[name] = float(v[0]) if len(v) == 1 else {"type": "rgb",
                                                      "value": [float(x) for x in v[:3]]}
    return out


def _values(bsdf):
    """How many values a fit of ``bsdf`` moves (a colour: 3)."""
    import mitsuba as mi
    from ..measured.variables import free_keys
    params = mi.traverse(bsdf)
    return sum(3 if isinstance(params[k], mi.Color3f) else 1 for k in free_keys(params))


def fit(model, fit_data, label, progress=None, evaluations=EVALUATIONS):
    """Fit this package's plugin ``model`` to ``fit_data`` (``data``); (the fitted model's
    ``load_dict`` dictionary, its summary: ``fit-measured --json``'s but its files
    ('xml', 'outputs'), with 'to' (the entry's label), 'budget' and 'command').
    ``progress(loss)`` after each evaluation may raise to stop it."""
    import mitsuba as mi
    from ..measured import report
    from ..measured.select import select_fit
    from ..measured.variables import colour_spec
    t0 = time.perf_counter()
    d, path = fit_data["measured"], fit_data["file"]
    # as fit-measured loads a model of this package (``measured.plugins.load_model``)
    spec = colour_spec({"type": model}, mi.load_dict({"type": model}))
    values = _values(mi.load_dict(spec))
    if d.bins < values:
        raise ValueError(f"{path}: {d.bins} measured samples within 80 "
                         f"deg of the normal, fewer than the {values} values {model} fits")
    r, _ = select_fit(d, lambda: mi.load_dict(spec), evaluations=evaluations,
                      progress=progress)
    r["seconds_total"] = time.perf_counter() - t0
    args = SimpleNamespace(file=path, weights="solid-angle")
    summary = report.fit_summary(args, path, d, model, spec, r, None, [])
    del summary["xml"], summary["outputs"]      # (the page exports the fitted entry)
    summary["rank_by"] = "holdout"              # (as the command without the judge)
    samples = fit_data["samples"]
    summary.update(to=label, budget=budget(samples, evaluations),
                   command=command(path, model, samples, evaluations, fit_data["seed"]))
    return _props(spec, r["params"]), summary
