"""The explorer's speed: how long a parameter change takes to reach the plots and the sphere.

``measure()`` loads two BSDFs as ``python -m mitsuba_brdfs explore ashikhmin_shirley
roughplastic`` does, warms the kernel cache (the first plots and sphere), then changes a
parameter ``repeats`` times through the page's API and times, with the cache warm:

- ``plots_ms``: the parameter update (``mi.traverse``) and every plot's data of both BSDFs,
  encoded as the JSON the page receives (the page's own drawing is not included);
- ``sphere_ms``: the first pass of the sphere of the changed BSDF, encoded as PNG;
- ``pass_ms``: a later pass (the refinement).

``measure_page()`` times the same in the page, in Debian's headless chromium driven by
Playwright (when both are there; else ``{"skipped": reason}``): from the change (a
parameter typed, the incidence slider moved) until the frame with every plot drawn is
painted, watched from outside through the page's DOM (its plots are ``aria-busy`` until
drawn) and the browser's resource timing, with the requests' share (until the last plots'
answer) and the plots' scripts' (from it to the plots drawn); the rest is the frame's
layout and painting, the 3D plot's WebGL included. Headless chromium draws the 3D plot
with SwiftShader, WebGL on the CPU, so this is an upper bound of what a desktop browser
takes.

``run()`` is the section "the explorer" of the performance study (``bench.sections``):
both, with the targets (150 ms for the plots, 0.5 s for the first sphere).

``measure_fits()`` times the page's fit (``POST /api/fit/ID``, ``Explorer.fit``) of each of
this package's models to a full-size MERL file (90 x 90 x 180 bins, written from a known
BRDF: Ngan et al.'s Cook-Torrance fit of gold-paint), as the server runs it: the first fit
of each model in the session (its kernels compiled or loaded from Dr.Jit's disk cache) and
the median of later ones, against the target of 5 s (``FIT_TARGET_S``); reading the file's
samples (once per file, before the first fit) apart. ``python -m
mitsuba_brdfs.bench.explore`` prints them as a Markdown table.
"""
import json
import os
import re
import shutil
import signal
import statistics
import subprocess
import sys
import time

__all__ = ["PLOTS_TARGET_MS", "SPHERE_TARGET_MS", "FIT_TARGET_S", "measure",
           "measure_page", "measure_fits", "fits_table", "run"]

PLOTS_TARGET_MS = 150
SPHERE_TARGET_MS = 500
FIT_TARGET_S = 5.0


def _ms(fn):
    t0 = time.perf_counter()
    fn()
    return (time.perf_counter() - t0) * 1e3


def measure(repeats=15, variant=None):
    """Medians (ms) of the explorer's redraw after a parameter change; see the module."""
    import drjit as dr
    import mitsuba as mi

    from ..variant import set_variant
    variant = variant or mi.variant() or "llvm_ad_rgb"  # bench --variant's
    set_variant(variant)  # the plugins registered in it too
    from ..explore.entries import make_entries
    from ..explore.session import PALETTE, Explorer
    found = make_entries("ashikhmin_shirley", {}, 0, PALETTE)
    found += make_entries("roughplastic", {}, 1, PALETTE)
    ex = Explorer(found, variant)
    body = {"theta_i": 45.0, "theta_h": 30.0, "theta_d": 30.0, "exposure": 0.0}
    light = (45.0, 135.0, 0.0)
    t_first = _ms(lambda: json.dumps(ex.plots(**body)))  # compiles, or loads from disk
    t_first_sphere = _ms(lambda: ex.sphere(0, 0, *light))
    for k in range(2):  # warm: the kernels after an update
        ex.patch(0, ("nu", 50.0 + k))
        json.dumps(ex.plots(**body))
        ex.sphere(0, 0, *light)
    plots, sphere, passes = [], [], []
    for k in range(repeats):
        value = 20.0 + 10 * k
        plots.append(_ms(lambda: (ex.patch(0, ("nu", value)),
                                  json.dumps(ex.plots(**body)))))
        sphere.append(_ms(lambda: ex.sphere(0, 0, *light)))
        passes.append(_ms(lambda: ex.sphere(0, 1, *light)))
    out = {"plots_ms": statistics.median(plots), "sphere_ms": statistics.median(sphere),
           "pass_ms": statistics.median(passes), "first_plots_ms": t_first,
           "first_sphere_ms": t_first_sphere, "repeats": repeats, "bsdfs": 2,
           "threads": dr.thread_count(), "variant": variant}
    return out


def _chromium():
    for p in (shutil.which("chromium"), shutil.which("chromium-browser"), "/usr/bin/chromium"):
        if p and os.path.exists(p):
            return p
    return None


