"""Seconds of ``fit-measured``: one MERL material fitted by each model, per fit and per
evaluation, and one call that fits and ranks the five preset models.

The section "fitting a measured material" of the performance study (``run``; its text is
``bench.sections.measured``). A full-size MERL file (90 x 90 x 180 bins, 35 MB) is written
from a known BRDF (the Cook-Torrance fit of gold-paint, ``presets.ngan2005``) into a
temporary directory, then each of ``MODELS`` is fitted to it as the command does: read
the file and subsample it (``measured.data.prepare``), then ``measured.report.fit_file``
(from the plugin's defaults, L-BFGS-B from several starts within ``measured.fitting.EVALUATIONS``
evaluations on ``measured.data.SAMPLES`` pairs, each evaluation one eval of the BSDF on the
pairs and on the energy term's directions, the loss and its backpropagation), then the
image judge (``measured.judge``: the fit's three views rendered and compared with the
file's, whose renders, through its RGL conversion, are timed once apart). Seconds are
wall-clock on the threads Dr.Jit has (the study sets 2); the first fit of a model compiles
its kernels, so ``runs`` fits of each are timed and the median reported, with the first
one's seconds apart. Then ``table_call``: ``fit-measured FILE --model
ashikhmin_shirley,blinn_phong,cook_torrance,ward,ward_duer`` (``TABLE_MODELS``) as a user
runs it, in its own process (start-up, reading, the five fits with their held-out losses,
the table, the XML, the summaries and the plot), timed once.

    from mitsuba_brdfs.bench.measured import measure
    numbers = measure(runs=3)
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

from .sections.measured import MODELS, steps

__all__ = ["TARGET_SECONDS", "IMAGE_TARGET_SECONDS", "MODELS", "TABLE_MODELS", "steps",
           "measure", "table_call", "run"]

#: the target: one material fitted in under 30 s on 2 cores, by any of the models
TARGET_SECONDS = 30
#: the image judge's target: a fit judged (rendered and compared) in at most 5 s
IMAGE_TARGET_SECONDS = 5
#: the models of the several-model call: fit-measured's preset models
TABLE_MODELS = ("ashikhmin_shirley", "blinn_phong", "cook_torrance", "ward", "ward_duer")


def _write_file(path):
    import mitsuba as mi
    from .. import presets
    from ..measured import merl
    merl.write(path, merl.from_bsdf(mi.load_dict(presets.ngan2005("cook_torrance",
                                                                  "gold-paint"))))


def table_call(path, evaluations=None, samples=None, models=TABLE_MODELS, extra=()):
    """Seconds of one ``fit-measured path --model M1,M2,...`` call in its own process, as
    a user runs it: {'models' (as given), 'seconds' (the call, wall-clock), 'ranked'
    [{'model', 'holdout_loss', 'image_error', 'seconds'} (each fit's, its held-out loss
    and image judge included)] in the order of the table}. ``evaluations``, ``samples``:
    None for the command's defaults; ``extra``: more of its options."""
    extra = ([] if evaluations is None else ["--evaluations", str(evaluations)]) + \
        ([] if samples is None else ["--samples", str(samples)]) + list(extra)
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        r = subprocess.run([sys.executable, "-m", "mitsuba_brdfs", "fit-measured", path,
                            "--model", ",".join(models), "--out", out, "--json", *extra],
                           capture_output=True, text=True)
        seconds = time.perf_counter() - t0
    if r.returncode != 0:
        raise RuntimeError(f"fit-measured --model {','.join(models)} failed: "
                           f"{r.stderr.strip().splitlines()[-1:]}")
    fits = json.loads(r.stdout)["fits"]
    return {"models": list(models), "seconds": seconds,
            "ranked": [{"model": f["model"], "holdout_loss": f["holdout_loss"],
                        "image_error": (f.get("image_error") or {}).get("mean"),
                        "seconds": f["seconds_total"]} for f in fits]}


