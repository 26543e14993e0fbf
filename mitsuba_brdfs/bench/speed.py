"""Side-by-side render timings: the Python plugins against Mitsuba's C++ ones, and what each
optional effect of a model costs.

Parts 2 and 4 of the performance study (``python -m mitsuba_brdfs bench``). Every
comparison is a pair of scenes that differ in one thing (the BSDF, one parameter, the
integrator), rendered alternately (A B B A ...) after a warm-up render each, so both see
the same machine load; the result is the median of the per-pair time ratios A / B with
its range. The warm-up render's JIT compilation (code generation + LLVM, or a load from
Dr.Jit's disk cache) and the operation count of the rendering kernel (the largest one,
from ``dr.kernel_history``) are reported beside it: at equal work the op counts explain
the ratio.
"""
import os
import re

import numpy as np

from ..messages import last_line
from ..paths import SCENES
from ..scene_xml import defaults, scene_integrator
from ..progress import advance

__all__ = ["CPP_PAIRS", "cpp_pairs", "effect_pairs", "drops_a_lobe", "compare", "run_cpp",
           "run_effects", "run_figures"]

RED = {"type": "rgb", "value": [0.6, 0.08, 0.05]}


def _as_metal(n, **kw):
    """An AS metal of exponent ``n`` (extra parameters ``kw``)."""
    return {"type": "ashikhmin_shirley", "nu": float(n), "nv": float(n),
            "specular_reflectance": 1.0, "diffuse_reflectance": 0.0, **kw}


def cpp_pairs():
    """(key, Python BSDF, C++ BSDF, why this neighbour): every model's ``cpp`` (``core.facts``),
    keyed by the plugin name and the entry's own key."""
    from ..core.facts import in_folder, label
    from ..models import facts
    return [(label(plugin, key, "_"), {"type": plugin, **in_folder(ours, SCENES)}, theirs, why)
            for plugin, f in facts().items() for key, ours, theirs, why in f.cpp]


#: (key, Python BSDF, C++ BSDF, why this neighbour)
CPP_PAIRS = cpp_pairs()


def _bitmap(channels, lo, hi, res=256, seed=3):
    """A smooth random bitmap texture with values in [lo, hi]."""
    import mitsuba as mi
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:res, 0:res] / res
    base = np.stack([0.5 + 0.5 * np.sin(2 * np.pi * (k + 1) * x + rng.uniform(0, 6))
                     * np.cos(2 * np.pi * (k + 2) * y) for k in range(channels)], axis=-1)
    arr = (lo + (hi - lo) * base).astype(np.float32)
    return {"type": "bitmap", "bitmap": mi.Bitmap(arr), "raw": True,
            "filter_type": "bilinear"}


def effect_pairs(models=()):
    """(key, A, B, what A / B prices); A is the case without the effect.

    Where the description of A ends in "dropped)" A has a lobe of constant zero weight,
    which the plugin must drop (fewer ops, less time); the other effects are only priced.
    ``models``: the models whose dropped lobes are timed (all when empty; that each one's
    absent lobe is not traced is also a test of its own, tests/test_scenes_lobes.py)."""
    from ..core.facts import in_folder, label
    from ..models import facts
    # the models' lobes of zero weight (``dropped_lobes`` of their facts)
    pairs = [(label(plugin, key, "_"), {"type": plugin, **in_folder(a, SCENES)},
              {"type": plugin, **in_folder(b, SCENES)}, label(plugin, what))
             for plugin, f in facts().items() for key, a, b, what in f.dropped_lobes
             if not models or plugin in models]
    # what anisotropy and textures cost, on the model that has both
    pairs += [
        ("as_isotropic_vs_anisotropic", _as_metal(100),
         {**_as_metal(100), "nu": 10.0, "nv": 1000.0},
         "ashikhmin_shirley nu = nv = 100 / nu = 10, nv = 1000 (one code path: ~1 expected)"),
        ("as_constant_vs_bitmap_rd",
         {"type": "ashikhmin_shirley", "diffuse_reflectance": RED},
         {"type": "ashikhmin_shirley", "diffuse_reflectance": _bitmap(3, 0.05, 0.6)},
         "ashikhmin_shirley constant Rd / bitmap Rd (256 x 256 RGB, bilinear)"),
        ("as_constant_vs_bitmap_all",
         {"type": "ashikhmin_shirley", "diffuse_reflectance": RED, "specular_reflectance": 0.1,
          "nu": 100.0, "nv": 100.0},
         {"type": "ashikhmin_shirley", "diffuse_reflectance": _bitmap(3, 0.05, 0.6),
          "specular_reflectance": _bitmap(1, 0.05, 0.15, seed=4),
          "nu": _bitmap(1, 50, 150, seed=5), "nv": _bitmap(1, 50, 150, seed=6)},
         "ashikhmin_shirley all four parameters constant / all four bitmaps"),
    ]
    return pairs


