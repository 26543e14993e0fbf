"""The price of accuracy choices: stable against naive formulas, tables against closed forms,
visible-normal sampling, and the statistical power of the chi-square test.

Part 3 of the performance study (``python -m mitsuba_brdfs bench``):

- Numerically stable exponent forms against the formulas as printed (the naive forms are
  in ``bench.plugins``): error against a float64 reference at exponents 1e2-1e6 on inputs
  drawn from the lobe itself (where a renderer evaluates them), and the time of ``n``
  evaluations, stable and naive interleaved. The same for a whole render
  (``bench_as_naive`` against ``ashikhmin_shirley``).
- ``oren_nayar``: the analytic form against the lecture's table (``lut_resolution``).
- ``cook_torrance`` GGX: visible-normal sampling against sampling D cos (variance of the
  sampled weight, seconds per sample, render time and pixel variance).
- The chi-square test (``mitsuba.chi2``): for each sample count, which planted pdf errors
  it detects, and how long it takes.
"""
import math
import statistics
import time

import numpy as np

from ..progress import advance

__all__ = ["run", "stable_vs_naive", "render_naive", "oren_nayar_lut", "ggx_visible", "chi2_power"]

EXPONENTS = (1e2, 1e3, 1e4, 1e5, 1e6)


def _np(x):
    """A Dr.Jit array as float64 NumPy, one row per entry."""
    a = np.array(x, dtype=np.float64)
    return a.T if a.ndim == 2 else a


def _uniform2(n, seed):
    """``n`` uniform 2D samples from a seeded NumPy generator."""
    from ..validate.probe import point2
    rng = np.random.default_rng(seed)
    u = rng.random((2, n), dtype=np.float32)
    return point2(u[0], u[1])


def _rel_err(val, ref):
    """Relative errors where the reference is not negligible; non-finite values counted."""
    val = np.asarray(val, np.float64)
    ref = np.asarray(ref, np.float64)
    bad = ~np.isfinite(val)
    keep = (ref > 1e-30) & ~bad
    e = np.abs(val[keep] - ref[keep]) / ref[keep]
    if e.size == 0:
        return {"median": math.nan, "p99": math.nan, "max": math.nan, "nonfinite": float(bad.mean())}
    return {"median": float(np.median(e)), "p99": float(np.quantile(e, 0.99)),
            "max": float(e.max()), "nonfinite": float(bad.mean())}


# -- stable against naive forms ----------------------------------------------------------------

def _forms():
    """name -> (stable fn, naive fn, inputs(n, exponent, seed), reference(inputs, exponent))."""
    import drjit as dr
    import mitsuba as mi

    from ..core import warp
    from . import plugins as bp

    forms = {}

    # AS eq. 4: (n.h)^E on half vectors drawn from the AS lobe
    def as_inputs(n, e, seed):
        """Half vectors drawn from the AS lobe of exponent ``e``."""
        h = warp.square_to_aniso_phong_half_vector(_uniform2(n, seed), e, e)
        dr.eval(h)
        return (h,)

    def as_ref(inp, e):
        """The float64 cos power of those half vectors."""
        h = _np(inp[0])
        n2 = (h ** 2).sum(1)
        s2 = (h[:, 0] ** 2 + h[:, 1] ** 2) / n2
        return np.exp(e * 0.5 * np.log1p(-s2))

    forms["AS eq. 4 exponent, (n.h)^E"] = (
        lambda h, e: warp.aniso_phong_cos_power(h, e, e),
        lambda h, e: bp.naive_aniso_phong_cos_power(h, e, e), as_inputs, as_ref)

    # AS eq. 9-10: the sampled half vector's sin(theta)
    def sin_of(v):
        """sin(theta) of a unit vector."""
        return dr.sqrt(v.x * v.x + v.y * v.y)

    def samp_inputs(n, e, seed):
        """The uniform samples the elevation sampler takes."""
        u = _uniform2(n, seed)
        dr.eval(u)
        return (u,)

    def samp_ref(inp, e):
        """The float64 sin(theta) of the sampled elevation."""
        u2 = _np(inp[0])[:, 1]
        return np.sqrt(-np.expm1(2 * np.log1p(-u2) / (e + 1)))

    forms["AS eq. 9-10 sampling, sin(theta_h)"] = (
        lambda u, e: sin_of(warp.square_to_aniso_phong_half_vector(u, e, e)),
        lambda u, e: sin_of(bp.naive_aniso_phong_half_vector(u, e, e)), samp_inputs, samp_ref)

    # Phong lobe cos^p(alpha) around a tilted axis (core.warp, where present)
    if hasattr(warp, "phong_lobe_cos_power") and hasattr(warp, "square_to_phong_lobe"):
        axis_np = np.array([0.5, 0.0, math.sqrt(0.75)])

        def phong_inputs(n, e, seed):
            """Directions drawn from the Phong lobe of exponent ``e`` around the axis."""
            axis = mi.Vector3f(*(float(x) for x in axis_np.astype(np.float32)))
            w = warp.square_to_phong_lobe(_uniform2(n, seed), axis, e)
            dr.eval(w)
            return (w, axis)

        def phong_ref(inp, e):
            """The float64 cos power of those directions."""
            w = _np(inp[0])
            w = w / np.linalg.norm(w, axis=1)[:, None]
            a = axis_np.astype(np.float32).astype(np.float64)
            a = a / np.linalg.norm(a)
            omc = 0.5 * ((w - a) ** 2).sum(1)
            return np.where(omc < 1, np.exp(e * np.log1p(-np.minimum(omc, 1))), 0)

        forms["Phong lobe, cos^p(alpha)"] = (
            lambda w, axis, e: warp.phong_lobe_cos_power(w, axis, e),
            lambda w, axis, e: bp.naive_phong_lobe_cos_power(w, axis, e), phong_inputs, phong_ref)
    return forms


