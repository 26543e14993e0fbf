"""Seconds per optimisation iteration, traced and frozen (``@dr.freeze``), Python plugins
against their C++ neighbours, and the ``fit`` example itself.

Part 7 of the performance study (``python -m mitsuba_brdfs bench``). Each configuration
recovers one colour parameter of the sphere's BSDF (``OPT_PAIRS``; the ``prb`` integrator)
from a target image with the loop a user writes: ``params.update(opt)`` (the plugins check
the new value's range there, reading it back), the render, the loss and its
backpropagation (frozen or not), the Adam step, the clamping into range, the loss read
back. The first ``opt_warmup`` iterations (tracing, compiling, recording) are not timed;
an iteration's seconds are the median over the ``opt_iterations`` after them. Each
configuration is built alone (Mitsuba traces every live BSDF into a kernel) and the four
of a pair run in alternating order, ``opt_runs`` rounds; ratios are medians of per-round
ratios. ``fit`` is timed the same way, ``fit(freeze=True)`` against ``fit(freeze=False)``,
over a whole fit (``fit_iterations``, timed after the first ``opt_warmup``) at each size
of ``fit_sizes`` (its default and a larger image): seconds per iteration and of the loop,
and how close it ends to the truth.
"""
import gc
import statistics
import time

from ..progress import advance

__all__ = ["OPT_PAIRS", "loop_seconds", "run"]

#: (key of speed.CPP_PAIRS, parameter optimised, its true value, the start value)
OPT_PAIRS = [
    ("lambert", "reflectance", 0.5, 0.2),
    ("ashikhmin_shirley_metal", "specular_reflectance", 1.0, 0.5),
]


def loop_seconds(bsdf, name, true, start, settings, frozen):
    """One configuration: seconds per iteration (median), of which ``params.update``, the
    frozen function's recordings, and the loss at the first and last iteration."""
    import drjit as dr
    import mitsuba as mi

    from ..collector import paused
    from ..sphere import sphere_scene

    scene = sphere_scene({**bsdf, name: true}, settings.opt_res, settings.opt_spp,
                         integrator="prb", max_depth=3)
    params = mi.traverse(scene)
    key = f"ball.bsdf.{name}.value"
    target = mi.render(scene, spp=4 * settings.opt_spp, seed=1 << 20)
    dr.eval(target)
    opt = mi.ad.Adam(lr=0.02)
    opt[key] = type(params[key])(start)

    @dr.freeze(enabled=frozen)
    def step(scene, target, seed):
        """Render, loss and backpropagation of one iteration."""
        img = mi.render(scene, mi.traverse(scene), seed=seed)
        loss = dr.mean(dr.square(img - target), axis=None)
        dr.backward(loss)
        return loss

    seconds, updates, losses = [], [], []
    gc.collect()  # what earlier configurations left is freed now, not while recording
    for it in range(settings.opt_warmup + settings.opt_iterations):
        t0 = time.perf_counter()
        params.update(opt)
        t1 = time.perf_counter()
        with paused():
            loss = step(scene, target, mi.UInt32(it))
        opt.step()
        opt[key] = dr.clip(opt[key], 0.0, 1.0)
        losses.append(loss.array[0])  # reads back: the iteration is done
        if it >= settings.opt_warmup:
            seconds.append(time.perf_counter() - t0)
            updates.append(t1 - t0)
    out = {"seconds": statistics.median(seconds), "update": statistics.median(updates),
           "recordings": step.n_recordings, "loss_first": losses[0], "loss_last": losses[-1],
           "all_seconds": seconds}
    del scene, params, opt, step, target, loss
    gc.collect()
    return out


def _ratio(a, b):
    """Median, min and max of the per-round ratios a / b."""
    rs = [x / y for x, y in zip(a, b)]
    return {"ratio": statistics.median(rs), "ratio_min": min(rs), "ratio_max": max(rs)}


def _fit_run(settings, res, spp, frozen):
    """``fit`` at one size: seconds per iteration (median after the warm-up), the whole
    loop's seconds, the final values and their relative errors."""
    import tempfile

    from ..image_fit import fit
    with tempfile.TemporaryDirectory() as tmp:
        r = fit(iterations=settings.fit_iterations, spp=spp, res=res, out=tmp, tile_res=8,
                progress=None, freeze=frozen)
    gc.collect()
    return {"seconds": statistics.median(r["history"]["seconds"][settings.opt_warmup:]),
            "loop": r["seconds"], "recordings": r["recordings"], "final": r["final"],
            "errors": r["errors"]}


