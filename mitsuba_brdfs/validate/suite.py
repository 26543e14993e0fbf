"""The validation suite: the checks of this package, run on any BSDF.

``run(bsdf, settings)`` runs every check of ``CHECKS`` on a loaded BSDF (a plugin of this
package, one of Mitsuba's, or one the user wrote, in Python or C++) and returns one
``Result`` per check: its name, its status, the numbers it measured and a line saying
what they mean. ``python -m mitsuba_brdfs check`` prints them; the package's tests run the
same suite on every model.

Statuses: ``PASS``; ``FAIL``, a defect that changes an image or breaks an integrator;
``WARN``, a departure from the plugin contract that Mitsuba's integrators mask (each
warning with its count and an example); ``NOTE``, a property the BSDF lacks that was not
asked for (reciprocity without ``reciprocal``, an albedo above 1 with ``allow_gain``);
``SKIP``, what could not be checked and why. A BSDF passes when no check fails
(``summary(results, strict=True)``: and none warns).

What the integrators mask, read in Mitsuba 3.9.1's ``src/integrators/path.cpp`` (``direct``,
``volpath`` and the Python ``prb*`` integrators, ``ad/integrators/common.py``, do the
same):

- a sample of weight 0 ends the path: ``throughput *= bsdf_weight``, then ``active``
  requires ``throughput_max != 0``, so its ``wo`` (the next ray) and its ``pdf`` (the next
  vertex's MIS weight, ``prev_bsdf_pdf``) are never read (``direct.cpp`` traces a BSDF
  sample only where ``any(bsdf_val != 0)``). A NaN or negative ``wo`` or ``pdf`` there is a
  WARN; with a non-zero weight it is a FAIL;
- ``pdf()`` (through ``eval_pdf``) enters only ``mis_weight(ds.pdf, bsdf_pdf)``, which squares
  both pdfs and returns 0 for a non-finite weight (``dr::select(dr::isfinite(w), w, 0)``),
  and that weight multiplies ``bsdf_val``. Where eval is 0 in every channel a NaN, negative
  or non-zero pdf (across the surface of a reflection-only BSDF, below a one-sided one, a
  side where ``sample()`` draws nothing) contributes nothing: a WARN. Where eval is not 0 a
  wrong pdf biases the MIS weights: a FAIL (``chi2``, ``weight``, ``hard_cases``);
- no integrator sets ``ctx.component`` or ``ctx.type_mask`` or reads
  ``bs.sampled_component``: what ``components`` finds, and a component index outside
  ``0 .. component_count() - 1``, are WARNs. The flags are read: ``flags()`` decides
  emitter sampling (``Smooth``) and ``sampled_type`` the MIS of the next hit (``Delta``),
  so wrong flags where something scatters, and eval not 0 where the flags say nothing
  scatters, are FAILs.

Everything else is a FAIL: a chi-square rejection, a weight that is not eval / pdf, a NaN,
infinite or negative eval or weight, an albedo above 1, a sampled direction of non-zero
weight that is not a finite unit vector.

The checks (each on the incidences of ``Settings``, theta_i in degrees, phi = 0.3):

- ``chi2``: Mitsuba's chi-square test of the sampled directions against pdf();
- ``weight``: each sample's weight is eval / pdf at its direction, its pdf is pdf(), and a
  sample that failed (pdf 0) weighs 0;
- ``eval_pdf``: eval_pdf() gives eval() and pdf();
- ``pdf``: pdf() integrates to at most 1 over the sphere;
- ``furnace``: the mean sample weight (the Monte Carlo albedo) equals a quadrature of eval()
  over the sphere: nothing eval() reflects is missed by the sampler, nothing is counted twice;
- ``energy``: the albedo is at most 1;
- ``reciprocity``: f(a, b) = f(b, a); across the surface of a transmissive BSDF
  f(a, b) / eta_a^2 = f(b, a) / eta_b^2 (radiance transport), and the same for the energy
  of a delta transmission (``validate.reciprocity`` derives it);
- ``hard_cases``: finite values >= 0 at the normal, at grazing and horizon directions, with
  h = n, nearly opposite grazing pairs, below the horizon, and at corner sample values;
- ``flags``: the declared flags agree with the sampled types and components, and with what
  the BSDF does (nothing on a side or in a direction that the flags exclude);
- ``components``: ``ctx.component`` selects one lobe: samples come from it, its weight is its
  eval / pdf and its mean weight its quadrature, and the lobes add up to the whole.

Two-sided BSDFs (a ``BackSide`` flag) are checked from both sides (incidences theta_i
above 90 degrees come from below); for one-sided ones a ``SKIP`` line, ``sides``, says so.
A BSDF without a transmission flag is checked on wi's side of the surface (and ``flags``
checks that nothing goes across); the energy of a transmissive one is measured in
importance transport (radiance is scaled by eta^2 across an interface). Delta lobes
(smooth mirrors and glass) and the null lobe of ``mask`` have no density: their samples
are left out of the checks that compare with eval and pdf, and ``chi2`` tests the other
lobes (its line says so), under the default context as integrators call the BSDF.

Mitsuba's conventions are followed: a sample of weight 0 is discarded whatever its pdf
(as ``mitsuba.chi2.BSDFAdapter`` does), and eval includes the cosine.
"""
import math
import time
from dataclasses import dataclass, field

