"""The suite's checks of sampling and density: ``chi2`` (sample() against pdf()), ``weight``
(weight = eval / pdf), ``eval_pdf``, ``pdf`` (integrates to at most 1), ``furnace`` (mean
weight = quadrature of eval) and ``energy`` (the albedo at most 1, by the mean weight and by
the quadrature of eval). Each takes a ``Subject`` and
returns a ``Result``; ``validate.suite`` runs them and says what FAILs and what WARNs.
"""
import re

import mitsuba as mi
import numpy as np

from .directions import sph
from .energy import albedo_bound, quadrature
from .probe import call_eval, call_eval_pdf, call_pdf, close, interaction, rows, short, vec
from .results import Result, deg, fmt, verdict, warning
from .sampling import chi2, weight_errors
from .subject import (furnace_tolerance, incidence_quadratures, kept, mean_weights,
                      per_incidence, quadratures, weights_ok)

__all__ = ["chi2_result", "weight_result", "eval_pdf_result", "pdf_result", "furnace_result",
           "energy_result"]


def chi2_result(s):
    """sample() against pdf(): Mitsuba's chi-square test at every chi-square incidence."""
    st = s.settings
    if len(s.delta) == s.count:
        return Result("chi2", "SKIP", message="every lobe is a delta lobe: no density to test")
    ctx = mi.BSDFContext()  # Dirac samples are dropped (``sampling.bsdf_functions``)
    thetas = s.thetas(st.chi2_thetas)
    table, failed, inconclusive, masked, idle, data = [], [], [], [], [], {}
    black = []  # incidences where every weight is 0 and eval too: samples judged by pdf > 0
    for t in thetas:
        wi = sph(np.radians(t), 0.3)[0]
        kw = dict(res=st.chi2_res, ires=st.chi2_ires, sample_count=st.chi2_samples,
                  significance=st.significance, test_count=len(thetas),
                  same_side=not s.transmissive)
        r = chi2(s.bsdf, wi, ctx, **kw)
        if r["histogram_sum"] == 0 and r["pdf_sum"] > 0 and _black(s, wi, ctx):
            black.append(t)
            r = chi2(s.bsdf, wi, ctx, by_pdf=True, **kw)
        if r["histogram_sum"] == 0 and r["pdf_sum"] == 0:  # nothing scatters (a back side)
            idle.append(t)
            continue
        table.append({"theta": t, "p_value": r["p_value"], "pdf_sum": r["pdf_sum"],
                      "kept": r["histogram_sum"], "ok": r["ok"]})
        data[t] = {"histogram": r["histogram"], "expected": r["expected"], "ok": r["ok"],
                   "p_value": r["p_value"]}
        if not r["ok"]:
            why, kind = _chi2_failure(s, r, wi, ctx)
            {"fail": failed, "inconclusive": inconclusive,
             "masked": masked}[kind].append((t, why))
    numbers = {"theta": [r["theta"] for r in table], "p_value": [r["p_value"] for r in table],
               "pdf_sum": [r["pdf_sum"] for r in table], "kept": [r["kept"] for r in table],
               "res": st.chi2_res, "ires": st.chi2_ires, "samples": st.chi2_samples,
               "idle": idle, "inconclusive": [t for t, _ in inconclusive]}
    ps = ", ".join(f"{fmt(r['p_value'], 2)} ({deg(r['theta'])})" for r in table)
    msg = (f"p-values {ps} at theta_i (deg); res {st.chi2_res}, ires {st.chi2_ires}, "
           f"{st.chi2_samples:,} samples each, significance {st.significance} over all")
    if idle:
        msg += f"; nothing scatters at theta_i = {', '.join(map(deg, idle))}"
    if black:
        msg += (f"; black at theta_i = {', '.join(map(deg, black))} (every weight 0): samples "
                f"of pdf > 0 tested")
    if s.delta:
        msg += f"; delta lobes {s.delta} left out"
    if inconclusive:
        msg += "; inconclusive " + "; ".join(_by_reason(inconclusive))
    problems = _by_reason(failed)
    warnings = [warning("incidences where sample() and eval() give nothing but pdf() is "
                        "not 0", len(masked), f"theta_i = {deg(masked[0][0])} deg: "
                        f"{masked[0][1]}")] if masked else []
    return verdict("chi2", numbers, msg, problems, warnings, data)


def _by_reason(items):
    """[(theta, why)] said once per reason: "at 0, 30 deg: why". Reasons that differ only in
    their numbers are one reason, said with the numbers of its first incidence."""
    groups = {}
    for t, why in items:
        groups.setdefault(re.sub(r"\d[\d.e+-]*", "#", why), []).append((t, why))
    out = []
    for members in groups.values():
        (t0, why), alike = members[0], {w for _, w in members}
        thetas = ", ".join(deg(t) for t, _ in members)
        if len(alike) > 1:
            why += f" (the numbers at {deg(t0)} deg)"
        out.append(f"at {thetas} deg: {why}")
    return out


