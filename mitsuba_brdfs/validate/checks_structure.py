"""The suite's checks of structure and robustness: ``reciprocity``, ``hard_cases`` (finite
values >= 0 where formulas break), ``flags`` (the declared flags agree with what the BSDF
does), ``components`` (``ctx.component`` selects one lobe) and the ``sides`` note. Each takes
a ``Subject`` and returns a ``Result`` (``sides``: or None); ``validate.suite`` runs them.
"""
import mitsuba as mi
import numpy as np

from .directions import hard_directions, hard_pairs, random_pairs, sph
from .probe import close, eval_np, pdf_np, sample_bsdf, short, to_np
from .reciprocity import (delta_transmission_reciprocity, interface_eta, reciprocity_error,
                          transmission_reciprocity)
from .results import Result, deg, flag_names, verdict, warning
from .sampling import weight_errors
from .stability import hard_cases
from .subject import furnace_tolerance, kept, mean_weights, quadratures, weights_ok

__all__ = ["reciprocity_result", "hard_cases_result", "flags_result", "components_result",
           "sides_result"]


def reciprocity_result(s):
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


def hard_cases_result(s):
    """Finite values >= 0 at the hard directions, pairs and sample corners. A NaN or
    negative pdf where eval is 0, and a non-finite pdf or direction in a sample of weight
    0, are warnings: Mitsuba's integrators mask them (see ``validate.suite``)."""
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


def flags_result(s):
    """The flags agree with the samples and with where the BSDF scatters."""
    F = mi.BSDFFlags
    problems = []
    union = 0
    for c in s.components:
        union |= c
    if s.count < 1:
        problems.append("no components")
    if union != s.flags:
        problems.append(f"flags() {flag_names(s.flags)} is not the union of the components' "
                        f"{flag_names(union)}")
    # the samples: sampled_type within the sampled component's flags, on the right side
    rec = s.record()
    taken = kept(rec)
    comp, typ = rec["sampled_component"][taken], rec["sampled_type"][taken]
    side = rec["wi"][taken, 2] * rec["wo"][taken, 2]
    in_range = (comp >= 0) & (comp < s.count)
    warnings = []
    if not in_range.all():  # no integrator reads sampled_component
        k = int(np.argmax(~in_range))
        warnings.append(warning(f"samples name a component outside 0..{s.count - 1}",
                                (~in_range).sum(), f"component {int(comp[k])} of type "
                                f"{flag_names(int(typ[k]))}"))
    # a sample naming no valid component is held to the BSDF's flags
    own = np.array(s.components + [s.flags])[np.where(in_range, comp, s.count)]
    lobe = typ & int(F.All)
    wrong_type = (lobe == 0) | ((typ & ~own) != 0)
    if wrong_type.any():
        k = int(np.argmax(wrong_type))
        problems.append(f"{int(wrong_type.sum())} samples have a sampled_type outside their "
                        f"component's flags (e.g. {flag_names(int(typ[k]))} from component "
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
    numbers = {"flags": flag_names(s.flags), "components": [flag_names(c) for c in s.components],
               "samples": int(taken.sum()), "excluded_pairs": int(excluded.sum()),
               "problems": problems}
    msg = f"{s.count} component(s) {s.describe()}"
    if not problems:
        msg += (f"; {int(taken.sum()):,} sampled types within their flags and on their side; "
                f"nothing scatters in the {int(excluded.sum()):,} pairs the flags exclude")
    return verdict("flags", numbers, msg, problems, warnings)


def components_result(s):
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
        taken = kept(rec)
        other = taken & (rec["sampled_component"] != i)
        if other.any():
            problems.append(warning(
                f"samples of ctx.component = {i} from other components", other.sum(),
                f"component(s) {sorted(set(rec['sampled_component'][other].tolist()))}"))
        row = {"component": i, "flags": flag_names(s.components[i]),
               "samples": int(taken.sum())}
        if i in smooth and s.count == 1:  # the whole BSDF: 'weight' and 'furnace' judge it
            lobes.append(eval_np(s.bsdf, a, b, ctx).reshape(len(a), -1))
            parts += lobes[-1]
        elif i in smooth:
            lobes.append(eval_np(s.bsdf, a, b, ctx).reshape(len(a), -1))
            parts += lobes[-1]
            atol = 1e-6 * float(np.abs(rec["weight"]).max(initial=0.0))
            e = weight_errors(rec, st.weight_rtol, st.weight_rtol, atol, zero_weight_fails=True)
            if not weights_ok(rec, e, st.weight_rtol, atol)[0]:
                problems.append(warning(
                    f"samples of component {i} whose weight is not its eval / pdf",
                    e["weight"]["off"] + e["pdf"]["off"] + e["failed"]["off"],
                    f"largest relative error {e['weight']['max_rel']:.2g}; of the sample pdf "
                    f"against pdf(): {e['pdf']['max_rel']:.2g}"))
            alb, err = mean_weights(rec, smooth_only=True)
            q, qerr, _, _ = quadratures(s, rec["thetas"], ctx)
            q, qerr = np.array(q), np.array(qerr)
            gap, tol = np.abs(alb - q), furnace_tolerance(err, q, qerr)
            if (gap > tol).any():
                k = np.unravel_index(int(np.argmax(gap / tol)), gap.shape)
                problems.append(warning(
                    f"incidences where component {i}'s mean weight is not its quadrature",
                    (gap > tol).any(axis=1).sum(), f"{alb[k]:.4f} against {q[k]:.4f} at "
                    f"theta_i = {deg(rec['thetas'][k[0]])} deg"))
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
    thetas = ", ".join(map(deg, s.thetas(st.component_thetas)))
    msg = f"{s.count} component(s) at theta_i = {thetas} deg: "
    if problems:  # no integrator of Mitsuba selects a component: see ``validate.suite``
        return verdict("components", numbers, msg.rstrip(": "), warnings=problems)
    if s.count == 1:
        msg += (f"it samples itself alone and evaluates to eval (largest relative error "
                f"{r['max_rel']:.2g}); its weights are the BSDF's ("
                + ("'energy')" if s.delta else "'weight', 'furnace')"))
    else:
        msg += ("each samples itself alone, with weight = its eval / pdf and mean weight = its "
                f"quadrature; the lobes add up to eval (largest relative error "
                f"{r['max_rel']:.2g})")
    if s.delta:
        msg += f"; delta lobes {s.delta}: only their sampling is checked"
    return Result("components", "PASS", numbers, msg)


def sides_result(s):
    """What the sides of the BSDF let the suite check."""
    if s.two_sided:
        return None
    return Result("sides", "SKIP", {"two_sided": False},
                  "one-sided (no BackSide flag): incidences from below are not sampled; "
                  "'flags' checks that nothing scatters there")