import mitsuba as mi
import numpy as np

from .directions import hard_directions, hard_pairs, random_pairs, sph
from .energy import albedo_bound, quadrature
from .probe import close, eval_np, interaction, pdf_np, rows, sample_bsdf, short, to_np, vec
from .reciprocity import (delta_transmission_reciprocity, interface_eta, reciprocity_error,
                          transmission_reciprocity)
from .sampling import DIRAC, chi2, sample_record, weight_errors
from .stability import hard_cases

__all__ = ["Settings", "SETTINGS", "Result", "warning", "verdict", "summary", "Subject", "CHECKS",
           "run", "assert_valid"]


@dataclass(frozen=True)
class Settings:
    """How hard the suite looks; ``SETTINGS`` holds the three presets."""
    chi2_thetas: tuple = (0, 30, 60, 75, 85, 89)  #: incidences of the chi-square tests (deg)
    chi2_res: int = 161                   #: histogram rows, in cos(theta) (phi: half as many)
    chi2_ires: int = 64                   #: pdf integration points per cell and dimension
    chi2_samples: int = 1_000_000         #: samples per chi-square test
    thetas: tuple = (0, 20, 40, 60, 70, 80, 85, 89)  #: incidences of the other checks
    samples: int = 100_000                #: samples per incidence (weights, furnace)
    quad: int = 128                       #: quadrature: polar cells per hemisphere
    pairs: int = 20_000                   #: random direction pairs (reciprocity, components)
    component_thetas: tuple = (30, 75)    #: incidences of the component checks
    significance: float = 0.01            #: of all chi-square tests together
    weight_rtol: float = 1e-3             #: weight against eval / pdf, sample pdf against pdf
    eval_pdf_rtol: float = 1e-5           #: eval_pdf against (eval, pdf)
    reciprocity_rtol: float = 1e-3
    allow_gain: bool = False              #: an albedo above 1 is a NOTE, not a FAIL
    reciprocal: bool = False              #: a non-reciprocal BSDF FAILs (else: NOTE)


SETTINGS = {
    "quick": Settings(chi2_thetas=(30, 85), chi2_res=64, chi2_ires=16, chi2_samples=200_000,
                      thetas=(0, 45, 80, 89), samples=30_000, quad=64, pairs=4000,
                      component_thetas=(45,)),
    "default": Settings(),
    "thorough": Settings(chi2_thetas=(0, 20, 40, 60, 75, 85, 89), chi2_res=201, chi2_ires=64,
                         chi2_samples=4_000_000,
                         thetas=tuple(range(0, 90, 5)) + (87, 89, 89.9), samples=100_000,
                         quad=256, pairs=200_000, component_thetas=(0, 30, 60, 85)),
}


@dataclass
class Result:
    """What one check found: ``status`` is PASS, WARN, FAIL, NOTE or SKIP; ``numbers`` what
    it measured (plain numbers, lists and strings, as JSON holds them); ``message`` one line
    saying what they mean; ``warnings`` what Mitsuba's integrators mask (one record per
    kind: ``what``, ``count``, ``example``); ``data`` arrays for plots."""
    name: str
    status: str
    numbers: dict = field(default_factory=dict)
    message: str = ""
    data: dict = field(default_factory=dict, repr=False)
    warnings: list = field(default_factory=list)

    @property
    def passed(self):
        return self.status != "FAIL"

    def as_dict(self):
        return {"name": self.name, "status": self.status, "passed": self.passed,
                "numbers": self.numbers, "message": self.message, "warnings": self.warnings}


def warning(what, count, example):
    """A WARN record: what was found, how often, one example (where and its values)."""
    return {"what": what, "count": int(count), "example": example}


def verdict(name, numbers, message, problems=(), warnings=(), data=None):
    """FAIL when there are problems (strings), WARN when there are only warnings
    (``warning`` records), PASS otherwise; the message lists both."""
    problems, warnings = list(problems), list(warnings)
    if problems:
        message += "; " + "; ".join(problems)
    if warnings:
        message += "; masked by Mitsuba's integrators: " + "; ".join(
            f"{w['count']:,} x {w['what']} (e.g. {w['example']})" for w in warnings)
    status = "FAIL" if problems else "WARN" if warnings else "PASS"
    return Result(name, status, numbers, message, data or {}, warnings)