def measure_page(repeats=10):
    """Medians (ms) of the page's redraw in headless chromium; ``{"skipped": reason}``
    without chromium or Playwright."""
    browser_path = _chromium()
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        return {"skipped": "Playwright is not installed (pip install playwright)"}
    if browser_path is None:
        return {"skipped": "no chromium (apt-get install chromium)"}
    from ..explore.sphere import PASS_SPP
    import mitsuba as mi
    proc = subprocess.Popen([sys.executable, "-m", "mitsuba_brdfs", "explore",
                             "ashikhmin_shirley", "roughplastic", "--port", "0", "--no-browser",
                             "--variant", mi.variant() or "llvm_ad_rgb"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        m = re.search(r"(http://\S+)", proc.stdout.readline())
        if not m:
            return {"skipped": "the server did not start"}
        with sync_playwright() as p:
            try:
                browser = p.chromium.launch(executable_path=browser_path, args=[
                    "--headless", "--no-sandbox", "--disable-gpu",
                    "--disable-background-networking"])
            except Exception as e:  # noqa: BLE001 (Playwright's Error: a browser it cannot run)
                return {"skipped": f"chromium did not start ({str(e).splitlines()[0]})"}
            # Playwright's waits evaluate strings, which the page's policy forbids
            page = browser.new_page(viewport={"width": 1400, "height": 1300},
                                    bypass_csp=True)
            page.goto(m.group(1))
            page.wait_for_function(_SETTLED, timeout=120_000)
            renderer = page.evaluate(_RENDERER)
            nu = page.get_by_label("nu", exact=True)

            def timed(action, sphere):
                # from a page at rest (every sphere refined): the change, then its plots
                # drawn (and, after a parameter, every sphere shown again: the changed one
                # at its first pass)
                page.wait_for_function(_SETTLED, timeout=120_000)
                page.evaluate(_WATCH % PASS_SPP)
                action()
                page.wait_for_function("window.__watch.painted !== undefined",
                                       timeout=60_000)
                if sphere:
                    page.wait_for_function("window.__watch.sphere !== undefined",
                                           timeout=60_000)
                return page.evaluate(_TIMES)

            def typed(k):
                nu.fill(str(60 + 10 * k))
                nu.press("Enter")
            timed(lambda: typed(-1), True)  # warm
            param = [timed(lambda k=k: typed(k), True) for k in range(repeats)]
            incidence = [timed(lambda k=k: page.locator("#theta-i").fill(str(20 + 3 * k)),
                               False) for k in range(repeats)]
            browser.close()
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=30)
    med = lambda rows, i: statistics.median(r[i] for r in rows)  # noqa: E731
    return {"param_ms": med(param, 0), "param_fetch_ms": med(param, 1),
            "param_script_ms": med(param, 3), "param_sphere_ms": med(param, 2),
            "incidence_ms": med(incidence, 0), "incidence_fetch_ms": med(incidence, 1),
            "incidence_script_ms": med(incidence, 3), "repeats": repeats,
            "renderer": renderer, "param_all_ms": [r[0] for r in param],
            "incidence_all_ms": [r[0] for r in incidence]}


#: the page's WebGL renderer (SwiftShader in headless chromium)
_RENDERER = """(() => { const g = document.createElement("canvas").getContext("webgl");
  if (!g) return "no WebGL";
  const x = g.getExtension("WEBGL_debug_renderer_info");
  return x ? g.getParameter(x.UNMASKED_RENDERER_WEBGL) : g.getParameter(g.RENDERER); })()"""
#: the page at rest: its plots drawn, every sphere at its last pass (the page marks both
#: with aria-busy)
_SETTLED = ("document.querySelector('#plots').getAttribute('aria-busy') === 'false' && "
            "document.querySelector('#spheres').getAttribute('aria-busy') === 'false'")
#: watches the page from outside, through its DOM and the browser's resource timing: the
#: time of the change's event (input or change), the plots no longer busy, the frame after
#: it painted, every sphere shown again (every caption with its spp), the changed one at its
#: first pass (a caption at the first pass's spp: the others are at their last at once)
_WATCH = """(() => {
  const w = window.__watch = {};
  performance.clearResourceTimings();  // (its buffer holds 250 requests)
  const at = (e) => { if (w.t0 === undefined) w.t0 = e.timeStamp; };
  document.addEventListener("input", at, { capture: true, once: true });
  document.addEventListener("change", at, { capture: true, once: true });
  const plots = document.getElementById("plots");
  let busy = false;
  new MutationObserver((_, obs) => {
    if (plots.getAttribute("aria-busy") === "true") { busy = true; return; }
    if (!busy) return;
    obs.disconnect();
    w.drawn = performance.now();
    requestAnimationFrame(() => setTimeout(() => { w.painted = performance.now(); }));
  }).observe(plots, { attributes: true, attributeFilter: ["aria-busy"] });
  const caps = () => [...document.querySelectorAll("#spheres .cap")].map((c) => c.textContent);
  new MutationObserver((_, obs) => {
    const c = caps();
    if (!c.every((t) => / \\(\\d+ spp\\)$/.test(t)) || !c.some((t) => t.endsWith(" (%d spp)")))
      return;
    obs.disconnect();
    w.sphere = performance.now();
  }).observe(document.getElementById("spheres"), { subtree: true, childList: true,
                                                   characterData: true });
})()"""
#: (redraw, fetch, sphere, script) ms of the change watched
_TIMES = """(() => {
  const w = window.__watch;
  const plots = performance.getEntriesByType("resource").filter(
    (r) => r.name.includes("/api/plots") && r.startTime >= w.t0);
  const end = plots.length ? plots[plots.length - 1].responseEnd : NaN;
  return [w.painted - w.t0, end - w.t0, (w.sphere ?? NaN) - w.t0, w.drawn - end];
})()"""


def run(settings, available, progress=None):
    """The study's section: ``measure`` and ``measure_page`` with the settings' repeats."""
    from ..progress import advance
    from .load import under_load

    def both():
        server = measure(settings.explore_repeats)
        advance(progress, 1, "server")
        page = measure_page(settings.explore_page_repeats)
        advance(progress, 1, "page")
        return {"server": server, "page": page,
                "targets": {"plots_ms": PLOTS_TARGET_MS, "sphere_ms": SPHERE_TARGET_MS}}

    out = under_load(both)
    page = out.pop("page")
    if "skipped" in page:
        out["skipped"] = [f"the page's redraw was not measured: {page['skipped']}"]
    else:
        out["page"] = page
    return out


def measure_fits(models=None, repeats=3, variant="llvm_ad_rgb", dims=(90, 90, 180),
                 samples=None, evaluations=None):
    """Seconds of the page's fits of ``models`` (default: every model of the package) to
    a MERL file of ``dims`` bins (see the module docstring), at the page's budget (or
    ``samples``, ``evaluations``, as ``explore --fit-samples --fit-evaluations``):
    {"data_s": reading the file's
    samples, "fits": {model: {"first_s", "median_s", "evaluations", "relative_rms" (the
    largest channel's), "holdout_loss"}}, "budget" (``fitting.budget``), "threads",
    "load_average", "cores"}."""
    import tempfile
    import drjit as dr
    import mitsuba as mi
    from .load import under_load
    from .. import presets
    from ..measured import merl
    from ..variant import set_variant
    set_variant(variant)
    from ..explore.entries import make_entries, plugin_models
    from ..explore.fitting import data
    from ..explore.session import PALETTE, Explorer
    models = list(models or sorted(plugin_models()))
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "gold-paint.binary")
        spec = presets.ngan2005("cook_torrance", "gold-paint")
        merl.write(path, merl.from_bsdf(mi.load_dict(spec), dims), dims)
        old = os.environ.get("MITSUBA_BRDFS_CACHE")
        os.environ["MITSUBA_BRDFS_CACHE"] = os.path.join(folder, "cache")
        try:
            ex = Explorer(make_entries(path, {}, 0, PALETTE), variant,
                          fit_samples=samples, fit_evaluations=evaluations)

            def fits():
                entry = ex.entries[0]
                t0 = time.perf_counter()
                entry.fit_data = data(entry.measured, ex.fit_budget["samples"])
                out = {"data_s": time.perf_counter() - t0, "fits": {}}
                for model in models:
                    times, last = [], None
                    for _ in range(1 + repeats):
                        t0 = time.perf_counter()
                        last = ex.fit(0, model)
                        times.append(time.perf_counter() - t0)
                        ex.remove(last["entry"]["id"])
                    out["fits"][model] = {
                        "first_s": times[0], "median_s": statistics.median(times[1:]),
                        "evaluations": last["fit"]["evaluations"],
                        "relative_rms": last["fit"]["relative_rms_max"],
                        "holdout_loss": last["fit"]["holdout_loss"]}
                return out
            out = under_load(fits)
        finally:
            if old is None:
                os.environ.pop("MITSUBA_BRDFS_CACHE", None)
            else:
                os.environ["MITSUBA_BRDFS_CACHE"] = old
    out.update(budget=ex.fit_budget, threads=dr.thread_count(), dims=list(dims))
    return out