def measure(runs=3, evaluations=None, samples=None, models=None, progress=None,
            table=TABLE_MODELS, image=None, table_args=()):
    """Time ``runs`` fits of one material by each model, each judged by the image judge
    (``measured.judge``: its renders and Delta E ITP; ``image`` (res, spp, to-rgl
    ``Resolution`` of the file's reference), by default the command's), then one
    ``table_call`` of the models ``table`` (None: none) on it (``table_args``: more of its
    options); returns the numbers (seconds)."""
    import drjit as dr
    import mitsuba as mi
    from ..variant import set_variant
    set_variant(mi.variant() or "llvm_ad_rgb")  # bench --variant's; the plugins registered
    from ..measured.data import SAMPLES, prepare
    from ..measured.fitting import EVALUATIONS
    from ..measured.variables import colour_spec
    from ..measured import acquire, judge as J
    from ..measured.report import fit_file
    from ..progress import advance
    evaluations = evaluations or EVALUATIONS
    samples = samples or SAMPLES
    res, spp, grid = image or (J.RES, J.SPP, acquire.Resolution())
    per_model = {}
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "gold-paint-ct.binary")
        _write_file(path)
        t0 = time.perf_counter()
        judge = J.Judge(J.reference(path, resolution=grid)[0], res, spp)
        seconds_reference = time.perf_counter() - t0
        for name, spec in (models or MODELS).items():
            fits = []
            for _ in range(runs):
                t0 = time.perf_counter()
                data = prepare(path, samples)
                t_read = time.perf_counter() - t0
                bsdf = mi.load_dict(colour_spec(spec, mi.load_dict(spec)))
                r = fit_file(data, bsdf, evaluations=evaluations)
                t_fit = time.perf_counter()
                error, _ = judge.error(bsdf)
                t_image = time.perf_counter() - t_fit
                fits.append({"read": t_read, "fit": r["seconds"], "image": t_image,
                             "image_error": error["mean"],
                             "total": time.perf_counter() - t0,
                             "evaluations": r["evaluations"],
                             "per_evaluation": r["seconds_per_evaluation"],
                             "loss": r["loss"], "start_loss": r["start_loss"],
                             "relative_rms": r["relative_rms_max"]})
                advance(progress, 1, f"{name} {len(fits)}")
            later = fits[1:] or fits
            per_model[name] = {
                "seconds_per_fit": statistics.median(x["total"] for x in later),
                "seconds_first_fit": fits[0]["total"],
                "seconds_read": statistics.median(x["read"] for x in later),
                "seconds_per_evaluation": statistics.median(x["per_evaluation"] for x in later),
                "seconds_image": statistics.median(x["image"] for x in later),
                "seconds_first_image": fits[0]["image"],
                "image_error": fits[-1]["image_error"],
                "evaluations": statistics.median(x["evaluations"] for x in later),
                "relative_rms": fits[-1]["relative_rms"], "loss": fits[-1]["loss"],
                "start_loss": fits[-1]["start_loss"], "fits": fits}
        several = None
        if table:
            several = table_call(path, evaluations, samples, table, table_args)
            advance(progress, 1, "five models in one call")
    slowest = max(per_model, key=lambda m: per_model[m]["seconds_per_fit"])
    return {"evaluations": evaluations, "samples": samples, "runs": runs,
            "threads": dr.thread_count(), "models": per_model, "model": slowest,
            "seconds_per_fit": per_model[slowest]["seconds_per_fit"],
            "seconds_first_fit": per_model[slowest]["seconds_first_fit"],
            "seconds_per_evaluation": per_model[slowest]["seconds_per_evaluation"],
            "loss": per_model[slowest]["loss"], "start_loss": per_model[slowest]["start_loss"],
            "image": {"res": res, "spp": spp, "seconds_reference": seconds_reference,
                      "seconds_per_fit": max(x["seconds_image"] for x in per_model.values()),
                      "target_seconds": IMAGE_TARGET_SECONDS},
            "table": several}


def run(settings, available, progress=None):
    """The study's section: ``measure`` with the settings' runs, evaluations
    (``measured_iterations``) and samples (0: ``fit-measured``'s defaults)."""
    from .load import under_load
    return under_load(lambda: {
        **measure(settings.measured_runs, settings.measured_iterations or None,
                  settings.measured_samples or None, progress=progress),
        "target_seconds": TARGET_SECONDS})


if __name__ == "__main__":
    import drjit as dr
    dr.set_thread_count(2)
    print(measure())
