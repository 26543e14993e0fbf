"""Honest timing of renders: warm-up, paired runs, medians, ratios taken side by side.

Absolute times on a shared machine are noisy; a ratio of two renders timed alternately in
the same run is not (both see the same load). ``paired_times`` alternates the scenes,
``summary`` reports medians and the median of the per-pair ratios. JIT compilation is
kept out of the render times: the first render of each scene (the warm-up) compiles and
is reported apart.
"""
import statistics
import time

import drjit as dr
import mitsuba as mi

__all__ = ["time_render", "kernel_stats", "paired_times", "paired_fresh", "paired_calls",
           "summary", "ir_instructions", "bsdf_instructions"]


def time_render(scene, spp=None, seed=0, integrator=None):
    """Seconds of one complete render (the image is evaluated before the clock stops)."""
    dr.sync_thread()
    t0 = time.perf_counter()
    img = mi.render(scene, spp=spp or 0, seed=seed, integrator=integrator)
    dr.eval(img)
    dr.sync_thread()
    return time.perf_counter() - t0, img


def kernel_stats(scene, spp=None, integrator=None):
    """Render once with Dr.Jit's kernel history on: JIT kernels, compile and run seconds.

    Called on a scene's first render, ``compile_s`` is the JIT compilation it costs
    (code generation + LLVM); on later renders the kernels come from the cache.
    """
    dr.kernel_history_clear()
    with dr.scoped_set_flag(dr.JitFlag.KernelHistory, True):
        time_render(scene, spp, 12345, integrator)
        hist = dr.kernel_history()
    kernels = [k for k in hist if k.get("type") == dr.KernelType.JIT]
    ops = [int(k.get("operation_count", 0)) for k in kernels]
    instr = [ir_instructions(k) for k in kernels]
    return {
        "kernels": len(kernels),
        "compile_s": sum(k.get("codegen_time", 0) + k.get("backend_time", 0) for k in kernels) / 1e3,
        "run_s": sum(k.get("execution_time", 0) for k in kernels) / 1e3,
        "cache_hits": sum(bool(k.get("cache_hit")) for k in kernels),
        # compiled before and loaded from Dr.Jit's disk cache: compile_s is then small
        "disk_hits": sum(bool(k.get("cache_disk")) for k in kernels),
        # IR operations of all kernels, and of the largest one (the rendering kernel);
        # operation_count leaves out the bodies of virtual calls (e.g. BSDF methods
        # when a scene has several BSDFs): ``instructions`` counts them too
        "ops": sum(ops),
        "ops_max": max(ops, default=0),
        "instructions": sum(instr),
        "instructions_max": max(instr, default=0),
    }


def ir_instructions(kernel):
    """Instructions in a kernel's IR (``dr.kernel_history`` entry), called functions included.

    For the LLVM backend: the lines of the module's function bodies that are not labels,
    comments or braces; 0 when the history holds no IR.
    """
    ir = kernel.get("ir")
    if ir is None:
        return 0
    text = ir.getvalue() if hasattr(ir, "getvalue") else str(ir)
    n = 0
    for line in text.splitlines():
        if line[:1] in (" ", "\t"):
            stripped = line.strip()
            if stripped and not stripped.startswith((";", "}")):
                n += 1
    return n


def paired_times(scenes, runs=7, warmup=1, spp=None, progress=None, integrator=None):
    """Time every scene ``runs`` times, alternating them; returns name -> list of seconds.

    The first ``warmup`` renders of each scene (JIT compilation, caches) are discarded;
    their seconds are returned under ``name + ':warmup'``.
    """
    out = {name: [] for name in scenes}
    for name, scene in scenes.items():
        out[name + ":warmup"] = [time_render(scene, spp, 0, integrator)[0] for _ in range(warmup)]
    for r in range(runs):
        order = list(scenes) if r % 2 == 0 else list(reversed(list(scenes)))
        for name in order:
            out[name].append(time_render(scenes[name], spp, r + 1, integrator)[0])
        if progress:
            progress.update(1)
    return out


