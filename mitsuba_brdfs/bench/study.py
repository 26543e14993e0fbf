"""The performance study: what accuracy costs in time, measured in one run.

``python -m mitsuba_brdfs bench [--quick] [--out docs] [--sections ...]`` (``command``)
writes ``docs/performance.md``, its plots under ``docs/perf/`` and every raw number in
``docs/perf/results.json``. It measures the sections of ``bench.sections.SECTIONS``, in
its order: error against time of each sampling strategy; each Python plugin against its
closest C++ neighbour; the price of accuracy choices; the price of optional effects, and
``direct`` against ``path`` on the figure scenes; peak memory of command-line renders; the
time to the first image in a fresh process; optimisation iterations, traced and frozen; the
``figures`` command's total; the explorer's redraw after a parameter change; the seconds of
``fit-measured`` on one material; the seconds of ``to-rgl``; energy compensation's
render time against its furnace error.

Method, everywhere: every figure comes from this one run; times are medians of several
runs after a warm-up render (which compiles the kernels; compile time is reported apart);
what is compared is timed alternately, side by side, and conclusions rest on the ratios,
not on absolute seconds. The document records the commit the code came from.

``--sections`` runs some parts only; their results replace those parts in an existing
``results.json`` of the same mode (``merge``), and the document says which run each part
comes from.

``--quick`` runs a reduced version (small images, one run of each comparison): about a
minute of CPU time (59 s, 152 s of wall time on the project's 2 cores under a load average
of 8-9, docs/speed.md). It checks that the study still works
(``tests/test_bench_command.py``); its numbers are not the study's.
Plugins that are not registered (``mitsuba_brdfs.plugin_models()``) are skipped with a
note in the output.
"""
import dataclasses
import json
import os
import platform
import subprocess
import sys
import time

from .sections import KEYS, section

__all__ = ["Settings", "QUICK", "FULL", "SECTIONS", "expected_models", "git_info", "measure",
           "merge", "read_results", "write_results"]

#: the folder that holds the package (the git checkout, when run from one)
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def expected_models():
    """The package's plugins: every one a module of ``mitsuba_brdfs.models`` declares (as
    that package finds them, so a new model file is expected here too); those not
    registered are skipped with a note."""
    from .. import models
    return tuple(models.facts())


@dataclasses.dataclass(frozen=True)
class Settings:
    mode: str
    # error: error against time
    err_res: int
    err_spps: tuple
    err_runs: int
    err_ref_spp: int
    err_target: float          # relative RMSE (RMSE / mean of the reference image)
    alone_samples: int         # BSDF-alone efficiency, GGX sampling variance
    # cpp, effects: paired render timings on the sphere
    speed_res: int
    speed_spp: int
    speed_runs: int
    effect_models: tuple       # effects: the models whose dropped lobes are timed (() = all)
    # accuracy: accuracy choices
    micro_n: int               # evaluations per timed kernel
    micro_runs: int
    error_n: int               # inputs per exponent for the float64 comparison
    naive_render_exponents: tuple
    onr_luts: tuple
    chi2_samples: tuple
    chi2_eps: tuple
    # figures: figure scenes
    fig_res: int
    fig_spp: int
    # memory
    mem_res: int
    mem_spps: tuple
    mem_pass_samples: int      # 0: the render command's default
    mem_onepass_spps: tuple   # the same render in one pass, for contrast
    # startup: the first image in a fresh process (pairs: keys of speed.CPP_PAIRS)
    startup_res: int
    startup_spp: int
    startup_runs: int
    startup_pairs: tuple
    # optimisation: optimisation iterations, and fit
    opt_res: int
    opt_spp: int
    opt_warmup: int            # iterations not timed (tracing, compiling, recording)
    opt_iterations: int        # timed iterations per configuration
    opt_runs: int
    opt_pairs: tuple           # keys of optimisation.OPT_PAIRS
    fit_sizes: tuple           # (image width and height, spp) of each fit timed
    fit_iterations: int        # iterations of each fit (timed after opt_warmup)
    # figures_command: the figures command (figcmd_only: the figures it renders; empty: all of them)
    figcmd_only: tuple
    figcmd_runs: int
    # explore: the explorer's redraw after a parameter change (server, and page in chromium)
    explore_repeats: int
    explore_page_repeats: int
    # measured: fit-measured on one MERL file (0: the command's default)
    measured_runs: int
    measured_iterations: int
    measured_samples: int
    # to_rgl: to-rgl of a BSDF, a MERL file and an RGL file, each timed this many times
    to_rgl_runs: int
    # energy: the cases of bench.energy.CASES timed (forms against none) and put in the furnace
    energy_cases: tuple


