"""Seconds of ``fit-measured``: one MERL material fitted by each model, per fit and per
evaluation.

The section "fitting a measured material" of the performance study (``run``; its text is
``bench.sections.measured``). A full-size MERL file (90 x 90 x 180 bins, 35 MB) is written
from a known BRDF (the Cook-Torrance fit of gold-paint, ``presets.ngan2005``) into a
temporary directory, then each of ``MODELS`` is fitted to it as the command does: read
the file and subsample it (``measured.data.prepare``), then ``measured.report.fit_file``
(from the plugin's defaults, L-BFGS-B from several starts within ``measured.fitting.EVALUATIONS``
evaluations on ``measured.data.SAMPLES`` pairs, each evaluation one eval of the BSDF on the
pairs and on the energy term's directions, the loss and its backpropagation). Seconds are
wall-clock on the threads Dr.Jit has (the study sets 2); the first fit of a model compiles
its kernels, so ``runs`` fits of each are timed and the median reported, with the first
one's seconds apart.

    from mitsuba_brdfs.bench.measured import measure
    numbers = measure(runs=3)
"""
import os
import statistics
import tempfile
import time

from .sections.measured import MODELS, steps

__all__ = ["TARGET_SECONDS", "MODELS", "steps", "measure", "run"]

#: the target: one material fitted in under 30 s on 2 cores, by any of the models
TARGET_SECONDS = 30


def _write_file(path):
    import mitsuba as mi
    from .. import presets
    from ..measured import merl
    merl.write(path, merl.from_bsdf(mi.load_dict(presets.ngan2005("cook_torrance",
                                                                  "gold-paint"))))


def measure(runs=3, evaluations=None, samples=None, models=None, progress=None):
    """Time ``runs`` fits of one material by each model; returns the numbers (seconds)."""
    import drjit as dr
    import mitsuba as mi
    from ..variant import set_variant
    set_variant("llvm_ad_rgb")  # the plugins registered in it too
    from ..measured.data import SAMPLES, prepare
    from ..measured.fitting import EVALUATIONS
    from ..measured.variables import colour_spec
    from ..measured.report import fit_file
    from ..progress import advance
    evaluations = evaluations or EVALUATIONS
    samples = samples or SAMPLES
    per_model = {}
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "gold-paint-ct.binary")
        _write_file(path)
        for name, spec in (models or MODELS).items():
            fits = []
            for _ in range(runs):
                t0 = time.perf_counter()
                data = prepare(path, samples)
                t_read = time.perf_counter() - t0
                bsdf = mi.load_dict(colour_spec(spec, mi.load_dict(spec)))
                r = fit_file(data, bsdf, evaluations=evaluations)
                fits.append({"read": t_read, "fit": r["seconds"],
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
                "evaluations": statistics.median(x["evaluations"] for x in later),
                "relative_rms": fits[-1]["relative_rms"], "loss": fits[-1]["loss"],
                "start_loss": fits[-1]["start_loss"], "fits": fits}
    slowest = max(per_model, key=lambda m: per_model[m]["seconds_per_fit"])
    return {"evaluations": evaluations, "samples": samples, "runs": runs,
            "threads": dr.thread_count(), "models": per_model, "model": slowest,
            "seconds_per_fit": per_model[slowest]["seconds_per_fit"],
            "seconds_first_fit": per_model[slowest]["seconds_first_fit"],
            "seconds_per_evaluation": per_model[slowest]["seconds_per_evaluation"],
            "loss": per_model[slowest]["loss"], "start_loss": per_model[slowest]["start_loss"]}


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
