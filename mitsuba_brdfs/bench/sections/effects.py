"""Section "only the effects a scene calls for" of the study's document: what each optional
effect costs (dropped lobes, anisotropy, textures), and its subsection ``direct`` against
``path`` on the figure scenes (measured by ``bench.speed``)."""
import os
import re

from .format import num, ratio, ratio_bars, ratio_items, sec, table

__all__ = ["steps", "text", "summary", "plot", "recompiled", "lobe_verdict",
           "figures_steps", "figures_text", "figures_recompiled"]


def steps(settings):
    """Progress steps of the measurement."""
    from ..speed import effect_pairs
    return len(effect_pairs(settings.effect_models))


def recompiled(eff):
    """Timed renders repeated because a kernel was compiled during them."""
    return sum(v.get("recompiled", 0) for v in eff.get("pairs", {}).values())


def summary(eff, doc):
    """Summary bullet: whether absent lobes cost nothing."""
    pairs = eff.get("pairs", {})
    if not pairs:
        return []
    wrong = [k for k, v in pairs.items() if lobe_verdict(k, v).startswith("**")]
    return ["- Lobes that are not present cost nothing: "
            + ("true for every model measured." if not wrong else
               "**not true for " + ", ".join(f"`{k}`" for k in wrong)
               + f"** (section {doc.number('effects')}).")]


def plot(eff, path):
    """Time ratio of each pair, without / with the effect."""
    return ratio_bars(ratio_items(eff["pairs"]), path, "render time without / with the effect",
                      "time ratio A / B (median, range)")


def figures_steps(settings):
    """Progress steps of the figure scenes' measurement."""
    from ...paths import SCENES
    return len([n for n in os.listdir(SCENES) if re.match(r"fig.*\.xml$", n)])


def figures_recompiled(fig):
    """Timed renders of the figure scenes repeated because a kernel was compiled."""
    return sum(v.get("recompiled", 0) for v in fig.get("scenes", {}).values())


def lobe_verdict(key, v):
    """What a lobe pair says of the plugin (a dropped lobe must trace fewer instructions)."""
    if v.get("kind") != "lobe":
        return ""
    if v["instr_a"] < v["instr_b"] and v["ratio"] <= 1.02:
        return "dropped: fewer instructions, less time"
    if v["instr_a"] < v["instr_b"]:
        return "dropped: fewer instructions; time difference within noise"
    return "**the absent lobe is still traced: plugin wrong**"


def text(eff, doc):
    """The section's text under its heading."""
    st = eff["settings"]
    out = [f"The sphere at {st['res']} x {st['res']}, {st['spp']} spp, `direct`; "
           f"{st['runs']} paired runs. Ratio = A / B, A being the configuration without the "
           "effect. A lobe whose weight is a constant zero must be dropped from the kernel "
           "(fewer instructions, ratio < 1); one weighted 1e-6 is kept."
           + (f" Dropped lobes timed for {', '.join(f'`{m}`' for m in st['models'])} only."
              if st.get("models") else ""), ""]
    if eff["pairs"]:
        out += doc.image("effects.png", "effect time ratios")
    rows = [[f"`{k}`", v["what"], ratio(v), f"{v['instr_a']} / {v['instr_b']}",
             f"{sec(v['compile_a'])} / {sec(v['compile_b'])}", lobe_verdict(k, v)]
            for k, v in eff["pairs"].items()]
    return out + table(["pair", "A / B", "time ratio (range)", "instr. A / B", "compile A / B",
                        "verdict"], rows) + [""]


def figures_text(fig, doc):
    """The text of the subsection on the figure scenes, under its heading."""
    st = fig["settings"]
    out = [f"Every `scenes/fig*.xml` that loads, at {st['res']} x {st['res']}, "
           f"{st['spp']} spp: its own integrator and the other one (`path` with the scene's max_depth, "
           "or 16 for a `direct` scene; the same `hide_emitters`). *mean diff.* = "
           "(path - direct) / path of the image means: the light `direct` leaves out "
           "(interreflections), plus noise.", ""]
    rows = [[f"`{name}`", v["own"] + (f" (max_depth {v['own_max_depth']})" if v["own_max_depth"] else ""),
             v["path_max_depth"], ratio(v), num(v["mean_rel_diff"], 2),
             f"{v['instr_a']} / {v['instr_b']}",
             f"{sec(v['compile_a'])} / {sec(v['compile_b'])}"]
            for name, v in fig["scenes"].items()]
    return out + table(["scene", "its integrator", "path max_depth", "time path / direct",
                        "mean diff.", "instr. path / direct", "compile path / direct"], rows) + [""]