FULL = Settings(
    mode="full",
    err_res=128, err_spps=(1, 4, 16, 64, 256, 1024), err_runs=3, err_ref_spp=8192,
    err_target=0.05, alone_samples=1 << 22,
    speed_res=256, speed_spp=64, speed_runs=9, effect_models=(),
    micro_n=1 << 22, micro_runs=9, error_n=1 << 20, naive_render_exponents=(1e3, 1e4, 1e5),
    onr_luts=(8, 32, 128), chi2_samples=(10_000, 100_000, 1_000_000, 10_000_000),
    chi2_eps=(0.005, 0.01, 0.02, 0.05, 0.1, 0.2),
    fig_res=192, fig_spp=32,
    mem_res=1024, mem_spps=(16, 256, 1024), mem_pass_samples=0, mem_onepass_spps=(16, 64),
    startup_res=256, startup_spp=64, startup_runs=5,
    startup_pairs=("lambert", "ashikhmin_shirley_metal"),
    opt_res=64, opt_spp=4, opt_warmup=3, opt_iterations=20, opt_runs=5,
    opt_pairs=("lambert", "ashikhmin_shirley_metal"),
    fit_sizes=((64, 8), (128, 8)), fit_iterations=200,
    figcmd_only=(), figcmd_runs=2,
    explore_repeats=15, explore_page_repeats=10,
    measured_runs=3, measured_iterations=0, measured_samples=0,
    to_rgl_runs=4,
    energy_cases=("ct_ggx_smith_gold", "ct_beckmann_vgroove_gold", "ct_ggx_smith_plastic",
                  "ts_p5"),
)

QUICK = Settings(
    mode="quick",
    err_res=32, err_spps=(1, 8, 64), err_runs=1, err_ref_spp=1024, err_target=0.1,
    alone_samples=1 << 16,
    speed_res=32, speed_spp=16, speed_runs=1, effect_models=("ashikhmin_shirley",),
    micro_n=1 << 18, micro_runs=3, error_n=1 << 16, naive_render_exponents=(1e4,),
    onr_luts=(8, 64), chi2_samples=(10_000, 100_000), chi2_eps=(0.05, 0.3),
    fig_res=32, fig_spp=4,
    mem_res=128, mem_spps=(4, 64), mem_pass_samples=1 << 16, mem_onepass_spps=(64,),
    startup_res=32, startup_spp=4, startup_runs=1, startup_pairs=("lambert",),
    opt_res=16, opt_spp=1, opt_warmup=2, opt_iterations=3, opt_runs=1, opt_pairs=("lambert",),
    fit_sizes=((16, 1),), fit_iterations=5,
    figcmd_only=("as_sphere",), figcmd_runs=1,
    explore_repeats=2, explore_page_repeats=2,
    measured_runs=1, measured_iterations=20, measured_samples=2000,
    to_rgl_runs=1,
    energy_cases=("ct_ggx_smith_gold",),
)

#: the parts of the study, in running order (their table: ``bench.sections``)
SECTIONS = KEYS