def drops_a_lobe(what):
    """Whether an effect pair (its description, ``effect_pairs``) has A drop a lobe."""
    return what.split("/")[0].strip().endswith(("dropped)", "dropped"))


def compare(a, b, settings, progress=None, note=""):
    """Time BSDFs ``a`` and ``b`` (dicts) on the sphere side by side.

    Returns the medians, the ratio a / b (median of the per-pair ratios, range), each
    one's warm-up compile seconds (and whether its kernels came from the disk cache) and
    the instruction count of its rendering kernel, both measured with that scene alone.
    """
    from ..sphere import sphere_scene
    return compare_builders(
        {"a": lambda: sphere_scene(a, settings.speed_res, settings.speed_spp),
         "b": lambda: sphere_scene(b, settings.speed_res, settings.speed_spp)},
        settings, progress=progress, note=note)


def compare_builders(builders, settings, integrators=None, progress=None, note="",
                     on_image=None):
    """``compare`` for two scene builders named ``a`` and ``b`` (see ``paired_fresh``)."""
    from ..timing import paired_fresh, summary
    times, stats = paired_fresh(builders, runs=settings.speed_runs, integrators=integrators,
                                on_image=on_image)
    s = summary(times, "a", "b")
    s.update({"compile_a": stats["a"]["compile_s"], "compile_b": stats["b"]["compile_s"],
              "disk_a": stats["a"]["disk_hits"], "disk_b": stats["b"]["disk_hits"],
              "instr_a": stats["a"]["instructions_max"], "instr_b": stats["b"]["instructions_max"],
              "times_a": times["a"], "times_b": times["b"],
              "recompiled": times["a:recompiled"] + times["b:recompiled"]})
    advance(progress, 1, f"{note} {s['ratio']:.2f}".strip())
    return s


def _bsdf_instructions(d):
    """``timing.bsdf_instructions`` of a BSDF dict (the instance is dropped afterwards)."""
    import gc

    import mitsuba as mi

    from ..timing import bsdf_instructions
    bsdf = mi.load_dict(d)
    counts = bsdf_instructions(bsdf)
    del bsdf
    gc.collect()
    return counts


def _plugins_of(d):
    """Plugin names a BSDF dict uses (nested ones included)."""
    names = []
    if isinstance(d, dict):
        if "type" in d:
            names.append(d["type"])
        for v in d.values():
            names += _plugins_of(v)
    return names


def _missing(d, available):
    """The package plugins of ``d`` that are not registered."""
    ours = set(_plugins_of(d)) - {"rgb", "bitmap", "diffuse", "roughconductor", "roughplastic"}
    return sorted(n for n in ours if n not in available and not n.startswith("bench_"))


def run_cpp(settings, available, progress=None):
    """Part 2: each Python plugin against its closest C++ neighbour."""
    from ..sphere import sphere_scene
    out = {"settings": {"res": settings.speed_res, "spp": settings.speed_spp,
                        "runs": settings.speed_runs, "integrator": "direct"},
           "pairs": {}, "skipped": []}
    for key, ours, theirs, note in CPP_PAIRS:
        miss = _missing(ours, available)
        if miss:
            out["skipped"].append(f"{key}: plugin `{miss[0]}` is not registered")
            advance(progress, 1, f"skip {key}")
            continue
        r = compare(ours, theirs, settings, progress, note=key)
        # the fixed cost of a render call (tracing the BSDF, launching), measured where the
        # kernel has almost nothing to do: 16 x 16 pixels, 1 spp
        tiny = compare_builders({"a": lambda: sphere_scene(ours, 16, 1),
                                 "b": lambda: sphere_scene(theirs, 16, 1)}, settings)
        r["call_a"], r["call_b"] = tiny["median_a"], tiny["median_b"]
        r.update({"python": ours, "cpp": theirs, "note": note,
                  "plugin": ours["type"], "cpp_plugin": theirs["type"],
                  "bsdf_instr_a": _bsdf_instructions(ours),
                  "bsdf_instr_b": _bsdf_instructions(theirs)})
        out["pairs"][key] = r
    return out


