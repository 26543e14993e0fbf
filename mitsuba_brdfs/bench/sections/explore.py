"""Section "the explorer" of the study's document: how long a parameter change takes to
reach the plots and the sphere of ``python -m mitsuba_brdfs explore``, on the server and in
the page (measured by ``bench.explore.run``), against the targets."""
from .format import sec, table

__all__ = ["steps", "text", "summary", "verdict", "load"]


def steps(settings):
    """Progress steps of the measurement: the server, the page."""
    return 2


def _ms(x):
    """Milliseconds as the document writes them."""
    return sec(x / 1e3)


def _split(page, what):
    """A redraw in the page, with its requests and scripts."""
    script = page.get(f"{what}_script_ms")
    return (f"**{_ms(page[f'{what}_ms'])}** (requests {_ms(page[f'{what}_fetch_ms'])}"
            + (f", scripts {_ms(script)}" if script is not None else "") + ")")


def verdict(ms, target):
    """Whether a median is within its target."""
    return "met" if ms <= target else "**not met**"


def load(data):
    """The sentence on the machine's load while the section was measured."""
    la, cores = data.get("load_average"), data.get("cores")
    if not la or not cores:
        return ""
    busy = max(la)
    what = ("a machine shared with other work, under load: other processes took "
            "part of the cores, so these times are upper bounds of a quiet machine's"
            if busy >= 0.5 * cores else "a quiet machine")
    return (f" Measured on {cores} cores, {what} (load average over 1 minute "
            f"{la[0]:.1f} at the start, {la[1]:.1f} at the end).")


def summary(ex, doc):
    """Summary bullet: the redraw and the first sphere against their targets."""
    s, t, page = ex["server"], ex["targets"], ex.get("page")
    parts = [f"the plots' data of both BSDFs {_ms(s['plots_ms'])} after a parameter change"]
    if page:
        parts.append(f"the page redrawn in {_ms(page['param_ms'])} in headless chromium "
                     f"(target {t['plots_ms']} ms: {verdict(page['param_ms'], t['plots_ms'])})")
        sphere = page["param_sphere_ms"]
        parts.append(f"both spheres shown again, the changed one at its first pass, in "
                     f"{_ms(sphere)} (target "
                     f"{t['sphere_ms']} ms: {verdict(sphere, t['sphere_ms'])})")
    else:
        parts.append(f"the first pass of a sphere {_ms(s['sphere_ms'])} (target "
                     f"{t['sphere_ms']} ms: {verdict(s['sphere_ms'], t['sphere_ms'])}; the "
                     "page not measured)")
    return [f"- The explorer (section {doc.number('explore')}), medians with a warm kernel "
            "cache: " + "; ".join(parts) + "."]


def text(ex, doc):
    """The section's text under its heading."""
    s, t, page = ex["server"], ex["targets"], ex.get("page")
    out = [f"`python -m mitsuba_brdfs explore ashikhmin_shirley roughplastic`: two BSDFs shown, "
           f"a parameter of the first (`nu`) changed {s['repeats']} times after the kernels are "
           f"warm (`{s['variant']}`, {s['threads']} Dr.Jit threads; "
           "`mitsuba_brdfs/bench/explore.py`). The targets: the plots redrawn within "
           f"{t['plots_ms']} ms of a change, the first image of the sphere within "
           f"{t['sphere_ms']} ms, on 2 cores with a warm kernel cache."
           + load(ex), "",
           "*Server*: the parameter update (`mi.traverse`, so no kernel is compiled) and the "
           "data of every plot of both BSDFs encoded as JSON, the page's drawing not included; "
           "the first pass of the changed BSDF's sphere encoded as PNG; a later pass. "
           "*Page*: Debian's headless chromium driven by Playwright, the page at rest (every "
           "sphere refined) before each change, watched from outside (its DOM's `aria-busy` and "
           "captions, the browser's resource timing): the time from the change's event "
           "(a value typed, or the incidence slider moved) until the frame with every plot "
           "drawn is painted, and until every sphere is shown again, the changed one at its "
           "first pass (the server keeps the others' images). Of the redraw, "
           "*requests* is the time until the server's last answer: the parameter's update and the "
           "plots' data of the changed BSDF (the other BSDF's plots have not changed; a move "
           "of the incidence slider asks for the lobes of both); *scripts* is Plotly "
           "updating the plots; the rest is the browser's layout and painting of the frame, "
           "the 3D plot's WebGL included. Headless chromium draws "
           "the 3D plot with WebGL on the CPU ("
           + (f"`{page['renderer']}`" if page else "SwiftShader") + "), on the same cores as "
           "the server, so the page's times are upper bounds of a desktop browser's. What "
           "the page does to be quick: a parameter change asks for the plots of its BSDF "
           "only; the 3D lobes are meshes of the server's grid (a Plotly `surface` would be "
           "resampled to a grid about 20 times finer), and that scene has no hover, so WebGL "
           "draws each frame once (not again for picking).", ""]
    rows = [["a parameter changed: every plot's data (server)", f"**{_ms(s['plots_ms'])}**",
             f"{t['plots_ms']} ms", verdict(s["plots_ms"], t["plots_ms"])]]
    if page:
        rows += [["a parameter typed: the page redrawn", _split(page, "param"),
                  f"{t['plots_ms']} ms", verdict(page["param_ms"], t["plots_ms"])],
                 ["the incidence slider moved: the page redrawn", _split(page, "incidence"),
                  f"{t['plots_ms']} ms", verdict(page["incidence_ms"], t["plots_ms"])]]
    rows.append(["a parameter changed: the first pass of its sphere (server)",
                 f"**{_ms(s['sphere_ms'])}**", f"{t['sphere_ms']} ms",
                 verdict(s["sphere_ms"], t["sphere_ms"])])
    if page:
        rows.append(["a parameter typed: the first pass of its sphere in the page",
                     f"**{_ms(page['param_sphere_ms'])}**", f"{t['sphere_ms']} ms",
                     verdict(page["param_sphere_ms"], t["sphere_ms"])])
    rows += [["a later pass of the sphere (server)", _ms(s["pass_ms"]), "", ""],
             ["the session's first plots (kernels compiled or loaded from the disk cache)",
              _ms(s["first_plots_ms"]), "", ""],
             ["the session's first sphere pass", _ms(s["first_sphere_ms"]), "", ""]]
    n = f"{s['repeats']} changes" + (f"; page: {page['repeats']}" if page else "")
    out += table([f"medians ({n})", "time", "target", ""], rows) + [""]
    if not page:
        out += [f"The page was not measured: {'; '.join(ex.get('skipped', []))}.", ""]
    else:
        out += ["Where the rest of the page's redraw goes (chromium's trace): the frame "
                "waits for the GPU process, where SwiftShader draws the 3D plot's two "
                "translucent lobes on the CPU (opaque lobes are drawn faster, but one would "
                "hide the other); after a move of the incidence slider, most of the "
                "request's time is the browser taking in the response (the server answers "
                "in a few milliseconds). Plotly's scripts update the five plots one after "
                "the other.", ""]
    return out