def summary(results, strict=False):
    """(passed, line): the verdict of one BSDF's results, e.g. ``PASS (11 checks, 1
    warning)`` or ``FAIL (2 of 11 checks failed: chi2, flags)``; with strict, a warning
    fails."""
    failed = [r.name for r in results if r.status == "FAIL"]
    warned = [r.name for r in results if r.status == "WARN"]
    n_warn = sum(len(r.warnings) for r in results)
    warn = f"{n_warn} warning{'s' * (n_warn != 1)}" if n_warn else ""
    if strict and warned:
        failed += [f"{w} (warning, --strict)" for w in warned]
    if failed:
        line = f"FAIL ({len(failed)} of {len(results)} checks failed: {', '.join(failed)}"
        return False, line + (f"; {warn})" if warn and not strict else ")")
    return True, f"PASS ({len(results)} checks" + (f", {warn})" if warn else ")")


def _flag_names(flags):
    names = [f.name for f in mi.BSDFFlags if f.value and (f.value & (f.value - 1)) == 0
             and flags & f.value]
    return "|".join(names) or "Empty"


class Subject:
    """A BSDF under test, with what its flags say about it and the samples several checks
    share (drawn once)."""

    def __init__(self, bsdf, name, settings):
        F = mi.BSDFFlags
        self.bsdf, self.name, self.settings = bsdf, name, settings
        self.count = bsdf.component_count()
        self.components = [int(bsdf.flags(i)) for i in range(self.count)]
        self.flags = int(bsdf.flags())
        self.two_sided = bool(self.flags & int(F.BackSide))
        self.transmissive = bool(self.flags & int(F.Transmission))
        delta = DIRAC
        self.delta = [i for i, c in enumerate(self.components) if c & delta]
        self.cache = {}  #: what several checks share, computed once

    def describe(self):
        return ", ".join(f"[{i}] {_flag_names(c)}" for i, c in enumerate(self.components))

    def thetas(self, thetas):
        """Incidences (degrees): thetas, and 180 - theta (from below) for a two-sided BSDF."""
        out = [float(t) for t in thetas]
        return out + [180.0 - t for t in out] if self.two_sided else out

    def context(self, **attrs):
        ctx = mi.BSDFContext()
        for k, v in attrs.items():
            setattr(ctx, k, v)
        return ctx

    def record(self, key="all", ctx=None, thetas=None):
        """``sampling.sample_record`` at every incidence (``settings.thetas`` by default),
        drawn once per key."""
        if key not in self.cache:
            th = self.thetas(self.settings.thetas if thetas is None else thetas)
            wis = np.concatenate([sph(np.radians(t), 0.3) for t in th])
            rec = sample_record(self.bsdf, wis, self.settings.samples, ctx=ctx)
            rec["thetas"] = th
            self.cache[key] = rec
        return self.cache[key]

    def pairs(self, n, seed=5):
        """n random pairs above the surface, and as many below for a two-sided BSDF."""
        a, b = random_pairs(seed, n)
        if self.two_sided:
            a, b = np.concatenate([a, -a]), np.concatenate([b, -b])
        return a, b


def _kept(rec):
    """The samples a renderer keeps: a pdf > 0 or a delta lobe, and a non-zero weight."""
    return (rec["ok"] | rec["delta"]) & (np.abs(rec["weight"]).max(axis=1) > 0)


def _per_incidence(rec, values):
    """values (one per sample of rec) split by incidence: shape (K, n, ...)."""
    k = len(rec["thetas"])
    return values.reshape((k, -1) + values.shape[1:])


def _fmt(x, digits=4):
    return f"{x:.{digits}g}"


def _deg(t):
    return f"{t:g}"


# -- the checks ----------------------------------------------------------------------------

def check_chi2(s):
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
    ps = ", ".join(f"{_fmt(r['p_value'], 2)} ({_deg(r['theta'])})" for r in table)
    msg = (f"p-values {ps} at theta_i (deg); res {st.chi2_res}, ires {st.chi2_ires}, "
           f"{st.chi2_samples:,} samples each, significance {st.significance} over all")
    if idle:
        msg += f"; nothing scatters at theta_i = {', '.join(map(_deg, idle))}"
    if black:
        msg += (f"; black at theta_i = {', '.join(map(_deg, black))} (every weight 0): samples "
                f"of pdf > 0 tested")
    if s.delta:
        msg += f"; delta lobes {s.delta} left out"
    if inconclusive:
        msg += "; inconclusive at " + "; ".join(f"{_deg(t)} deg: {m}" for t, m in inconclusive)
    problems = [f"{_deg(t)} deg: {m}" for t, m in failed]
    warnings = [warning("incidences where sample() and eval() give nothing but pdf() is "
                        "not 0", len(masked), f"theta_i = {_deg(masked[0][0])} deg: "
                        f"{masked[0][1]}")] if masked else []
    return verdict("chi2", numbers, msg, problems, warnings, data)


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