def stable_vs_naive(settings, progress=None):
    """Error against float64 and time of each stable formula and its naive form."""
    import drjit as dr
    import mitsuba as mi

    from ..timing import paired_calls
    out = {"samples": settings.micro_n, "error_samples": settings.error_n, "forms": {}}
    for name, (stable, naive, inputs, ref) in _forms().items():
        row = {"error": {}}
        for e in EXPONENTS:
            inp = inputs(settings.error_n, e, seed=int(math.log10(e)))
            r = ref(inp, e)
            row["error"][f"{e:g}"] = {"stable": _rel_err(_np(stable(*inp, mi.Float(e))), r),
                                      "naive": _rel_err(_np(naive(*inp, mi.Float(e))), r)}
        # time at a high exponent; the exponent is opaque (no recompilation per value)
        inp = inputs(settings.micro_n, 1e4, seed=11)
        e_op = dr.opaque(mi.Float, 1e4)

        def timed(fn):
            """A call that evaluates ``fn`` on the inputs and waits for it."""
            def f():
                """Run it once and wait for it."""
                v = fn(*inp, e_op)
                dr.eval(v)
                dr.sync_thread()
            return f
        times = paired_calls({"stable": timed(stable), "naive": timed(naive)},
                             runs=settings.micro_runs, warmup=2)
        ratios = [a / b for a, b in zip(times["naive"], times["stable"])]
        row.update({"ns_stable": statistics.median(times["stable"]) / settings.micro_n * 1e9,
                    "ns_naive": statistics.median(times["naive"]) / settings.micro_n * 1e9,
                    "ratio_naive_stable": statistics.median(ratios),
                    "ratio_min": min(ratios), "ratio_max": max(ratios)})
        out["forms"][name] = row
        advance(progress, 1, name.split(",")[0])
    return out


def render_naive(settings, progress=None):
    """``bench_as_naive`` against ``ashikhmin_shirley`` on the metal sphere at high exponents."""
    from ..sphere import sphere_scene
    from ..timing import time_render
    from .speed import compare
    out = {}
    for n in settings.naive_render_exponents:
        stable = {"type": "ashikhmin_shirley", "nu": n, "nv": n, "specular_reflectance": 1.0,
                  "diffuse_reflectance": 0.0}
        naive = {**stable, "type": "bench_as_naive"}
        r = compare(naive, stable, settings)
        imgs = {}
        for k, b in (("stable", stable), ("naive", naive)):
            _, img = time_render(sphere_scene(b, settings.speed_res, settings.speed_spp), None, 5)
            imgs[k] = np.array(img, dtype=np.float64)
        s, v = imgs["stable"], imgs["naive"]
        finite = np.isfinite(v).all(axis=-1)
        r.update({"nonfinite_pixels": int((~finite).sum()),
                  "mean_rel_diff": float((np.nan_to_num(v).mean() - s.mean()) / s.mean()),
                  "max_pixel_stable": float(s.max()),
                  "max_pixel_naive": float(np.nan_to_num(v, posinf=0).max())})
        out[f"{n:g}"] = r
        advance(progress, 1, f"naive render n={n:g}")
    return out


# -- Oren-Nayar: analytic against the table ----------------------------------------------------

