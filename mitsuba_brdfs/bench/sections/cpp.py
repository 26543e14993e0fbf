"""Section "speed against Mitsuba's C++ plugins" of the study's document: each Python plugin
against its closest C++ neighbour (measured by ``bench.speed.run_cpp``)."""
import statistics

from .format import ratio, ratio_bars, ratio_items, sec, table

__all__ = ["TARGET_RATIO", "EXPLANATIONS", "steps", "text", "summary", "plot", "recompiled"]

#: a Python plugin should render within this factor of its C++ neighbour
TARGET_RATIO = 1.1

#: why a pair differs, where the difference is understood; printed under the table for the
#: pairs that are slower than TARGET_RATIO in the run
EXPLANATIONS = {
    "oren_nayar": "Mitsuba has no Oren-Nayar plugin: `oren_nayar` evaluates the A and B terms "
                  "and the max(0, cos(phi_i - phi_o)) sin(alpha) tan(beta) factor (or a table "
                  "lookup) on top of what `diffuse` does, so a ratio above 1 is the model's "
                  "price, not overhead.",
    "toon": "Mitsuba has no toon shader: `toon` evaluates its bands, smooth steps and a "
            "specular band on top of a cosine-sampled diffuse lobe, more than `diffuse` does.",
}


def steps(settings):
    """Progress steps of the measurement."""
    from ..speed import CPP_PAIRS
    return len(CPP_PAIRS)


def recompiled(cpp):
    """Timed renders repeated because a kernel was compiled during them."""
    return sum(v.get("recompiled", 0) for v in cpp.get("pairs", {}).values())


def _calls(cpp):
    """(Python, C++) seconds of a nearly empty render call, per pair that measured it."""
    return [(v["call_a"], v["call_b"]) for v in cpp.get("pairs", {}).values() if "call_a" in v]


def summary(cpp, doc):
    """Summary bullets: the pairs within the target, the fixed cost of a render call."""
    pairs, out = cpp.get("pairs", {}), []
    n = doc.number("cpp")
    if pairs:
        slow = {k: v for k, v in pairs.items() if v["ratio"] > TARGET_RATIO}
        out.append(f"- Against Mitsuba's C++ plugins: {len(pairs) - len(slow)} of {len(pairs)} "
                   f"Python configurations render within {TARGET_RATIO}x of their neighbour"
                   + (": all of them." if not slow else "; slower: "
                      + ", ".join(f"`{k}` {v['ratio']:.2f}x" for k, v in slow.items())
                      + f" (see section {n})."))
    calls = _calls(cpp)
    if calls:
        out.append(f"- Fixed cost of a render call (16 x 16 pixels, 1 spp; section {n}): median "
                   f"{sec(statistics.median(a for a, _ in calls))} with the Python plugins, "
                   f"{sec(statistics.median(b for _, b in calls))} with their C++ neighbours "
                   f"(median difference {sec(statistics.median(a - b for a, b in calls))}).")
    return out


def _compact(d):
    """A plugin's parameters in one short line."""
    if isinstance(d, dict):
        if d.get("type") == "rgb":
            return str(d["value"])
        if d.get("type") == "bitmap":
            return "bitmap"
        return "{" + ", ".join(f"{k}: {_compact(v)}" for k, v in d.items()) + "}"
    return repr(d) if isinstance(d, str) else f"{d:g}" if isinstance(d, float) else str(d)


def _slower(cpp):
    """Why each pair slower than the target is slower, as far as the run tells."""
    slow = [k for k, v in cpp["pairs"].items() if v["ratio"] > TARGET_RATIO]
    if not slow:
        return []
    out = ["Where a Python plugin is slower:", ""]
    for k in slow:
        v = cpp["pairs"][k]
        ba, bb = v["bsdf_instr_a"], v["bsdf_instr_b"]
        more = [m for m in ("sample", "eval_pdf") if ba[m] > bb[m]]
        traced = (f"its {' and '.join(more)} trace"
                  + "".join(f" {ba[m]} instructions against {bb[m]}" + (";" if m != more[-1] else "")
                            for m in more)
                  if more else "its methods trace no more instructions than the C++ ones, "
                  "so the difference is not in the work per sample")
        why = EXPLANATIONS.get(k) or EXPLANATIONS.get(v["plugin"]) or ""
        out.append(f"- `{k}` ({v['ratio']:.2f}x): {traced}. {why}".rstrip())
    return out + [""]


def text(cpp, doc):
    """The section's text under its heading."""
    st = cpp["settings"]
    out = [f"The sphere at {st['res']} x {st['res']}, {st['spp']} spp, `{st['integrator']}` "
           f"integrator; {st['runs']} paired runs after a warm-up. Ratio = Python / C++ "
           f"(median of the per-pair ratios, range); target <= {TARGET_RATIO}.", ""]
    if cpp["pairs"]:
        out += doc.image("speed_vs_cpp.png", "Python / C++ time ratios")
    rows = []
    for k, v in cpp["pairs"].items():
        verdict = "ok" if v["ratio"] <= TARGET_RATIO else "**slower**"
        ba, bb = v["bsdf_instr_a"], v["bsdf_instr_b"]
        rows.append([f"`{k}`", f"`{v['cpp_plugin']}`", sec(v["median_a"]), sec(v["median_b"]),
                     ratio(v), verdict, f"{v['instr_a']} / {v['instr_b']}",
                     f"{ba['sample']} / {bb['sample']}", f"{ba['eval_pdf']} / {bb['eval_pdf']}",
                     f"{sec(v['compile_a'])} / {sec(v['compile_b'])}", v["note"]])
    out += table(["Python configuration", "C++", "Python", "C++ time", "ratio (range)", "",
                  "instr. render Python / C++", "instr. sample", "instr. eval_pdf",
                  "compile Python / C++", "closest neighbour because"], rows) + [""]
    calls = _calls(cpp)
    if calls:
        extra = statistics.median([a - b for a, b in calls])
        out += [f"Fixed cost of a render call (16 x 16 pixels, 1 spp, where the kernel has almost "
                f"nothing to do; medians over the pairs): Python plugins "
                f"{sec(statistics.median(a for a, _ in calls))}, C++ plugins "
                f"{sec(statistics.median(b for _, b in calls))}, a median difference of "
                f"{sec(extra)} per call. A Python BSDF is traced by running its Python methods "
                "at every `mi.render` call (the kernel itself comes from the cache); that cost "
                "does not grow with the image, so it weighs on many small renders (an "
                "optimisation loop) and not on one large one.", ""]
    out += ["*instr. sample* and *instr. eval_pdf*: the BSDF's own methods traced alone, outside "
            "a scene (the render kernel also holds the camera, the shapes, the emitters and the "
            "integrator, the same for both).", ""]
    out += ["Parameters of each pair:", ""]
    for k, v in cpp["pairs"].items():
        out.append(f"- `{k}`: `{_compact(v['python'])}` against `{_compact(v['cpp'])}`")
    return out + [""] + _slower(cpp)


def plot(cpp, path):
    """Python / C++ time ratio of each pair."""
    return ratio_bars(ratio_items(cpp["pairs"]), path,
                      "render time, Python plugin / C++ neighbour",
                      "time ratio (median, range)", (1.0, TARGET_RATIO))