def fits_table(r):
    """``measure_fits``'s result as a Markdown table."""
    rows = ["| model | first fit (s) | later fits, median (s) | evaluations | relative RMS "
            "| held-out loss |", "|---|---|---|---|---|---|"]
    for model, f in r["fits"].items():
        rows.append(f"| `{model}` | {f['first_s']:.2f} | {f['median_s']:.2f} | "
                    f"{f['evaluations']} | {f['relative_rms']:.3f} | "
                    f"{f['holdout_loss']:.3g} |")
    la, b = r["load_average"], r["budget"]
    rows.append(f"\nReading the file's samples (the first fit of a file): {r['data_s']:.2f} s. "
                f"{b['samples']} samples, at most {b['most']} evaluations ({b['evaluations']} "
                f"a stage), "
                f"{r['threads']} Dr.Jit threads, {r['cores']} cores, load average "
                f"{la[0]:.1f} before, {la[1]:.1f} after.")
    return "\n".join(rows)


if __name__ == "__main__":
    import argparse
    p = argparse.ArgumentParser(description="time the explorer's fits")
    p.add_argument("--models", help="comma-separated models (default: all)")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--threads", type=int, default=2)
    a = p.parse_args()
    import drjit as dr
    dr.set_thread_count(a.threads)
    result = measure_fits(a.models.split(",") if a.models else None, a.repeats)
    print(fits_table(result))