def _black(s, wi, ctx):
    """Whether eval() integrates to 0 at wi (in every channel)."""
    (f, _), _ = quadrature(s.bsdf, wi, s.settings.quad // 2, ctx, same_side=not s.transmissive)
    return not np.any(f != 0)


def _chi2_failure(s, r, wi, ctx):
    """Why a chi-square test failed, in a few words, and of what kind: "fail"; "masked",
    sample() draws nothing where pdf() is not 0 but eval() is 0 (only a MIS weight sees that
    pdf, and it multiplies eval = 0); "inconclusive", the test's cells were too coarse for
    the pdf (they integrate it to a total that differs from a finer quadrature: the expected
    counts are off, whatever the BSDF does, and the 'pdf' and 'furnace' checks, on the finer
    quadrature, stand in)."""
    if r["histogram_sum"] == 0:
        why = (f"sample() draws nothing (every weight 0, every pdf 0), but pdf() integrates "
               f"to {r['pdf_sum']:.4g}")
        if _black(s, wi, ctx):  # nor does eval: only a MIS weight sees this pdf
            return why + " (eval() is 0 there too)", "masked"
        return why, "fail"
    lines = r["messages"].splitlines()
    reasons = [ln.removeprefix("Failure: ").rstrip(".!") for ln in lines
               if ln.startswith(("Failure", "Encountered", "Sample weights"))]
    stat = next((ln for ln in lines if ln.startswith("Chi^2 statistic")), "")
    if reasons:  # samples where nothing is expected, negative values: no resolution excuses
        return "; ".join(reasons), "fail"
    _, (p_quad, p_err) = quadrature(s.bsdf, wi, s.settings.quad, ctx,
                                    same_side=not s.transmissive)
    st = s.settings
    if abs(r["pdf_sum"] - p_quad) > max(2e-3, 2 * p_err) * max(p_quad, 1e-3):
        return (f"the test's cells integrate the pdf to {r['pdf_sum']:.4f}, a finer quadrature "
                f"to {p_quad:.4f}: the lobe is too sharp for res {st.chi2_res}, ires "
                f"{st.chi2_ires} (p = {r['p_value']:.2g}; --thorough is finer)"), "inconclusive"
    return (f"rejected, p = {r['p_value']:.2g} ({stat.lower()}); the pdf integrates to "
            f"{r['pdf_sum']:.4f} and the samples kept are {r['histogram_sum']:.4f} of all"), "fail"


def _only_delta(rec):
    """Whether every sample of rec that counts is a delta (or null) lobe's: none of a smooth
    lobe with pdf > 0, whose weight, pdf and eval the checks could compare."""
    return bool(rec["delta"].any() and not rec["ok"].any())


def weight_result(s):
    """weight = eval / pdf and sample pdf = pdf() on the sampled directions."""
    st = s.settings
    rec = s.record()
    if _only_delta(rec):
        return Result("weight", "SKIP", {"samples": int(len(rec["ok"]))},
                      f"every one of {len(rec['ok']):,} samples is of a delta lobe, whose "
                      f"weight is not eval / pdf (both 0 off the delta): 'energy' bounds "
                      f"those weights, 'hard_cases' checks they are finite")
    atol = 1e-6 * float(np.abs(rec["weight"]).max(initial=0.0))
    e = weight_errors(rec, st.weight_rtol, st.weight_rtol, atol, zero_weight_fails=True)
    valid = [float(v.mean()) for v in per_incidence(rec, kept(rec))]
    numbers = {"samples": int(len(rec["ok"])), "weight_max_rel": e["weight"]["max_rel"],
               "weight_off": e["weight"]["off"], "pdf_max_rel": e["pdf"]["max_rel"],
               "pdf_off": e["pdf"]["off"], "failed_weight_max": e["failed"]["max_rel"],
               "rtol": st.weight_rtol, "theta": rec["thetas"], "valid": valid}
    ok, rounding = weights_ok(rec, e, st.weight_rtol, atol)
    msg = (f"{numbers['samples']:,} samples: largest relative error of the weight against "
           f"eval/pdf {e['weight']['max_rel']:.2g}, of the sample pdf against pdf() "
           f"{e['pdf']['max_rel']:.2g} (tolerance {st.weight_rtol:g}); "
           + ("samples with pdf 0 weigh 0" if e["failed"]["ok"] else
              f"samples with pdf 0 weigh up to {e['failed']['max_rel']:.2g}"))
    n_delta = int(rec["delta"].sum())
    if n_delta:
        msg += f"; {n_delta:,} samples of delta lobes left out (their weight is not eval/pdf)"
    if rounding:
        msg += (f"; {rounding} sample(s) within 10 x the tolerance (float rounding, allowed in "
                f"up to 1 sample in 100,000)")
    problems = []
    if not ok:
        bad = [k for k in ("weight", "pdf", "failed") if not e[k]["ok"]]
        problems.append("off: " + ", ".join(f"{e[k]['off']} {k}" for k in bad))
    # what the path tracer uses of a sample of non-zero weight: its pdf (MIS) and direction
    used = (rec["weight"] != 0).any(axis=1) & ~rec["delta"]
    broken = used & ~(np.isfinite(rec["pdf"]) & (rec["pdf"] >= 0)
                      & np.isfinite(rec["wo"]).all(axis=1))
    if broken.any():
        k = int(np.argmax(broken))
        problems.append(f"{int(broken.sum())} samples of non-zero weight with a pdf or direction "
                        f"that is not finite (e.g. pdf {short(rec['pdf'][k])}, wo "
                        f"{short(rec['wo'][k])} at wi = {short(rec['wi'][k])})")
    return verdict("weight", numbers, msg, problems)


def eval_pdf_result(s):
    """eval_pdf() = (eval(), pdf()) on the sampled directions and on random pairs."""
    st = s.settings
    rec = s.record()
    a, b = s.pairs(st.pairs // 4)
    ctx = mi.BSDFContext()
    si = interaction(a)
    f, p = call_eval_pdf(s.bsdf, ctx, si, vec(b))
    n = len(a)
    ef = np.concatenate([rec["ep_eval"].ravel(), rows(f, n, True).ravel()])
    ee = np.concatenate([rec["eval"].ravel(),
                         rows(call_eval(s.bsdf, ctx, si, vec(b)), n, True).ravel()])
    pf = np.concatenate([rec["ep_pdf"], rows(p, n)])
    pe = np.concatenate([rec["pdf_wo"], rows(call_pdf(s.bsdf, ctx, si, vec(b)), n)])
    tol = st.eval_pdf_rtol  # relative, and of the largest value
    rf = close(ef, ee, tol, tol * float(np.nanmax(np.abs(ee), initial=0)))
    rp = close(pf, pe, tol, tol * float(np.nanmax(np.abs(pe), initial=0)))
    numbers = {"directions": int(len(pe)), "eval_max_rel": rf["max_rel"], "eval_off": rf["off"],
               "pdf_max_rel": rp["max_rel"], "pdf_off": rp["off"], "rtol": st.eval_pdf_rtol}
    ok = rf["ok"] and rp["ok"]
    msg = (f"{len(pe):,} directions (sampled and random): largest relative difference "
           f"{rf['max_rel']:.2g} (eval), {rp['max_rel']:.2g} (pdf) (tolerance "
           f"{st.eval_pdf_rtol:g})")
    return Result("eval_pdf", "PASS" if ok else "FAIL", numbers, msg)


def pdf_result(s):
    """pdf() integrates to at most 1 over the sphere at every incidence."""
    rec = s.record()
    _, _, p, perr = incidence_quadratures(s)
    p, perr = np.array(p), np.array(perr)
    bound = 1 + 2 * perr + 2e-3  # twice the quadrature's error and 0.2% above 1
    over = p > bound
    i = int(np.argmax(p - bound))
    numbers = {"theta": rec["thetas"], "integral": p.tolist(), "error": perr.tolist()}
    smooth = kept(rec) & ~rec["delta"]  # what pdf() describes: delta samples have no density
    msg = (f"largest integral {p[i]:.4f} (theta_i = {deg(rec['thetas'][i])} deg, bound "
           f"{bound[i]:.4f}: 1 + 0.2% + twice the quadrature error); share of samples of "
           f"non-zero weight there {float(per_incidence(rec, smooth)[i].mean()):.4f}"
           + (" (of smooth lobes: delta samples have no density)" if rec["delta"].any() else ""))
    if _only_delta(rec):
        msg += ("; every sample is of a delta lobe, for which pdf() is 0 off the delta "
                "(Mitsuba's convention)" if not over.any() else
                "; every sample is of a delta lobe, yet pdf() is not 0 off the delta")
    return Result("pdf", "FAIL" if over.any() else "PASS", numbers, msg)


def furnace_result(s):
    """The mean sample weight at each incidence equals the quadrature of eval."""
    rec = s.record()
    a, err = mean_weights(rec, smooth_only=True)
    q, qerr, _, _ = incidence_quadratures(s)
    q, qerr = np.array(q), np.array(qerr)
    gap = np.abs(a - q)
    tol = furnace_tolerance(err, q, qerr)
    if _only_delta(rec) and (gap <= tol).all():
        return Result("furnace", "SKIP", {"theta": rec["thetas"], "quadrature": q.tolist()},
                      "every sample is of a delta lobe and eval is 0 off the delta: no "
                      "smooth lobe to integrate ('energy' bounds the delta lobes' weights)")
    i = np.unravel_index(int(np.argmax(gap / tol)), gap.shape)
    numbers = {"theta": rec["thetas"], "mean_weight": a.tolist(), "stderr": err.tolist(),
               "quadrature": q.tolist(), "quadrature_error": qerr.tolist(),
               "largest_gap": float(gap.max()), "samples": s.settings.samples}
    ok = bool((gap <= tol).all())
    msg = (f"mean weight against the quadrature of eval at {len(q)} incidences; worst at "
           f"theta_i = {deg(rec['thetas'][i[0]])} deg: {a[i]:.4f} against {q[i]:.4f} "
           f"(gap {gap[i]:.2g}, allowed {tol[i]:.2g}: 5 standard errors + twice the "
           f"quadrature error + 0.001 + 0.2%)")
    return Result("furnace", "PASS" if ok else "FAIL", numbers, msg,
                  {"theta": rec["thetas"], "albedo": a, "stderr": err, "quadrature": q})


def energy_result(s):
    """The albedo, what the BSDF reflects of the light it receives, is at most 1 at every
    incidence by both of its estimates: the mean sample weight (delta lobes included) and
    the quadrature of eval() (what eval() reflects, whatever the sampler draws)."""
    st = s.settings
    if s.transmissive:  # radiance is scaled by eta^2 across an interface: bound the adjoint
        ctx = s.context(mode=mi.TransportMode.Importance)
        rec = s.record("importance", ctx)
        if "quad_importance" not in s.cache:
            s.cache["quad_importance"] = quadratures(s, rec["thetas"], ctx)
        q, qerr, _, _ = s.cache["quad_importance"]
    else:
        rec = s.record()
        q, qerr, _, _ = incidence_quadratures(s)
    a, err = mean_weights(rec)
    q, qerr = np.array(q), np.array(qerr)
    qbound = 1 + 2 * qerr + 2e-3  # twice the quadrature's error and 0.2% above 1
    over, qover = a > albedo_bound(err), q > qbound
    i = np.unravel_index(int(np.argmax(a)), a.shape)
    j = np.unravel_index(int(np.argmax(q)), q.shape)
    numbers = {"theta": rec["thetas"], "albedo": a.tolist(), "stderr": err.tolist(),
               "largest": float(a[i]), "at_theta": rec["thetas"][i[0]],
               "quadrature": q.tolist(), "quadrature_error": qerr.tolist(),
               "largest_quadrature": float(q[j]), "quadrature_at_theta": rec["thetas"][j[0]]}
    msg = (f"largest albedo {a[i]:.4f} +- {err[i]:.1g} by the mean sample weight (theta_i = "
           f"{deg(rec['thetas'][i[0]])} deg), {q[j]:.4f} by the quadrature of eval "
           f"(theta_i = {deg(rec['thetas'][j[0]])} deg); bounds: 1 + 4 standard errors + "
           f"1e-3, 1 + 0.2% + twice the quadrature error")
    if s.transmissive:
        msg += "; measured in importance transport (no eta^2 scaling)"
    if over.any() or qover.any():
        for name, bad in (("mean weight", over), ("eval", qover)):
            if bad.any():
                gains = sorted({deg(rec["thetas"][k]) for k in np.argwhere(bad)[:, 0]},
                               key=float)
                msg += f"; above 1 by the {name} at theta_i = {', '.join(gains)} deg"
        if qover.any() and not over.any():
            msg += " (eval reflects more than the samples carry: see 'furnace')"
        if s.transmissive and over.any() and _ignores_mode(s, a):
            msg += ("; its weights are those of radiance transport: it scales by eta^2 in "
                    "importance transport too (ctx.mode; Mitsuba's dielectric scales only "
                    "when ctx.mode is Radiance)")
        if st.allow_gain:
            return Result("energy", "NOTE", numbers, msg + " (allowed: --allow-gain)")
        return Result("energy", "FAIL", numbers, msg)
    return Result("energy", "PASS", numbers, msg)


def _ignores_mode(s, importance):
    """Whether the mean weights in radiance transport are those measured in importance
    transport (``importance``): a transmissive BSDF that ignores ``ctx.mode``."""
    radiance, _ = mean_weights(s.record())
    return bool(np.allclose(radiance, importance, rtol=1e-3, atol=1e-4))
