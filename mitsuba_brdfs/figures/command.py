"""The ``figures`` command: render the paper's figures and the model catalog into ``--out``
(default ``mitsuba_brdfs-out/figures/``; ``make docs`` writes the repository's ``renders/``).

    python -m mitsuba_brdfs figures [--quality preview|final] [--only NAME ...]
    python -m mitsuba_brdfs figures --check [--only NAME ...]

Every figure is rendered with ``panels.render_figure``: an EXR per panel and the labelled
PNG; seconds and spp per figure go to ``timings.json`` there. ``--check`` renders the
checked panels of each figure with the scene's own integrator and with a deeper path
tracer and prints how far apart they are (``check.check_integrator``). ``catalog`` is the
model catalog of ``catalog.py``: every model on the same sphere (models whose plugin is
not registered yet are left out with a note); ``ngan2005`` the measured-material presets
(``ngan2005.py``); ``energy_compensation`` rough metals with and without the light
single scattering loses (``energy.py``).
"""
import json
import os
import time

from .. import output, passes, variant
from ..arguments import default_out, positive_int
from .catalog import catalog_figure
from .check import check_integrator
from .energy import energy_figure
from .ngan2005 import ngan2005_figure
from .panels import render_figure
from .paper import FIGURES

__all__ = ["NAMES", "figure", "add_arguments", "run"]

#: every file is written whole (``output.atomic``): an interruption can say what was written
WRITES_ATOMICALLY = True

#: every figure name, in the order the command renders them; `catalog` is built when
#: rendered (it depends on which plugins are registered)
NAMES = list(FIGURES) + ["catalog", "ngan2005", "energy_compensation"]


def figure(name):
    """The Figure called ``name`` (the catalog is built now, from the registered plugins)."""
    if name == "catalog":
        return catalog_figure()
    if name == "ngan2005":  # the measured-material presets (``ngan2005.py``)
        return ngan2005_figure()
    if name == "energy_compensation":  # rough metals in a furnace (``energy.py``)
        return energy_figure()
    return FIGURES[name]


def add_arguments(p):
    p.add_argument("--quality", choices=("preview", "final"), default="preview",
                   help="sample count and resolution (default: %(default)s)")
    p.add_argument("--only", nargs="+", metavar="NAME", choices=NAMES,
                   help="render only these figures: " + ", ".join(NAMES))
    p.add_argument("--out", default=default_out("figures"),
                   help="output directory (default: %(default)s/ in the current directory)")
    p.add_argument("-m", "--mode", "--variant", dest="variant", default="llvm_ad_rgb",
                   metavar="VARIANT", help="Mitsuba variant (default: %(default)s)")
    p.add_argument("--pass-samples", type=positive_int, default=passes.DEFAULT_PASS_SAMPLES,
                   metavar="N", help="samples (pixels x spp) traced at once; bounds memory "
                                     "(default: %(default)s)")
    p.add_argument("--check", action="store_true",
                   help="instead of rendering, compare each figure's integrator with a deeper "
                        "path tracer on its checked panels (128 px, 1024 spp)")


def _check(names):
    for name in names:
        fig = figure(name)
        for k in fig.check:
            panel = fig.panels[k]
            if callable(panel.scene):
                print(f"{name}: built in Python, not checked")
                break
            print("\n".join(check_integrator(panel.scene, panel.defines)), flush=True)
    return 0


def run(args):
    names = args.only or NAMES
    if not args.check:
        output.check_folder(args.out)
    variant.set_variant(args.variant)
    if args.check:
        return _check(names)
    timings_path = os.path.join(args.out, "timings.json")
    timings = {}
    if os.path.exists(timings_path):
        with open(timings_path) as f:
            timings = json.load(f)
    t0 = time.perf_counter()
    for name in names:
        fig = figure(name)
        if not fig.panels:
            print(f"{name}: nothing to render")
            continue
        t = render_figure(fig, args.quality, args.out, args.pass_samples)
        timings[name] = t
        spp = t["spp"] if isinstance(t["spp"], int) else "/".join(map(str, t["spp"]))
        res = t["resolution"] if isinstance(t["resolution"], int) else "x".join(
            map(str, t["resolution"]))
        print(f"{name}: {t['seconds_total']:.1f} s ({t['panels']} panel(s), {spp} spp, "
              f"{res} px)", flush=True)
    total = time.perf_counter() - t0
    print(f"{len(names)} figure(s) in {total:.1f} s")
    timings["last_run"] = {"figures": names, "quality": args.quality,
                           "seconds_total": round(total, 3), "cpu_count": os.cpu_count()}
    output.write_json(timings_path, timings, indent=2, sort_keys=True)
    return 0
