"""Error against time: what each sampling strategy needs to reach a given image error.

Part 1 of the performance study (``python -m mitsuba_brdfs bench``). Every scene is the
sphere of ``scenes/as_sphere.xml`` with one material. A reference is rendered at high spp
with the model's own importance sampling and multiple importance sampling (MIS) with
emitter sampling, in two independent halves: half the mean squared difference of the
halves, over two, is the variance the reference still carries, and is subtracted from
every measured mean squared error (the error is then that against the exact image).

Strategies, all with Mitsuba's ``direct`` integrator (what the path tracer does at each
vertex: one emitter sample and one BSDF sample, weighted by MIS, or BSDF sampling alone):

- ``importance + MIS``: the model's sampler, emitter sampling and MIS;
- ``importance, BSDF only``: the model's sampler alone (``emitter_samples = 0``);
- ``cosine + MIS`` / ``cosine, BSDF only``: cosine-weighted directions instead
  (``sampling = cosine`` for ``ashikhmin_shirley``; the ``bench_cosine`` wrapper around
  the model's ``eval`` for the others).

Each strategy renders at increasing spp; at each spp every strategy is rendered ``runs``
times with new seeds, in alternating order, after a warm-up render that compiles its
kernels (reported apart). Time is the median, the error sqrt(mean MSE - reference
variance) over the runs, relative to the mean of the reference image. Each render builds
its scene afresh so that its kernel holds its own BSDF only (see ``timing.paired_fresh``). The time to reach a
target relative RMSE extrapolates from the largest spp with RMSE^2 x time = const (the
Monte Carlo law, which the measured slopes are checked against).
"""
import math
import statistics

import numpy as np

from ..progress import advance

__all__ = ["SCENES", "STRATEGIES", "relative_rmse", "time_to_target", "run"]

RED = [0.6, 0.08, 0.05]

#: (key, title, plugin, parameters)
SCENES = [
    ("as_metal_1000", "AS metal, nu = nv = 1000", "ashikhmin_shirley",
     {"nu": 1000.0, "nv": 1000.0, "specular_reflectance": 1.0, "diffuse_reflectance": 0.0}),
    ("as_aniso_10_1000", "AS metal, nu = 10, nv = 1000", "ashikhmin_shirley",
     {"nu": 10.0, "nv": 1000.0, "specular_reflectance": 1.0, "diffuse_reflectance": 0.0}),
    ("as_polished", "AS polished, Rs = 0.05, red Rd, nu = nv = 400", "ashikhmin_shirley",
     {"nu": 400.0, "nv": 400.0, "specular_reflectance": 0.05,
      "diffuse_reflectance": {"type": "rgb", "value": RED}}),
    ("phong", "Phong normalized, p = 200, kd red, ks = 0.3", "phong",
     {"exponent": 200.0, "form": "normalized", "specular_reflectance": 0.3,
      "diffuse_reflectance": {"type": "rgb", "value": RED}}),
    ("ward", "Ward, alpha_u = 0.05, alpha_v = 0.2, kd red, ks = 0.3", "ward",
     {"alpha_u": 0.05, "alpha_v": 0.2, "specular_reflectance": 0.3,
      "diffuse_reflectance": {"type": "rgb", "value": RED}}),
    ("cook_torrance", "Cook-Torrance Beckmann, rho = 0.15, k = 0.5, f0 = 0.5, red m_D",
     "cook_torrance",
     {"distribution": "beckmann", "geometry": "cook_torrance", "roughness": 0.15, "k": 0.5,
      "f0": 0.5, "diffuse_reflectance": {"type": "rgb", "value": RED}}),
]

#: strategy -> (importance sampling?, MIS with emitter sampling?)
STRATEGIES = {
    "importance + MIS": (True, True),
    "importance, BSDF only": (True, False),
    "cosine + MIS": (False, True),
    "cosine, BSDF only": (False, False),
}


def _bsdf(plugin, params, importance):
    """The BSDF dict of a strategy: the plugin, or it sampled cosine-weighted."""
    d = {"type": plugin, **params}
    if importance:
        return d
    if plugin == "ashikhmin_shirley":
        return {**d, "sampling": "cosine"}
    return {"type": "bench_cosine", "bsdf": d}