def git_info():
    """Commit, its date, and the files of the package (scenes included) that differ from it."""
    def git(*args):
        """The output of a git command in the checkout ("" if git fails)."""
        try:
            return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                                  timeout=30).stdout
        except (OSError, subprocess.SubprocessError):
            return ""
    # porcelain lines are "XY path": two status columns, a space, the path
    status = git("status", "--porcelain", "--", "mitsuba_brdfs", "scenes")
    dirty = [ln[3:] for ln in status.splitlines() if ln.strip()]
    return {"commit": git("rev-parse", "HEAD").strip(),
            "date": git("log", "-1", "--format=%cI").strip(), "dirty": dirty}


def machine_info():
    """The CPU, threads and versions the study ran with."""
    import drjit as dr
    import mitsuba as mi
    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next((ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), cpu)
    except OSError:
        pass
    return {"cpu": cpu, "cores": os.cpu_count(), "drjit_threads": dr.thread_count(),
            "mitsuba": mi.__version__, "drjit": dr.__version__,
            "llvm": ".".join(map(str, dr.detail.llvm_version())),
            "python": platform.python_version(), "variant": mi.variant()}


def measure(settings, sections=SECTIONS, log=None):
    """Run the chosen sections; returns the results dict (JSON-ready)."""
    from ..core.registry import models as plugin_models
    from ..progress import progress_bar
    from . import plugins

    log = log or (lambda msg: print(msg, file=sys.stderr, flush=True))
    plugins.register()
    available = set(plugin_models())
    missing = [m for m in expected_models() if m not in available]
    results = {"mode": settings.mode, "settings": dataclasses.asdict(settings),
               "git": git_info(), "machine": machine_info(), "available": sorted(available),
               "missing": missing, "sections": list(sections), "section_seconds": {},
               "load_average_start": list(os.getloadavg())}
    if missing:
        log("not registered (skipped where needed): " + ", ".join(missing))
    t_start = time.perf_counter()
    for i, sec in enumerate(sections, 1):
        part = section(sec)
        label = f"[{i}/{len(sections)}] {part.title}"
        log(f"{label} ...")
        t0 = time.perf_counter()
        with progress_bar(part.steps(settings), label) as bar:
            results[sec] = part.run(settings, available, bar)
        results["section_seconds"][sec] = time.perf_counter() - t0
        log(f"{label}: {results['section_seconds'][sec]:.0f} s "
            f"(total {time.perf_counter() - t_start:.0f} s)")
    results["total_seconds"] = time.perf_counter() - t_start
    results["load_average_end"] = list(os.getloadavg())
    return results


def _run_info(results):
    """Where and when a run measured its sections (for the document's header)."""
    keys = ("sections", "git", "machine", "load_average_start", "load_average_end",
            "total_seconds", "section_seconds")
    return {k: results.get(k) for k in keys}


def merge(old, new):
    """``new`` (a run of some sections) written over those sections of ``old`` (an earlier
    run of the same mode); ``runs`` lists each run and its sections, oldest first. Returns
    ``new`` alone when there is nothing to keep from ``old``."""
    if not old or old.get("mode") != new["mode"] or set(old["sections"]) <= set(new["sections"]):
        return new
    merged = dict(old)
    runs = [dict(r) for r in old.get("runs") or [_run_info(old)]]
    for r in runs:  # sections measured again leave the earlier runs
        r["sections"] = [s for s in r["sections"] if s not in new["sections"]]
    merged["runs"] = [r for r in runs if r["sections"]] + [_run_info(new)]
    for sec in new["sections"]:
        merged[sec] = new[sec]
    merged["sections"] = [s for s in SECTIONS if s in old["sections"] or s in new["sections"]]
    merged["section_seconds"] = {**old.get("section_seconds", {}), **new["section_seconds"]}
    merged["settings"] = {**old.get("settings", {}), **new["settings"]}
    merged["total_seconds"] = sum(merged["section_seconds"].get(s, 0) for s in merged["sections"])
    return merged


def read_results(path):
    """The results of an earlier run, or None."""
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def write_results(results, path):
    """Write the results to ``path`` whole (a partial file, then renamed)."""
    from ..output import jsonable, write_text
    # as check --json: inf and nan (which JSON lacks) as strings, other objects as text
    write_text(path, json.dumps(jsonable(results), indent=1, default=str))