def oren_nayar_lut(settings, progress=None):
    """Oren-Nayar's table against its closed form: render time and eval error."""
    import mitsuba as mi

    from .speed import compare
    base = {"type": "oren_nayar", "reflectance": 0.8, "sigma": 0.5}
    analytic = mi.load_dict(base)
    rng = np.random.default_rng(5)
    n = 100_000
    wi, wo = (_hemisphere(rng, n) for _ in range(2))
    f0 = _eval(analytic, wi, wo)
    del analytic  # a live BSDF would be traced into every render's kernel
    scale = f0.max()
    out = {}
    for res in settings.onr_luts:
        lut = {**base, "lut_resolution": res}
        f = _eval(mi.load_dict(lut), wi, wo)
        r = compare(lut, base, settings)
        r.update({"max_abs_err_rel": float(np.abs(f - f0).max() / scale),
                  "mean_abs_err_rel": float(np.abs(f - f0).mean() / scale)})
        out[str(res)] = r
        advance(progress, 1, f"oren_nayar lut {res}")
    return out


def _hemisphere(rng, n):
    """``n`` random float32 directions on the upper hemisphere."""
    ct = rng.uniform(0.001, 1, n)
    phi = rng.uniform(0, 2 * np.pi, n)
    st = np.sqrt(1 - ct * ct)
    return np.stack([st * np.cos(phi), st * np.sin(phi), ct], 1).astype(np.float32)


def _si(wi):
    """A surface interaction per direction ``wi`` (frame and uv as the chi-square adapter has them)."""
    import drjit as dr
    import mitsuba as mi
    from ..validate.probe import vec
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = vec(wi)
    si.uv = mi.Point2f(0.5, 0.5)
    return si


def _eval(bsdf, wi, wo):
    """The BSDF's eval at the pairs (wi, wo), averaged over the channels."""
    import mitsuba as mi
    from ..validate.probe import vec
    f = bsdf.eval(mi.BSDFContext(), _si(wi), vec(wo))
    return _np(f).mean(axis=1)


# -- GGX: visible normals against D cos -------------------------------------------------------

def ggx_visible(settings, progress=None):
    """GGX visible-normal sampling against sampling D cos: weight variance, time, renders."""
    import drjit as dr
    import mitsuba as mi

    from ..sphere import sphere_scene
    from ..timing import paired_calls, time_render
    from .speed import compare
    out = {"roughness": {}}
    for rho in (0.1, 0.5):
        cfg = {s: {"type": "cook_torrance", "distribution": "ggx", "geometry": "ggx",
                   "roughness": rho, "k": 0.0, "f0": 1.0, "sample_visible": s}
               for s in (True, False)}
        bsdfs = {s: mi.load_dict(c) for s, c in cfg.items()}
        n = settings.alone_samples
        rows = {}
        for theta in (0, 45, 75, 85):
            wi = np.repeat([[math.sin(math.radians(theta)), 0, math.cos(math.radians(theta))]], n, 0)
            si = _si(wi.astype(np.float32))
            sampler = mi.load_dict({"type": "independent"})
            sampler.seed(theta, n)
            u1, u2 = sampler.next_1d(), sampler.next_2d()
            dr.eval(si, u1, u2)
            ctx = mi.BSDFContext()
            row = {}
            for s, b in bsdfs.items():
                _, w = b.sample(ctx, si, u1, u2)
                w = _np(w[0])
                row["visible" if s else "plain"] = {"albedo": float(w.mean()),
                                                    "rel_variance": float(w.var() / w.mean() ** 2)}

            def sample_fn(b, ctx=ctx, si=si, u1=u1, u2=u2):
                """A call that samples ``b`` at these inputs and waits for it."""
                def f():
                    """Run it once and wait for it."""
                    _, w = b.sample(ctx, si, u1, u2)
                    dr.eval(w)
                    dr.sync_thread()
                return f
            times = paired_calls({"visible": sample_fn(bsdfs[True]), "plain": sample_fn(bsdfs[False])},
                                 runs=settings.micro_runs, warmup=1)
            for k in ("visible", "plain"):
                row[k]["ns_per_sample"] = statistics.median(times[k]) / n * 1e9
            v, p = row["visible"], row["plain"]
            row["efficiency_ratio"] = (p["rel_variance"] * p["ns_per_sample"]) / \
                (v["rel_variance"] * v["ns_per_sample"]) if v["rel_variance"] > 0 else math.inf
            rows[theta] = row
        # the whole render: time ratio and per-pixel variance (from two seeds); live BSDFs
        # would be traced into every render's kernel
        del bsdfs, si, u1, u2, sample_fn
        r = compare(cfg[True], cfg[False], settings)
        var = {}
        for s, c in cfg.items():
            scene = sphere_scene(c, settings.speed_res, settings.speed_spp)
            a = np.array(time_render(scene, None, 101)[1], dtype=np.float64)
            b = np.array(time_render(scene, None, 102)[1], dtype=np.float64)
            var[s] = float(np.mean((a - b) ** 2) / 2)
        r.update({"pixel_variance_visible": var[True], "pixel_variance_plain": var[False]})
        r["render_efficiency_ratio"] = (var[False] * r["median_b"]) / (var[True] * r["median_a"]) \
            if var[True] > 0 else math.inf
        out["roughness"][f"{rho:g}"] = {"bsdf": rows, "render": r}
        advance(progress, 1, f"GGX visible rho={rho:g}")
    return out