def paired_fresh(builders, runs=7, spp=None, integrators=None, progress=None, on_image=None,
                 seed0=1):
    """``paired_times`` with every scene built afresh for each render and dropped after it.

    A render's kernel traces the methods of *every* live BSDF (Mitsuba dispatches BSDF
    calls over all registered instances), so timing two scenes that are both alive puts
    both BSDFs, and the Python tracing of both, into each render. Building each scene just
    before its render (``builders``: name -> function returning a scene; construction is
    not timed) keeps a render to its own BSDFs. The first render of each (the warm-up) is
    ``kernel_stats``: its compile seconds and IR size, measured with that scene alone.
    ``integrators``: optional name -> integrator. ``on_image(name, run, image)`` sees each
    timed image. A timed render during which a kernel had to be compiled is timed again
    (up to twice; counted under ``name + ':recompiled'``). Returns (name -> seconds per run,
    name -> kernel_stats of the warm-up).
    """
    import gc
    integrators = integrators or {}
    out = {name: [] for name in builders}
    stats = {}
    for name, build in builders.items():
        scene = build()
        stats[name] = kernel_stats(scene, spp, integrators.get(name))
        del scene
        gc.collect()
    for name in builders:
        out[name + ":recompiled"] = 0
    for r in range(runs):
        order = list(builders) if r % 2 == 0 else list(reversed(list(builders)))
        for name in order:
            for attempt in range(3):
                scene = builders[name]()
                t, img, compiled = _time_cached(scene, spp, seed0 + r, integrators.get(name))
                if not compiled or attempt == 2:
                    break
                # a kernel was compiled inside the timed run: time it again
                out[name + ":recompiled"] += 1
                del img, scene
                gc.collect()
            out[name].append(t)
            if on_image is not None:
                on_image(name, r, img)
            # free the scene before the next one is built: its objects' registry ids are
            # part of the kernel, and reused ids give the warm-up's kernel (no recompile)
            del img, scene
            gc.collect()
        if progress:
            progress.update(1)
    return out, stats


def _time_cached(scene, spp, seed, integrator):
    """``time_render`` that also says whether a JIT kernel was not resident yet: compiled,
    or loaded from Dr.Jit's disk cache (which the kernel history reports as a cache hit
    with ``cache_disk`` set). The kernel history costs no measurable time."""
    dr.kernel_history_clear()
    with dr.scoped_set_flag(dr.JitFlag.KernelHistory, True):
        t, img = time_render(scene, spp, seed, integrator)
        hist = dr.kernel_history()
    compiled = any(k.get("type") == dr.KernelType.JIT
                   and (not k.get("cache_hit") or k.get("cache_disk")) for k in hist)
    return t, img, compiled


def paired_calls(funcs, runs=7, warmup=1, progress=None):
    """``paired_times`` for any callables: name -> zero-argument function that returns once
    its work is done (e.g. after ``dr.eval`` and ``dr.sync_thread``). Returns name -> seconds
    per run, alternating the order run by run; warm-up seconds under ``name + ':warmup'``."""
    out = {name: [] for name in funcs}
    for name, f in funcs.items():
        out[name + ":warmup"] = []
        for _ in range(warmup):
            t0 = time.perf_counter()
            f()
            out[name + ":warmup"].append(time.perf_counter() - t0)
    for r in range(runs):
        order = list(funcs) if r % 2 == 0 else list(reversed(list(funcs)))
        for name in order:
            t0 = time.perf_counter()
            funcs[name]()
            out[name].append(time.perf_counter() - t0)
        if progress:
            progress.update(1)
    return out


def summary(times, a, b):
    """Median seconds of ``a`` and ``b`` and the median of the per-run ratios a/b."""
    ratios = [x / y for x, y in zip(times[a], times[b])]
    return {"median_a": statistics.median(times[a]), "median_b": statistics.median(times[b]),
            "ratio": statistics.median(ratios), "ratio_min": min(ratios), "ratio_max": max(ratios),
            "runs": len(ratios)}


def bsdf_instructions(bsdf, n=1024):
    """IR instructions of a BSDF's own ``sample`` and ``eval_pdf``, traced outside a scene.

    Each method is evaluated once on ``n`` varied inputs in a kernel of its own, so the
    count is that BSDF's code alone (no integrator, no dispatch over other BSDFs).
    Returns {"sample": count, "eval_pdf": count}.
    """
    i = dr.arange(mi.Float, n) / n
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = dr.normalize(mi.Vector3f(i - 0.5, 0.3 * i, 1))
    si.uv = mi.Point2f(i, 1 - i)
    ctx = mi.BSDFContext()
    out = {}
    for what in ("sample", "eval_pdf"):
        dr.kernel_history_clear()
        with dr.scoped_set_flag(dr.JitFlag.KernelHistory, True):
            if what == "sample":
                bs, w = bsdf.sample(ctx, si, i, mi.Point2f(0.7 * i, 1 - i))
                dr.eval(bs.wo, bs.pdf, w, bs.sampled_type)
            else:
                f, pdf = bsdf.eval_pdf(ctx, si, dr.normalize(mi.Vector3f(0.2, i, 1)))
                dr.eval(f, pdf)
            hist = dr.kernel_history()
        out[what] = sum(ir_instructions(k) for k in hist if k.get("type") == dr.KernelType.JIT)
    return out