def _fit(settings, progress):
    """``fit(freeze=True)`` against ``fit(freeze=False)`` at each of ``fit_sizes``,
    alternately, ``opt_runs`` rounds; the row of fit's defaults is marked."""
    from .. import image_fit as fit_module
    rows = []
    for res, spp in settings.fit_sizes:
        runs = {True: [], False: []}
        for r in range(settings.opt_runs):
            for frozen in ((True, False) if r % 2 == 0 else (False, True)):
                runs[frozen].append(_fit_run(settings, res, spp, frozen))
            advance(progress, 1, f"fit {res}x{res}")
        sec = {k: [x["seconds"] for x in v] for k, v in runs.items()}
        rows.append({
            "res": res, "spp": spp,
            "default": (res, spp) == (fit_module.RES, fit_module.SPP),
            "frozen": statistics.median(sec[True]), "plain": statistics.median(sec[False]),
            **_ratio(sec[True], sec[False]),
            "loop_frozen": statistics.median(x["loop"] for x in runs[True]),
            "loop_plain": statistics.median(x["loop"] for x in runs[False]),
            "recordings": max(x["recordings"] for x in runs[True]),
            "final_frozen": runs[True][0]["final"], "final_plain": runs[False][0]["final"],
            "errors_frozen": runs[True][0]["errors"], "errors_plain": runs[False][0]["errors"],
            "seconds_frozen": sec[True], "seconds_plain": sec[False]})
    return rows


def run(settings, available, progress=None):
    """Part 7 (see the module docstring)."""
    from .speed import CPP_PAIRS, _missing
    cpp = {k: (ours, theirs) for k, ours, theirs, _ in CPP_PAIRS}
    out = {"settings": {"res": settings.opt_res, "spp": settings.opt_spp,
                        "warmup": settings.opt_warmup, "iterations": settings.opt_iterations,
                        "runs": settings.opt_runs, "integrator": "prb", "max_depth": 3,
                        "fit_sizes": [list(x) for x in settings.fit_sizes],
                        "fit_iterations": settings.fit_iterations},
           "pairs": {}, "skipped": []}
    configs = [(side, mode) for mode in ("plain", "frozen") for side in ("python", "cpp")]
    for key, name, true, start in OPT_PAIRS:
        if key not in settings.opt_pairs:
            continue
        ours, theirs = cpp[key]
        miss = _missing(ours, available)
        if miss:
            out["skipped"].append(f"{key}: plugin `{miss[0]}` is not registered")
            advance(progress, settings.opt_runs, f"skip {key}")
            continue
        rows = {c: [] for c in configs}
        for r in range(settings.opt_runs):
            for side, mode in (configs if r % 2 == 0 else configs[::-1]):
                bsdf = ours if side == "python" else theirs
                rows[side, mode].append(loop_seconds(bsdf, name, true, start, settings,
                                                     mode == "frozen"))
            advance(progress, 1, key)
        sec = {c: [x["seconds"] for x in v] for c, v in rows.items()}
        res = {"parameter": name, "true": true, "start": start, "plugin": ours["type"],
               "cpp_plugin": theirs["type"], "python": ours, "cpp": theirs}
        for side, mode in configs:
            v = rows[side, mode]
            res[f"{side}_{mode}"] = {
                "seconds": statistics.median(sec[side, mode]),
                "update": statistics.median(x["update"] for x in v),
                "recordings": max(x["recordings"] for x in v),
                "loss_first": statistics.median(x["loss_first"] for x in v),
                "loss_last": statistics.median(x["loss_last"] for x in v),
                "runs": [x["all_seconds"] for x in v]}
        for side in ("python", "cpp"):
            res[f"{side}_frozen_vs_plain"] = _ratio(sec[side, "frozen"], sec[side, "plain"])
        for mode in ("plain", "frozen"):
            res[f"python_vs_cpp_{mode}"] = _ratio(sec["python", mode], sec["cpp", mode])
        out["pairs"][key] = res
    if "ashikhmin_shirley" in available:
        out["fit"] = _fit(settings, progress)
    else:
        out["skipped"].append("fit: plugin `ashikhmin_shirley` is not registered")
        advance(progress, settings.opt_runs * len(settings.fit_sizes), "skip fit")
    return out