# -- the chi-square test's power ----------------------------------------------------------------

def chi2_power(settings, progress=None):
    """Planted pdf errors against the chi-square test, per sample count.

    The BSDF is ``cook_torrance`` (GGX, rho = 0.3, metal) at 45 degrees incidence, sampled
    correctly; its pdf is then reported wrong in one of two ways:

    - ``scale``: pdf x (1 + eps) everywhere (integrates to 1 + eps);
    - ``tilt``: pdf x (1 + eps sign(wo_y)), still integrating to 1 (the lobe is symmetric
      in y): a shape error that no normalisation check sees.

    Res 161 and ires 16, as the project's cook_torrance tests. Seconds: histogram + pdf
    tabulation + test, after a warm-up at each sample count (compilation apart).
    """
    import drjit as dr
    import mitsuba as mi
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    cfg = {"type": "cook_torrance", "distribution": "ggx", "geometry": "ggx", "roughness": 0.3,
           "k": 0.0, "f0": 1.0}
    t = math.radians(45)
    sample_func, pdf_func = BSDFAdapter("cook_torrance", cfg,
                                        wi=mi.Vector3f(math.sin(t), 0, math.cos(t)))
    eps_var = dr.opaque(mi.Float, 0.0)
    kind = {"v": "scale"}

    def planted_pdf(wo, *args):
        """The pdf with the planted error (a scale or a tilt of eps)."""
        p = pdf_func(wo, *args)
        if kind["v"] == "scale":
            return p * (1 + eps_var)
        return p * (1 + eps_var * dr.sign(wo.y))

    def one(n):
        """One chi-square test at ``n`` samples: rejected, p-value, seconds."""
        test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func,
                             pdf_func=planted_pdf, sample_dim=3, sample_count=n, res=161,
                             ires=16, seed=n % 1000 + 1)
        t0 = time.perf_counter()
        ok = test.run(0.01, quiet=True)
        p = test.p_value
        p = float(p[0]) if hasattr(p, "__len__") else float(p)
        return (not ok), p, time.perf_counter() - t0

    out = {"plugin": cfg, "theta_i": 45, "res": 161, "ires": 16, "significance": 0.01,
           "samples": {}}
    for n in settings.chi2_samples:
        kind["v"] = "scale"
        eps_var = dr.opaque(mi.Float, 0.0)
        t0 = time.perf_counter()
        one(n)  # warm-up: compiles
        warm = time.perf_counter() - t0
        row = {"warmup_s": warm, "clean": None, "scale": {}, "tilt": {}}
        rejected, p, sec = one(n)
        row["clean"] = {"rejected": rejected, "p_value": p, "seconds": sec}
        for k in ("scale", "tilt"):
            kind["v"] = k
            for eps in settings.chi2_eps:
                eps_var = dr.opaque(mi.Float, eps)
                rejected, p, sec = one(n)
                row[k][f"{eps:g}"] = {"rejected": rejected, "p_value": p, "seconds": sec}
        for k in ("scale", "tilt"):
            # smallest eps from which on every larger one is detected
            eps_sorted = sorted(float(e) for e in row[k])
            thr = math.nan
            for e in reversed(eps_sorted):
                if row[k][f"{e:g}"]["rejected"]:
                    thr = e
                else:
                    break
            row[f"{k}_threshold"] = thr
        row["median_seconds"] = statistics.median(
            [v["seconds"] for k in ("scale", "tilt") for v in row[k].values()])
        out["samples"][str(n)] = row
        advance(progress, 1, f"chi2 {n} samples")
    return out


def run(settings, available, progress=None):
    """Measure the section: every comparison whose plugins are registered."""
    out = {"skipped": []}
    out["stable_vs_naive"] = stable_vs_naive(settings, progress)
    if "ashikhmin_shirley" in available:
        out["render_naive"] = render_naive(settings, progress)
    if "oren_nayar" in available:
        out["oren_nayar_lut"] = oren_nayar_lut(settings, progress)
    else:
        out["skipped"].append("Oren-Nayar analytic vs table: plugin `oren_nayar` is not registered")
        advance(progress, len(settings.onr_luts), "skip oren_nayar")
    if "cook_torrance" in available:
        out["ggx_visible"] = ggx_visible(settings, progress)
        out["chi2"] = chi2_power(settings, progress)
    else:
        out["skipped"].append("GGX sampling and chi-square: plugin `cook_torrance` is not registered")
    return out