def _integrator(mis):
    """``direct`` with emitter sampling and MIS, or BSDF sampling alone."""
    import mitsuba as mi
    if mis:
        return mi.load_dict({"type": "direct"})
    return mi.load_dict({"type": "direct", "emitter_samples": 0, "bsdf_samples": 1})


def relative_rmse(mse, ref_var, ref_mean):
    """sqrt(max(mse - ref_var, 0)) / ref_mean: the error against the exact image."""
    return math.sqrt(max(mse - ref_var, 0.0)) / ref_mean


def time_to_target(points, target):
    """Seconds to reach relative RMSE ``target`` from measured (seconds, rel_rmse) points.

    Interpolates in log-log between the two points that bracket the target; beyond the
    largest spp extrapolates from it with RMSE^2 x time = const. Returns (seconds,
    extrapolated?) or (nan, False) without usable points.
    """
    pts = [(t, e) for t, e in points if t > 0 and e > 0 and math.isfinite(e)]
    if not pts:
        return math.nan, False
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if e0 >= target >= e1 and e0 != e1:
            a = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + a * (math.log(t1) - math.log(t0))), False
    if pts[0][1] <= target:
        return pts[0][0], False  # already below the target at the smallest spp
    t, e = pts[-1]
    return t * (e / target) ** 2, True


def _slope(points):
    """Least-squares slope of log(rel RMSE) against log(seconds) (-1/2 for Monte Carlo)."""
    pts = [(math.log(t), math.log(e)) for t, e in points if t > 0 and e > 0]
    if len(pts) < 2:
        return math.nan
    x, y = np.array(pts).T
    return float(np.polyfit(x, y, 1)[0])