def check_weight(s):
    """weight = eval / pdf and sample pdf = pdf() on the sampled directions."""
    st = s.settings
    rec = s.record()
    atol = 1e-6 * float(np.abs(rec["weight"]).max(initial=0.0))
    e = weight_errors(rec, st.weight_rtol, st.weight_rtol, atol, zero_weight_fails=True)
    valid = [float(v.mean()) for v in _per_incidence(rec, _kept(rec))]
    numbers = {"samples": int(len(rec["ok"])), "weight_max_rel": e["weight"]["max_rel"],
               "weight_off": e["weight"]["off"], "pdf_max_rel": e["pdf"]["max_rel"],
               "pdf_off": e["pdf"]["off"], "failed_weight_max": e["failed"]["max_rel"],
               "rtol": st.weight_rtol, "theta": rec["thetas"], "valid": valid}
    ok, rounding = _weights_ok(rec, e, st.weight_rtol, atol)
    msg = (f"{numbers['samples']:,} samples: largest relative error of the weight against "
           f"eval/pdf {e['weight']['max_rel']:.2g}, of the sample pdf against pdf() "
           f"{e['pdf']['max_rel']:.2g} (tolerance {st.weight_rtol:g}); "
           + ("samples with pdf 0 weigh 0" if e["failed"]["ok"] else
              f"samples with pdf 0 weigh up to {e['failed']['max_rel']:.2g}"))
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


def _weights_ok(rec, e, rtol, atol):
    """Whether a ``weight_errors`` record e of rec passes, and how many samples it lets
    through: those off by less than 10 x rtol, when they are at most 1 in 100,000 (a
    float32 formula can lose a few digits where it is ill-conditioned, e.g. the half
    vector of a refraction near the critical angle)."""
    if e["weight"]["ok"] and e["pdf"]["ok"] and e["failed"]["ok"]:
        return True, 0
    loose = weight_errors(rec, 10 * rtol, 10 * rtol, atol, zero_weight_fails=True)
    off = e["weight"]["off"] + e["pdf"]["off"]
    if (loose["weight"]["ok"] and loose["pdf"]["ok"] and e["failed"]["ok"]
            and off <= max(1, 1e-5 * len(rec["ok"]))):
        return True, off
    return False, 0


