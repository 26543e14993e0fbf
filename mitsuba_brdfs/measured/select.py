"""A model's fit, judged, and chosen among candidates by how it looks; fits ranked.

``judged_fit``: one fit (``report.fit_file``) of a freshly loaded model, with its held-out
loss under each of the three losses (``losses.LOSSES``: the same held-out pairs for every
fit of the data) and its image error (``judge.Judge``: Delta E ITP of the sphere's renders
against the measurement's).

``select_fit``: by ``loss`` (one fit, the one its loss finds best: L-BFGS-B from several
starts, the best on), or by ``image``: a candidate per loss (``l2cos``, ``log``, ``cbrt``)
and per start (the given parameters and each lobe width of ``fitting.START_WIDTHS``, each
fitted from that start alone with its share of the budget), and the candidate whose
renders come closest to the measurement's kept (Bieron & Peers 2020 choose among fitted
candidates so). The kept fit lists every candidate ('candidates').

``ranked``: the fits in order of image error (``image``; NaN last, then the held-out loss)
or of held-out loss (``holdout``).

References: J. Bieron, P. Peers, "An Adaptive BRDF Fitting Metric", EGSR 2020.
"""
import math
import time

from .losses import LOSSES

__all__ = ["SELECT", "RANK_BY", "judged_fit", "select_fit", "ranked"]

SELECT = ("loss", "image")
RANK_BY = ("image", "holdout")


def judged_fit(data, load, judge=None, *, loss="l2cos", holdout_kind=None, **fit_kwargs):
    """(``report.fit_file``'s result of ``load()``, a fresh BSDF, to ``data``, that BSDF):
    the result with 'holdout_loss' (under ``holdout_kind``, by default the fit's loss),
    'holdout_losses' {loss: held-out loss}, 'holdout_samples', 'image_error' ({"metric",
    "mean", "p95"}, or None without a judge) and '_images' (the renders),
    'seconds_image'. ``fit_kwargs`` go to ``fit_file``."""
    from .quality import shape_loss
    from .report import fit_file
    bsdf = load()
    r = fit_file(data, bsdf, loss, **fit_kwargs)
    r["holdout_losses"] = {k: shape_loss(bsdf, *data.holdout, kind=k) for k in LOSSES}
    r["holdout_loss"] = r["holdout_losses"][holdout_kind or loss]
    r["holdout_samples"] = len(data.holdout[0])
    r["image_error"], r["_images"], r["seconds_image"] = None, None, 0.0
    if judge is not None:
        error, r["_images"] = judge.error(bsdf)
        r["seconds_image"] = error.pop("seconds")
        r["image_error"] = error
    return r, bsdf


def _image(r):
    e = r.get("image_error")
    return e["mean"] if e and math.isfinite(e["mean"]) else math.inf


def select_fit(data, load, judge=None, select="loss", loss="l2cos", evaluations=None,
               progress=None, **fit_kwargs):
    """The fit of the model ``load()`` loads, chosen by ``select`` (``SELECT``; ``image``
    needs a judge): (result, BSDF) as ``judged_fit``'s, the held-out loss under ``loss``;
    by image, with 'selected_by' "image" and 'candidates' [{'loss', 'start', 'loss_value',
    'holdout_loss', 'holdout_losses', 'image_error', 'params'}] (every candidate, in the
    order fitted). ``evaluations``: the budget of one fit (``fitting.EVALUATIONS`` by
    default), each candidate's its share among the starts."""
    from .fitting import EVALUATIONS
    if select not in SELECT:
        raise ValueError(f"--select must be one of {', '.join(SELECT)} (got {select!r})")
    if select == "image" and judge is None:
        raise ValueError("--select image needs the image judge (--image-spp above 0)")
    budget = EVALUATIONS if evaluations is None else evaluations
    common = dict(fit_kwargs, evaluations=budget, progress=progress, holdout_kind=loss)
    if select == "loss":
        r, bsdf = judged_fit(data, load, judge, loss=loss, **common)
        r["selected_by"] = "loss"
        return r, bsdf
    t0 = time.perf_counter()
    isotropic = fit_kwargs.get("isotropic")
    starts = _starts(load(), fit_kwargs.get("keys"),
                     getattr(data, "isotropic", True) if isotropic is None else isotropic)
    share = dict(common, evaluations=max(budget // starts, 1))
    best, candidates = None, []
    for kind in LOSSES:
        for k in range(starts):
            r, bsdf = judged_fit(data, load, judge, loss=kind, start=k, **share)
            candidates.append({"loss": kind, "start": k, "loss_value": r["loss"],
                               "holdout_loss": r["holdout_loss"],
                               "holdout_losses": r["holdout_losses"],
                               "image_error": r["image_error"], "params": r["params"]})
            if best is None or _image(r) < _image(best[0]):
                best = (r, bsdf)
    r, bsdf = best
    r.update(selected_by="image", candidates=candidates,
             seconds_candidates=time.perf_counter() - t0)
    return r, bsdf


def _starts(bsdf, keys, isotropic):
    """How many starts ``fitting.fit`` has for this model: the given parameters, and each
    of ``START_WIDTHS`` where the model has a lobe width."""
    import mitsuba as mi
    from .fitting import START_WIDTHS
    from .variables import blocks, free_keys
    params = mi.traverse(bsdf)
    widths = any(b.width_start(START_WIDTHS[0]) is not None
                 for b in blocks(bsdf, params, free_keys(params, keys), isotropic))
    return 1 + len(START_WIDTHS) * widths


def ranked(fits, rank_by="image"):
    """The names of ``fits`` ({name: result}) in order: by image error's mean (``image``;
    fits without one last), then held-out loss; or by held-out loss (``holdout``), then
    loss. NaN last."""
    if rank_by not in RANK_BY:
        raise ValueError(f"--rank-by must be one of {', '.join(RANK_BY)} (got {rank_by!r})")
    held = lambda m: (not math.isfinite(fits[m]["holdout_loss"]), fits[m]["holdout_loss"])
    if rank_by == "image":
        key = lambda m: (_image(fits[m]),) + held(m)
    else:
        key = lambda m: held(m) + (fits[m]["loss"],)
    return sorted(fits, key=key)