def _reference(scene, spp, seed):
    """Two independent halves: (mean image, per-pixel variance of that mean, averaged)."""
    from ..passes import render_passes
    half = max(spp // 2, 1)
    a, _ = render_passes(scene, half, seed=seed, progress=False)
    b, _ = render_passes(scene, half, seed=seed + 1, progress=False)
    a, b = a.astype(np.float64), b.astype(np.float64)
    ref = 0.5 * (a + b)
    # E[(a - b)^2] = 2 var(half); var(ref) = var(half) / 2
    return ref, float(np.mean((a - b) ** 2)) / 4


def run(settings, available, progress=None):
    """Measure every scene whose plugin is registered; returns a JSON-ready dict."""
    import drjit as dr

    from ..sphere import sphere_scene
    from ..timing import paired_fresh

    out = {"settings": {"res": settings.err_res, "spps": list(settings.err_spps),
                        "runs": settings.err_runs, "reference_spp": settings.err_ref_spp,
                        "target": settings.err_target},
           "scenes": {}, "skipped": []}
    for key, title, plugin, params in SCENES:
        if plugin not in available:
            out["skipped"].append(f"{key}: plugin `{plugin}` is not registered")
            advance(progress, len(settings.err_spps) + 1, f"skip {key}")
            continue
        builders = {name: (lambda b=_bsdf(plugin, params, imp): sphere_scene(b, settings.err_res, 1))
                    for name, (imp, _) in STRATEGIES.items()}
        integrators = {name: _integrator(mis) for name, (_, mis) in STRATEGIES.items()}
        scene = builders["importance + MIS"]()
        ref, ref_var = _reference(scene, settings.err_ref_spp, seed=7)
        del scene
        ref_mean = float(ref.mean())
        advance(progress, 1, f"{key} reference")
        res = {"title": title, "plugin": plugin, "params": params, "reference_mean": ref_mean,
               "reference_rel_std": math.sqrt(ref_var) / ref_mean,
               "strategies": {name: {"spp": [], "seconds": [], "rel_rmse": [], "compile_s": [],
                                     "instructions": []}
                              for name in STRATEGIES}}
        for spp in settings.err_spps:
            mses = {name: [] for name in STRATEGIES}

            def on_image(name, run, img):
                """Record the squared error of a strategy's image."""
                arr = np.array(img, dtype=np.float64)
                mses[name].append(float(np.mean((arr - ref) ** 2)))

            # each strategy is rendered alone (built afresh), alternating, after a warm-up
            secs, stats = paired_fresh(builders, runs=settings.err_runs, spp=spp,
                                       integrators=integrators, on_image=on_image,
                                       seed0=1000 * spp)
            dr.flush_malloc_cache()
            for name in STRATEGIES:
                s = res["strategies"][name]
                s["spp"].append(spp)
                s["seconds"].append(statistics.median(secs[name]))
                s["rel_rmse"].append(relative_rmse(statistics.fmean(mses[name]), ref_var, ref_mean))
                s["compile_s"].append(stats[name]["compile_s"])
                s["recompiled"] = s.get("recompiled", 0) + secs[name + ":recompiled"]
                s["instructions"].append(stats[name]["instructions_max"])
            advance(progress, 1, f"{key} {spp} spp")
        for name, s in res["strategies"].items():
            pts = list(zip(s["seconds"], s["rel_rmse"]))
            s["slope"] = _slope(pts)
            s["time_to_target"], s["extrapolated"] = time_to_target(pts, settings.err_target)
            # efficiency 1 / (MSE x time) at the largest spp, relative MSE
            t, e = pts[-1]
            s["efficiency"] = 1.0 / (e * e * t) if e > 0 else math.inf
        out["scenes"][key] = res
        dr.flush_malloc_cache()
    if "ashikhmin_shirley" in available:
        out["bsdf_alone"] = bsdf_alone_efficiency(settings, progress)
    return out


def bsdf_alone_efficiency(settings, progress=None):
    """1 / (variance x time) of AS half-vector against cosine sampling, BSDF alone.

    The estimator is the sampled weight f cos / pdf at a fixed incidence (its mean is the
    directional albedo): its variance over ``n`` samples and the seconds per sample of the
    ``sample`` call (median of interleaved runs after a warm-up), nu = nv = 1000, Rs = 1.
    """
    import drjit as dr
    import mitsuba as mi

    from ..timing import paired_calls

    n = settings.alone_samples
    out = {"samples": n, "nu": 1000.0, "nv": 1000.0, "incidences": {}}
    bsdfs = {s: mi.load_dict({"type": "ashikhmin_shirley", "nu": 1000.0, "nv": 1000.0,
                              "specular_reflectance": 1.0, "diffuse_reflectance": 0.0,
                              "sampling": s}) for s in ("half_vector", "cosine")}
    sampler = mi.load_dict({"type": "independent"})
    for theta in (0, 45, 75):
        sampler.seed(theta, n)
        u1, u2 = sampler.next_1d(), sampler.next_2d()
        dr.eval(u1, u2)
        st, ct = math.sin(math.radians(theta)), math.cos(math.radians(theta))
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(st, 0, ct)
        si.uv = mi.Point2f(0.5, 0.5)
        dr.eval(si)
        ctx = mi.BSDFContext()
        weights = {}

        def sample_fn(b, keep=None):
            """A call that samples ``b`` (keeping the weights if asked) and waits."""
            def f():
                """Run it once and wait for it."""
                _, w = b.sample(ctx, si, u1, u2)
                w = w[0]
                dr.eval(w)
                dr.sync_thread()
                if keep is not None:
                    keep.append(w)
            return f

        for s, b in bsdfs.items():
            keep = []
            sample_fn(b, keep)()
            weights[s] = np.array(keep[0], dtype=np.float64)
        times = paired_calls({s: sample_fn(b) for s, b in bsdfs.items()}, runs=settings.micro_runs)
        row = {}
        for s in bsdfs:
            w = weights[s]
            sec = statistics.median(times[s]) / n
            var = float(w.var())
            row[s] = {"albedo": float(w.mean()), "variance": var, "seconds_per_sample": sec,
                      "efficiency": 1.0 / (var * sec) if var > 0 else math.inf}
        hv, cs = row["half_vector"], row["cosine"]
        row["efficiency_ratio"] = hv["efficiency"] / cs["efficiency"]
        row["time_ratio"] = hv["seconds_per_sample"] / cs["seconds_per_sample"]
        row["variance_ratio"] = cs["variance"] / hv["variance"] if hv["variance"] > 0 else math.inf
        out["incidences"][theta] = row
    advance(progress, 1, "BSDF-alone efficiency")
    return out
