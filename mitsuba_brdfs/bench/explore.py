"""The explorer's speed: how long a parameter change takes to reach the plots and the sphere.

``measure()`` loads two BSDFs as ``python -m mitsuba_brdfs explore ashikhmin_shirley
roughplastic`` does, warms the kernel cache (the first plots and sphere), then changes a
parameter ``repeats`` times through the page's API and times, with the cache warm:

- ``plots_ms``: the parameter update (``mi.traverse``) and every plot's data of both BSDFs,
  encoded as the JSON the page receives (the page's own drawing is not included);
- ``sphere_ms``: the first pass of the sphere of the changed BSDF, encoded as PNG;
- ``pass_ms``: a later pass (the refinement).

Returns the medians and ``markdown``, a short paragraph for the performance study, which
compares them with the targets (150 ms for the plots, 0.5 s for the first sphere).
"""
import json
import statistics
import time

__all__ = ["PLOTS_TARGET_MS", "SPHERE_TARGET_MS", "measure", "markdown"]

PLOTS_TARGET_MS = 150
SPHERE_TARGET_MS = 500


def _ms(fn):
    t0 = time.perf_counter()
    fn()
    return (time.perf_counter() - t0) * 1e3


def measure(repeats=15, variant="llvm_ad_rgb"):
    """Medians (ms) of the explorer's redraw after a parameter change; see the module."""
    import drjit as dr
    import mitsuba as mi
    if mi.variant() != variant:
        mi.set_variant(variant)
    import mitsuba_brdfs
    mitsuba_brdfs.register()
    from ..explore.entries import make_entries
    from ..explore.server import PALETTE, Explorer
    found = make_entries("ashikhmin_shirley", {}, 0, PALETTE)
    found += make_entries("roughplastic", {}, 1, PALETTE)
    ex = Explorer(found, variant)
    body = {"theta_i": 45, "theta_h": 30, "theta_d": 30, "exposure": 0}
    light = (45.0, 135.0, 0.0)
    t_first = _ms(lambda: json.dumps(ex.plots(body)))  # compiles, or loads from disk
    t_first_sphere = _ms(lambda: ex.sphere(0, 0, *light))
    for k in range(2):  # warm: the kernels after an update
        ex.patch(0, {"name": "nu", "value": 50.0 + k})
        json.dumps(ex.plots(body))
        ex.sphere(0, 0, *light)
    plots, sphere, passes = [], [], []
    for k in range(repeats):
        value = 20.0 + 10 * k
        plots.append(_ms(lambda: (ex.patch(0, {"name": "nu", "value": value}),
                                  json.dumps(ex.plots(body)))))
        sphere.append(_ms(lambda: ex.sphere(0, 0, *light)))
        passes.append(_ms(lambda: ex.sphere(0, 1, *light)))
    out = {"plots_ms": statistics.median(plots), "sphere_ms": statistics.median(sphere),
           "pass_ms": statistics.median(passes), "first_plots_ms": t_first,
           "first_sphere_ms": t_first_sphere, "repeats": repeats, "bsdfs": 2,
           "threads": dr.thread_count(), "variant": variant}
    out["markdown"] = markdown(out)
    return out


def markdown(m):
    """The paragraph of the performance study."""
    ok = lambda x, t: "within" if x <= t else "over"  # noqa: E731
    return (
        f"**Explorer.** With two BSDFs shown (`ashikhmin_shirley`, `roughplastic`; "
        f"{m['variant']}, {m['threads']} threads, warm kernel cache), a parameter change "
        f"reaches the data of every plot in {m['plots_ms']:.0f} ms (median of "
        f"{m['repeats']}; {ok(m['plots_ms'], PLOTS_TARGET_MS)} the {PLOTS_TARGET_MS} ms "
        f"target, the browser's drawing not included) and the first pass of the sphere in "
        f"{m['sphere_ms']:.0f} ms ({ok(m['sphere_ms'], SPHERE_TARGET_MS)} the "
        f"{SPHERE_TARGET_MS} ms target); each further pass takes {m['pass_ms']:.0f} ms. "
        f"The parameters are updated through `mi.traverse`, so no kernel is compiled: the "
        f"first plots of a session took {m['first_plots_ms']:.0f} ms and its first sphere "
        f"{m['first_sphere_ms']:.0f} ms (kernels compiled or loaded from Dr.Jit's disk "
        f"cache).")