def run_effects(settings, available, progress=None):
    """Part 4: each optional effect against its absence, on the sphere."""
    out = {"settings": {"res": settings.speed_res, "spp": settings.speed_spp,
                        "runs": settings.speed_runs, "models": list(settings.effect_models)},
           "pairs": {}, "skipped": []}
    for key, a, b, what in effect_pairs(settings.effect_models):
        kind = "lobe" if drops_a_lobe(what) else "other"
        miss = _missing(a, available) or _missing(b, available)
        if miss:
            out["skipped"].append(f"{key}: plugin `{miss[0]}` is not registered")
            advance(progress, 1, f"skip {key}")
            continue
        r = compare(a, b, settings, progress, note=key)
        r.update({"what": what, "kind": kind, "a": _described(a), "b": _described(b)})
        out["pairs"][key] = r
    return out


def _described(d):
    """A scene dict described with plain values: an object (a transform, say) by the name of
    its type."""
    if isinstance(d, dict):
        return {k: _described(v) for k, v in d.items()}
    if isinstance(d, (list, tuple)):
        return [_described(v) for v in d]
    if isinstance(d, (str, int, float, bool)) or d is None:
        return d
    return type(d).__name__


# -- figure scenes: direct against path ---------------------------------------------------

def run_figures(settings, available, progress=None):
    """``direct`` against ``path`` on every ``scenes/fig*.xml`` that loads.

    Each scene renders with its own integrator and with the other one (``path`` with the
    scene's max_depth, or 16 for a ``direct`` scene; the same ``hide_emitters``), side by
    side. Besides the time ratio: the relative difference of the image means (what
    ``direct`` misses) and the relative RMS difference per pixel (noise included).
    """
    import mitsuba as mi

    out = {"settings": {"res": settings.fig_res, "spp": settings.fig_spp,
                        "runs": settings.speed_runs}, "scenes": {}, "skipped": []}
    files = sorted(f for f in os.listdir(SCENES) if re.match(r"fig.*\.xml$", f))
    out["files"] = files
    for f in files:
        path = os.path.join(SCENES, f)
        try:
            integrator = scene_integrator(path)
            kind, depth = integrator["type"], integrator.get("max_depth")
            hide = integrator.get("hide_emitters", False)
            accepted = defaults(path)
            defines = {k: str(v) for k, v in (("res", settings.fig_res), ("spp", settings.fig_spp))
                       if k in accepted}
            scene = mi.load_file(path, **defines)
        except Exception as e:  # a scene being written, or a plugin not yet registered
            msg = last_line(e)[:160]
            out["skipped"].append(f"{f}: does not load ({msg})")
            advance(progress, 1, f"skip {f}")
            continue
        path_depth = depth if kind == "path" and depth else 16
        del scene
        integ = {"a": mi.load_dict({"type": "path", "max_depth": path_depth, "hide_emitters": hide}),
                 "b": mi.load_dict({"type": "direct", "hide_emitters": hide})}
        means = {}

        def on_image(name, run, img):
            """Keep the first image of each configuration."""
            if run == 0:
                means[name] = np.array(img, dtype=np.float64)

        build = lambda: mi.load_file(path, **defines)  # noqa: E731
        r = compare_builders({"a": build, "b": build}, settings, integrators=integ,
                             on_image=on_image)
        p, d = means["a"], means["b"]
        r.update({"own": kind, "own_max_depth": depth, "path_max_depth": path_depth,
                  "mean_direct": float(d.mean()), "mean_path": float(p.mean()),
                  "mean_rel_diff": float((p.mean() - d.mean()) / (p.mean() or 1.0))})
        out["scenes"][f] = r
        advance(progress, 1, f)
    return out