def check_eval_pdf(s):
    """eval_pdf() = (eval(), pdf()) on the sampled directions and on random pairs."""
    st = s.settings
    rec = s.record()
    a, b = s.pairs(st.pairs // 4)
    ctx = mi.BSDFContext()
    si = interaction(a)
    f, p = s.bsdf.eval_pdf(ctx, si, vec(b))
    n = len(a)
    ef = np.concatenate([rec["ep_eval"].ravel(), rows(f, n, True).ravel()])
    ee = np.concatenate([rec["eval"].ravel(),
                         rows(s.bsdf.eval(ctx, si, vec(b)), n, True).ravel()])
    pf = np.concatenate([rec["ep_pdf"], rows(p, n)])
    pe = np.concatenate([rec["pdf_wo"], rows(s.bsdf.pdf(ctx, si, vec(b)), n)])
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


def _quadratures(s, thetas, ctx=None):
    out = [quadrature(s.bsdf, sph(np.radians(t), 0.3)[0], s.settings.quad, ctx,
                      same_side=not s.transmissive) for t in thetas]
    return ([o[0][0] for o in out], [o[0][1] for o in out],
            [o[1][0] for o in out], [o[1][1] for o in out])


def _quad(s):
    if "quad" not in s.cache:
        s.cache["quad"] = _quadratures(s, s.record()["thetas"])
    return s.cache["quad"]


def check_pdf(s):
    """pdf() integrates to at most 1 over the sphere at every incidence."""
    rec = s.record()
    _, _, p, perr = _quad(s)
    p, perr = np.array(p), np.array(perr)
    bound = 1 + 2 * perr + 2e-3  # twice the quadrature's error and 0.2% above 1
    over = p > bound
    i = int(np.argmax(p - bound))
    numbers = {"theta": rec["thetas"], "integral": p.tolist(), "error": perr.tolist()}
    msg = (f"largest integral {p[i]:.4f} (theta_i = {_deg(rec['thetas'][i])} deg, bound "
           f"{bound[i]:.4f}: 1 + 0.2% + twice the quadrature error); share of samples of "
           f"non-zero weight there {float(_per_incidence(rec, _kept(rec))[i].mean()):.4f}")
    return Result("pdf", "FAIL" if over.any() else "PASS", numbers, msg)


def _furnace_tolerance(err, q, qerr):
    """How far the mean weight (standard error err) may be from the quadrature q (error
    qerr): 5 standard errors, twice the quadrature's error, and 0.1% + 0.2% of q (a
    sampler biased by less is not worth a failure; the message still shows the gap)."""
    return 5 * err + 2 * qerr + 1e-3 + 2e-3 * np.abs(q)


def _albedo(rec, smooth_only=False):
    w = rec["weight"] * (~rec["delta"])[:, None] if smooth_only else rec["weight"]
    w = _per_incidence(rec, w)
    return w.mean(axis=1), w.std(axis=1) / math.sqrt(w.shape[1])


def check_furnace(s):
    """The mean sample weight at each incidence equals the quadrature of eval."""
    rec = s.record()
    a, err = _albedo(rec, smooth_only=True)
    q, qerr, _, _ = _quad(s)
    q, qerr = np.array(q), np.array(qerr)
    gap = np.abs(a - q)
    tol = _furnace_tolerance(err, q, qerr)
    i = np.unravel_index(int(np.argmax(gap / tol)), gap.shape)
    numbers = {"theta": rec["thetas"], "mean_weight": a.tolist(), "stderr": err.tolist(),
               "quadrature": q.tolist(), "quadrature_error": qerr.tolist(),
               "largest_gap": float(gap.max()), "samples": s.settings.samples}
    ok = bool((gap <= tol).all())
    msg = (f"mean weight against the quadrature of eval at {len(q)} incidences; worst at "
           f"theta_i = {_deg(rec['thetas'][i[0]])} deg: {a[i]:.4f} against {q[i]:.4f} "
           f"(gap {gap[i]:.2g}, allowed {tol[i]:.2g}: 5 standard errors + twice the "
           f"quadrature error + 0.001 + 0.2%)")
    return Result("furnace", "PASS" if ok else "FAIL", numbers, msg,
                  {"theta": rec["thetas"], "albedo": a, "stderr": err, "quadrature": q})


def check_energy(s):
    """The albedo (mean sample weight, delta lobes included) is at most 1."""
    st = s.settings
    if s.transmissive:  # radiance is scaled by eta^2 across an interface: bound the adjoint
        rec = s.record("importance", s.context(mode=mi.TransportMode.Importance))
    else:
        rec = s.record()
    a, err = _albedo(rec)
    over = a > albedo_bound(err)
    i = np.unravel_index(int(np.argmax(a)), a.shape)
    numbers = {"theta": rec["thetas"], "albedo": a.tolist(), "stderr": err.tolist(),
               "largest": float(a[i]), "at_theta": rec["thetas"][i[0]]}
    msg = (f"largest albedo {a[i]:.4f} +- {err[i]:.1g} at theta_i = {_deg(rec['thetas'][i[0]])} "
           f"deg (bound: 1 + 4 standard errors + 1e-3)")
    if s.transmissive:
        msg += "; measured in importance transport (no eta^2 scaling)"
    if over.any():
        gains = sorted({_deg(rec["thetas"][k]) for k in np.argwhere(over)[:, 0]}, key=float)
        msg += f"; above 1 at theta_i = {', '.join(gains)} deg"
        if st.allow_gain:
            return Result("energy", "NOTE", numbers, msg + " (allowed: --allow-gain)")
        return Result("energy", "FAIL", numbers, msg)
    return Result("energy", "PASS", numbers, msg)


def check_reciprocity(s):
    """f(a, b) = f(b, a) on random pairs on one side; for a transmissive BSDF also across
    the surface with the eta^2 factor of radiance transport, f(a, b) / eta_a^2 =
    f(b, a) / eta_b^2, and for its delta transmission the energy each way
    (``reciprocity``'s docstring derives both)."""
    st = s.settings
    a, b = s.pairs(st.pairs)
    r = reciprocity_error(s.bsdf, a, b, st.reciprocity_rtol)
    numbers = {"pairs": int(len(a)), "max_rel": r["max_rel"], "off": r["off"],
               "rtol": st.reciprocity_rtol}
    msg = (f"{len(a):,} pairs: largest |f(a, b) - f(b, a)| {r['max_rel']:.2g} of the largest "
           f"value (tolerance {st.reciprocity_rtol:g})")
    off = [f"{r['off']} pairs off"] if not r["ok"] else []
    if s.transmissive:
        eta = interface_eta(s.bsdf)
        if eta is None:
            msg += "; nothing transmitted from 40 deg above: pairs across not checked"
        else:
            a, b = random_pairs(11, st.pairs // 2)
            t = transmission_reciprocity(s.bsdf, a, b * [1, 1, -1], eta, st.reciprocity_rtol)
            wis = sph(np.radians(s.settings.thetas[:-1]), 0.3)  # not 89: total reflection
            d = delta_transmission_reciprocity(s.bsdf, wis, eta)
            numbers.update(eta=eta, across_max_rel=t["max_rel"], across_off=t["off"],
                           delta_pairs=d["pairs"], delta_max_rel=d["max_rel"])
            msg += (f"; across the surface (eta = {eta:.5g} below, from the transmitted "
                    f"samples' bs.eta), f(a, b) / eta_a^2 against f(b, a) / eta_b^2 on "
                    f"{len(a):,} pairs: largest difference {t['max_rel']:.2g}")
            if d["pairs"]:
                msg += (f"; delta transmission at {d['pairs']} incidences: E(a) eta^2 against "
                        f"E(t(a)) / eta^2, largest difference {d['max_rel']:.2g}")
            if not t["ok"]:
                off.append(f"{t['off']} pairs across off")
            if not d["ok"]:
                off.append(f"{d['off']} delta transmissions off ({d['values']})")
    if not off:
        return Result("reciprocity", "PASS", numbers, msg)
    if st.reciprocal:
        return Result("reciprocity", "FAIL", numbers, msg + "; " + ", ".join(off))
    return Result("reciprocity", "NOTE", numbers,
                  msg + f"; not reciprocal ({', '.join(off)}; --reciprocal makes this fail)")


def check_hard_cases(s):
    """Finite values >= 0 at the hard directions, pairs and sample corners. A NaN or
    negative pdf where eval is 0, and a non-finite pdf or direction in a sample of weight
    0, are warnings: Mitsuba's integrators mask them (see the module's docstring)."""
    h = hard_cases(s.bsdf)
    found = h["findings"]
    numbers = {"pairs": h["pairs"], "samples": h["samples"],
               "findings": [{k: f[k] for k in ("what", "count", "masked", "example")}
                            for f in found]}
    msg = (f"{h['pairs']:,} direction pairs (normal, grazing, horizon, h = n, nearly opposite, "
           f"below the horizon) and {h['samples']:,} corner samples: ")
    if not found:
        return Result("hard_cases", "PASS", numbers, msg + "every value finite and >= 0")
    if not any(not f["masked"] for f in found):
        msg += "every value an integrator uses finite and >= 0"
    else:
        msg = msg.rstrip(": ")

    def where(f):
        more = f" and {len(f['wi']) - 3} more" if len(f["wi"]) > 3 else ""
        return ", ".join(short(w) for w in f["wi"][:3]) + more

    problems = [f"{f['count']:,} x {f['what']}, with wi = {where(f)}; first: {f['example']}"
                for f in found if not f["masked"]]
    warnings = [warning(f["what"], f["count"], f["example"]) for f in found if f["masked"]]
    return verdict("hard_cases", numbers, msg, problems, warnings)


def check_flags(s):
    """The flags agree with the samples and with where the BSDF scatters."""
    F = mi.BSDFFlags
    problems = []
    union = 0
    for c in s.components:
        union |= c
    if s.count < 1:
        problems.append("no components")
    if union != s.flags:
        problems.append(f"flags() {_flag_names(s.flags)} is not the union of the components' "
                        f"{_flag_names(union)}")
    # the samples: sampled_type within the sampled component's flags, on the right side
    rec = s.record()
    taken = _kept(rec)
    comp, typ = rec["sampled_component"][taken], rec["sampled_type"][taken]
    side = rec["wi"][taken, 2] * rec["wo"][taken, 2]
    in_range = (comp >= 0) & (comp < s.count)
    warnings = []
    if not in_range.all():  # no integrator reads sampled_component
        k = int(np.argmax(~in_range))
        warnings.append(warning(f"samples name a component outside 0..{s.count - 1}",
                                (~in_range).sum(), f"component {int(comp[k])} of type "
                                f"{_flag_names(int(typ[k]))}"))
    # a sample naming no valid component is held to the BSDF's flags
    own = np.array(s.components + [s.flags])[np.where(in_range, comp, s.count)]
    lobe = typ & int(F.All)
    wrong_type = (lobe == 0) | ((typ & ~own) != 0)
    if wrong_type.any():
        k = int(np.argmax(wrong_type))
        problems.append(f"{int(wrong_type.sum())} samples have a sampled_type outside their "
                        f"component's flags (e.g. {_flag_names(int(typ[k]))} from component "
                        f"{int(comp[k])})")
    refl, trans = (lobe & int(F.Reflection)) != 0, (lobe & int(F.Transmission)) != 0
    wrong_side = (refl & ~trans & (side < 0)) | (trans & ~refl & (side > 0))
    if wrong_side.any():
        problems.append(f"{int(wrong_side.sum())} samples of non-zero weight go to the side "
                        f"their type excludes")
    # nothing where the flags exclude it: across the surface without a transmission flag,
    # from below without a back side
    wi, wo = hard_pairs(hard_directions())
    a, b = s.pairs(2000)
    below = b * [1, 1, -1]
    wi, wo = np.concatenate([wi, a, below]), np.concatenate([wo, below, a])
    rules = []  # (where, mask): the pairs where the flags say nothing scatters
    if not s.transmissive:
        rules.append(("with wo across the surface (no transmission flag)",
                      wi[:, 2] * wo[:, 2] < 0))
    if not s.two_sided:
        rules.append(("with wi below the surface (no BackSide flag)", wi[:, 2] < 0))
    excluded = np.zeros(len(wi), bool)
    for _, mask in rules:
        excluded |= mask
    f, p = eval_np(s.bsdf, wi, wo).reshape(len(wi), -1), pdf_np(s.bsdf, wi, wo)
    dark = ~(f != 0).any(axis=1)  # eval 0 in every channel (NaN is not 0)
    for what, values, where_dark in (("eval", f, False), ("pdf", p[:, None], True)):
        size = np.where(np.isnan(values), np.inf, np.abs(values)).max(axis=1)
        for where, mask in rules:
            leak = mask & (size != 0) & (dark if where_dark else True)
            if leak.any():
                k = int(np.argmax(np.where(leak, size, -1)))
                line = (f"{what} is not 0 {where} in {int(leak.sum())} of {int(mask.sum())} "
                        f"pairs")
                example = (f"{short(values[k])} at wi = {short(wi[k])}, wo = "
                           f"{short(wo[k])}")
                if where_dark:  # eval is 0 there: only a MIS weight sees this pdf
                    warnings.append(warning(f"{what} is not 0 {where} where eval is 0",
                                            leak.sum(), example))
                else:
                    problems.append(f"{line} (largest {example})")
    if not s.two_sided:  # sampled from below, a one-sided BSDF gives nothing
        _, (bs, w) = sample_bsdf(s.bsdf, [0.3, 0.2, -0.9327379], 1000)
        if (to_np(w) != 0).any():
            problems.append("samples with wi below the surface have non-zero weights")
    numbers = {"flags": _flag_names(s.flags), "components": [_flag_names(c) for c in s.components],
               "samples": int(taken.sum()), "excluded_pairs": int(excluded.sum()),
               "problems": problems}
    msg = f"{s.count} component(s) {s.describe()}"
    if not problems:
        msg += (f"; {int(taken.sum()):,} sampled types within their flags and on their side; "
                f"nothing scatters in the {int(excluded.sum()):,} pairs the flags exclude")
    return verdict("flags", numbers, msg, problems, warnings)


def check_components(s):
    """ctx.component selects one lobe: sampled from it alone, weighted by its eval / pdf,
    its mean weight its quadrature; the lobes add up to the BSDF."""
    st = s.settings
    problems, per = [], []
    a, b = s.pairs(st.pairs // 4)
    total = eval_np(s.bsdf, a, b).reshape(len(a), -1)
    parts, lobes = np.zeros_like(total), []
    smooth = [i for i in range(s.count) if i not in s.delta]
    for i in range(s.count):
        ctx = s.context(component=i)
        rec = s.record(f"component {i}", ctx, st.component_thetas)
        taken = _kept(rec)
        other = taken & (rec["sampled_component"] != i)
        if other.any():
            problems.append(warning(
                f"samples of ctx.component = {i} from other components", other.sum(),
                f"component(s) {sorted(set(rec['sampled_component'][other].tolist()))}"))
        row = {"component": i, "flags": _flag_names(s.components[i]),
               "samples": int(taken.sum())}
        if i in smooth and s.count == 1:  # the whole BSDF: 'weight' and 'furnace' judge it
            lobes.append(eval_np(s.bsdf, a, b, ctx).reshape(len(a), -1))
            parts += lobes[-1]
        elif i in smooth:
            lobes.append(eval_np(s.bsdf, a, b, ctx).reshape(len(a), -1))
            parts += lobes[-1]
            atol = 1e-6 * float(np.abs(rec["weight"]).max(initial=0.0))
            e = weight_errors(rec, st.weight_rtol, st.weight_rtol, atol, zero_weight_fails=True)
            if not _weights_ok(rec, e, st.weight_rtol, atol)[0]:
                problems.append(warning(
                    f"samples of component {i} whose weight is not its eval / pdf",
                    e["weight"]["off"] + e["pdf"]["off"] + e["failed"]["off"],
                    f"largest relative error {e['weight']['max_rel']:.2g}; of the sample pdf "
                    f"against pdf(): {e['pdf']['max_rel']:.2g}"))
            alb, err = _albedo(rec, smooth_only=True)
            q, qerr, _, _ = _quadratures(s, rec["thetas"], ctx)
            q, qerr = np.array(q), np.array(qerr)
            gap, tol = np.abs(alb - q), _furnace_tolerance(err, q, qerr)
            if (gap > tol).any():
                k = np.unravel_index(int(np.argmax(gap / tol)), gap.shape)
                problems.append(warning(
                    f"incidences where component {i}'s mean weight is not its quadrature",
                    (gap > tol).any(axis=1).sum(), f"{alb[k]:.4f} against {q[k]:.4f} at "
                    f"theta_i = {_deg(rec['thetas'][k[0]])} deg"))
            row.update(weight_max_rel=e["weight"]["max_rel"], mean_weight=alb.tolist(),
                       quadrature=q.tolist())
        per.append(row)
    scale = float(np.abs(total).max(initial=0.0))
    r = close(parts, total, 1e-4, 1e-6 * scale)
    if len(lobes) > 1 and scale > 0 and all(close(f, total, 1e-6)["ok"] for f in lobes):
        problems.append(warning("ctx.component ignored: each component evaluates to the whole "
                                "BSDF", len(lobes), f"{len(a):,} pairs"))
    elif not r["ok"]:
        problems.append(warning("pairs where the components' evals do not add up to eval",
                                r["off"], f"largest relative error {r['max_rel']:.2g}"))
    numbers = {"components": per, "sum_max_rel": r["max_rel"], "theta": list(map(float,
               s.thetas(st.component_thetas))), "warnings": len(problems)}
    thetas = ", ".join(map(_deg, s.thetas(st.component_thetas)))
    msg = f"{s.count} component(s) at theta_i = {thetas} deg: "
    if problems:  # no integrator of Mitsuba selects a component: see the docstring
        return verdict("components", numbers, msg.rstrip(": "), warnings=problems)
    if s.count == 1:
        msg += (f"it samples itself alone and evaluates to eval (largest relative error "
                f"{r['max_rel']:.2g}); its weights are the BSDF's ('weight', 'furnace')")
    else:
        msg += ("each samples itself alone, with weight = its eval / pdf and mean weight = its "
                f"quadrature; the lobes add up to eval (largest relative error "
                f"{r['max_rel']:.2g})")
    if s.delta:
        msg += f"; delta lobes {s.delta}: only their sampling is checked"
    return Result("components", "PASS", numbers, msg)


def note_sides(s):
    """What the sides of the BSDF let the suite check."""
    if s.two_sided:
        return None
    return Result("sides", "SKIP", {"two_sided": False},
                  "one-sided (no BackSide flag): incidences from below are not sampled; "
                  "'flags' checks that nothing scatters there")


#: (name, function(Subject) -> Result or None), in the order they run and print
CHECKS = [
    ("chi2", check_chi2),
    ("weight", check_weight),
    ("eval_pdf", check_eval_pdf),
    ("pdf", check_pdf),
    ("furnace", check_furnace),
    ("energy", check_energy),
    ("reciprocity", check_reciprocity),
    ("hard_cases", check_hard_cases),
    ("flags", check_flags),
    ("components", check_components),
    ("sides", note_sides),
]


def run(bsdf, settings=None, name="bsdf", only=None, on_result=None):
    """Every check of CHECKS (or the named ones in ``only``) on a loaded BSDF; a check that
    raises FAILs with the exception as its message. ``on_result(result)`` is called as each
    check ends. Returns the list of Results."""
    s = Subject(bsdf, name, settings or SETTINGS["default"])
    results = []
    for check_name, fn in CHECKS:
        if only is not None and check_name not in only:
            continue
        t0 = time.perf_counter()
        try:
            r = fn(s)
        except Exception as e:  # a BSDF that raises has failed the check
            if "KeyboardInterrupt" in str(e):  # Ctrl-C, wrapped by Dr.Jit: stop
                raise KeyboardInterrupt from e
            r = Result(check_name, "FAIL", {}, f"raised {type(e).__name__}: {_one_line(e)}")
        if r is None:
            continue
        r.numbers["seconds"] = round(time.perf_counter() - t0, 3)
        results.append(r)
        if on_result:
            on_result(r)
    return results


def _one_line(e):
    """An exception's message; for Mitsuba's errors that embed a Python traceback, its
    first line and the cause."""
    lines = [ln.strip() for ln in str(e).splitlines() if ln.strip()]
    if not lines:
        return ""
    return lines[0] if len(lines) == 1 else f"{lines[0]} ... {lines[-1]}"


def assert_valid(bsdf, settings="quick", strict=False, only=None, **options):
    """Run the suite on ``bsdf`` and raise ``AssertionError`` listing every failed check
    (with ``strict``, every warning too), for a test suite::

        from mitsuba_brdfs.validate import assert_valid

        def test_my_bsdf():
            assert_valid({"type": "my_bsdf", "roughness": 0.3})

    ``bsdf`` is a loaded BSDF, a plugin name or a ``mi.load_dict`` dictionary;
    ``settings`` a preset name (``"quick"``, about a second; ``"default"``; ``"thorough"``)
    or a ``Settings``; ``options`` replace fields of it (``allow_gain=True``,
    ``reciprocal=True``, ``samples=...``); ``only`` names the checks to run. Returns the
    results when nothing failed."""
    import dataclasses
    __tracebackhide__ = True  # pytest shows the caller's line and the message
    if isinstance(bsdf, str):
        bsdf = {"type": bsdf}
    name = bsdf.get("type", "bsdf") if isinstance(bsdf, dict) else (bsdf.id() or "bsdf")
    if isinstance(bsdf, dict):
        bsdf = mi.load_dict(bsdf)
    if isinstance(settings, str):
        if settings not in SETTINGS:
            raise ValueError(f"assert_valid: settings {settings!r} is not one of "
                             f"{', '.join(SETTINGS)} (or a Settings)")
        settings = SETTINGS[settings]
    settings = dataclasses.replace(settings, **options)
    results = run(bsdf, settings, name, only=only)
    ok, line = summary(results, strict)
    if ok:
        return results
    lines = [f"{name}: {line}"]
    for r in results:
        if r.status == "FAIL" or (strict and r.status == "WARN"):
            lines.append(f"  {r.status} {r.name}: {r.message}")
    raise AssertionError("\n".join(lines))
