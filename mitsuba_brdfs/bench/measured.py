"""Seconds of ``fit-measured``: one MERL material fitted, per fit and per iteration.

The section "fitting a measured material" of the performance study (``run``; its text is
``bench.sections.measured``). A full-size MERL file (90 x 90 x 180 bins, 35 MB) is written
from a known BRDF (the Cook-Torrance fit of gold-paint, ``presets.ngan2005``) into a
temporary directory, then ``fit_measured`` runs as the command does: read and subsample
the file (``prepare``), then ``fit`` (Ward from its defaults, ``fit_measured.ITERATIONS``
Adam steps on ``fit_measured.SAMPLES`` pairs, each iteration one eval of the BSDF on the
pairs, the loss and its backpropagation). Seconds are wall-clock on the threads Dr.Jit
has (the study sets 2); the first fit compiles its kernels, so ``runs`` fits are timed and
the median reported, with the first one's seconds apart.

    from mitsuba_brdfs.bench.measured import measure
    numbers = measure(runs=3)
"""
import os
import statistics
import tempfile
import time

import numpy as np

__all__ = ["TARGET_SECONDS", "measure", "run"]

#: the target: one material fitted in under 30 s on 2 cores
TARGET_SECONDS = 30


def _write_file(path):
    import mitsuba as mi
    from .. import merl, presets
    from ..validate.probe import eval_np
    wi, wo = merl.directions(merl.DIMS)
    ok = (wi[:, 2] > 1e-6) & (wo[:, 2] > 1e-6)
    f = np.full((len(wi), 3), np.nan)
    bsdf = mi.load_dict(presets.ngan2005("cook_torrance", "gold-paint"))
    f[ok] = eval_np(bsdf, wi[ok], wo[ok]) / wo[ok][:, 2:3]
    merl.write(path, f)


def measure(runs=3, iterations=None, samples=None, model="ward", progress=None):
    """Time ``runs`` fits of one material; returns the numbers (seconds)."""
    import drjit as dr
    import mitsuba as mi
    from ..variant import set_variant
    set_variant("llvm_ad_rgb")  # the plugins registered in it too
    from .. import fit_measured as F
    from ..progress import advance
    iterations = iterations or F.ITERATIONS
    samples = samples or F.SAMPLES
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "gold-paint-ct.binary")
        _write_file(path)
        fits = []
        for _ in range(runs):
            t0 = time.perf_counter()
            wi, wo, f = F.prepare(path, samples)
            t_read = time.perf_counter() - t0
            spec = {"type": model}
            bsdf = mi.load_dict(F.colour_spec(spec, mi.load_dict(spec)))
            r = F.fit(bsdf, wi, wo, f, iterations)
            fits.append({"read": t_read, "fit": r["seconds"], "total": time.perf_counter() - t0,
                         "per_iteration": r["seconds_per_iteration"], "loss": r["loss"],
                         "start_loss": r["start_loss"]})
            advance(progress, 1, f"fit {len(fits)}")
    later = fits[1:] or fits
    numbers = {
        "model": model, "iterations": iterations, "samples": samples, "runs": runs,
        "threads": dr.thread_count(),
        "seconds_per_fit": statistics.median(x["total"] for x in later),
        "seconds_first_fit": fits[0]["total"],
        "seconds_read": statistics.median(x["read"] for x in later),
        "seconds_per_iteration": statistics.median(x["per_iteration"] for x in later),
        "loss": fits[-1]["loss"], "start_loss": fits[-1]["start_loss"], "fits": fits,
    }
    return numbers


def run(settings, available, progress=None):
    """The study's section: ``measure`` with the settings' runs, iterations and samples
    (0: ``fit-measured``'s defaults)."""
    load = os.getloadavg()[0]
    out = measure(settings.measured_runs, settings.measured_iterations or None,
                  settings.measured_samples or None, progress=progress)
    out.update(target_seconds=TARGET_SECONDS, load_average=[load, os.getloadavg()[0]],
               cores=os.cpu_count())
    return out


if __name__ == "__main__":
    import drjit as dr
    dr.set_thread_count(2)
    print(measure())
