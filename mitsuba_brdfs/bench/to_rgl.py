"""Seconds of ``to-rgl``: a BSDF, a MERL file, an RGL file and an anisotropic BSDF written
as RGL files.

The section "writing a measured material as an RGL file" of the performance study
(``run``; its text is ``bench.sections.to_rgl``). Three sources, each converted ``runs``
times at the command's default resolution (``measured.acquire.Resolution``) as the
command does (``measured.convert.convert``): Mitsuba's ``roughplastic``, a full-size MERL
file (90 x 90 x 180 bins, written from the Cook-Torrance fit of gold-paint into a
temporary directory: reading it is timed too), the RGL file written from the
``roughplastic``, and an anisotropic ``ward`` (an anisotropic file, 17 azimuths of
incidence). The comparison with the source (``measured.roundtrip``) is timed apart.
Medians of the runs but the first (which compiles the kernels), wall-clock seconds on the
threads Dr.Jit has.

    from mitsuba_brdfs.bench.to_rgl import measure
    numbers = measure(runs=3)
"""
import os
import statistics
import tempfile
import time

__all__ = ["TARGET_SECONDS", "measure", "run"]

#: the target: a material written in under 10 s on 2 cores, its comparison included
TARGET_SECONDS = 10


def _write_merl(path):
    """A full-size MERL file of the Cook-Torrance fit of gold-paint (unmeasured bins below
    the horizon)."""
    import mitsuba as mi
    from .. import presets
    from ..measured import merl
    merl.write(path, merl.from_bsdf(mi.load_dict(presets.ngan2005("cook_torrance",
                                                                  "gold-paint"))))


def measure(runs=3, progress=None):
    """Time ``runs`` conversions of each source; returns the numbers."""
    import drjit as dr
    import mitsuba as mi
    from ..measured import acquire, convert, sources
    from ..progress import advance
    from ..variant import set_variant
    set_variant(mi.variant() or "llvm_ad_rgb")  # bench --variant's
    res = acquire.Resolution()
    out = {"runs": runs, "threads": dr.thread_count(), "sources": [],
           "resolution": {"ndf": res.ndf, "theta_i": res.theta_i, "vndf": res.vndf,
                          "grid": res.grid}}
    with tempfile.TemporaryDirectory() as tmp:
        merl_path = os.path.join(tmp, "gold-paint-ct.binary")
        _write_merl(merl_path)
        plastic = os.path.join(tmp, "roughplastic.bsdf")
        cases = [("roughplastic (Mitsuba's)", lambda: sources.Source(
                      sources.bsdf_evaluator(mi.load_dict({"type": "roughplastic"})),
                      "roughplastic", "bsdf", "roughplastic", [])),
                 ("MERL file, 90 x 90 x 180", lambda: sources.open_source(merl_path)),
                 ("RGL file (the roughplastic's)", lambda: sources.open_source(plastic)),
                 ("ward, anisotropic (alpha_u 0.05, alpha_v 0.3)", lambda: sources.Source(
                      sources.bsdf_evaluator(mi.load_dict({"type": "ward", "alpha_u": 0.05,
                                                           "alpha_v": 0.3})),
                      "ward", "bsdf", "ward", []))]
        for k, (name, opener) in enumerate(cases):
            times = []
            for _ in range(runs):
                t0 = time.perf_counter()
                source = opener()
                t_open = time.perf_counter() - t0
                path = plastic if k == 0 else os.path.join(tmp, f"out{k}.bsdf")
                s = convert.convert(source, path, res)
                times.append({"open": t_open, "write": s["seconds"],
                              "compare": s["seconds_compare"],
                              "total": time.perf_counter() - t0, "bytes": s["bytes"]})
                advance(progress, 1, name.split(" ")[0])
            later = times[1:] or times
            out["sources"].append({
                "name": name, "bytes": times[-1]["bytes"], "first": times[0]["total"],
                **{k: statistics.median(t[k] for t in later)
                   for k in ("open", "write", "compare", "total")}})
    return out


def run(settings, available, progress=None):
    """The study's section: ``measure`` with the settings' runs."""
    from .load import under_load
    return under_load(lambda: {**measure(settings.to_rgl_runs, progress=progress),
                               "target_seconds": TARGET_SECONDS})


if __name__ == "__main__":
    import drjit as dr
    dr.set_thread_count(2)
    print(measure())
