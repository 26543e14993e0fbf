"""The explorer's speed: how long a parameter change takes to reach the plots and the sphere.

``measure()`` loads two BSDFs as ``python -m mitsuba_brdfs explore ashikhmin_shirley
roughplastic`` does, warms the kernel cache (the first plots and sphere), then changes a
parameter ``repeats`` times through the page's API and times, with the cache warm:

- ``plots_ms``: the parameter update (``mi.traverse``) and every plot's data of both BSDFs,
  encoded as the JSON the page receives (the page's own drawing is not included);
- ``sphere_ms``: the first pass of the sphere of the changed BSDF, encoded as PNG;
- ``pass_ms``: a later pass (the refinement).

``measure_page()`` times the same in the page, in Debian's headless chromium driven by
Playwright (when both are there): from the request to the last plot drawn, after a
parameter typed and after the incidence slider moved. Headless chromium draws the 3D plot
with a software renderer, so this is an upper bound of what a desktop browser takes.

Both return the medians and ``markdown``, a short paragraph for the performance study,
which compares them with the targets (150 ms for the plots, 0.5 s for the first sphere).
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

__all__ = ["PLOTS_TARGET_MS", "SPHERE_TARGET_MS", "measure", "markdown", "measure_page",
           "page_markdown"]

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
    proc = subprocess.Popen([sys.executable, "-m", "mitsuba_brdfs", "explore",
                             "ashikhmin_shirley", "roughplastic", "--port", "0", "--no-browser"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        m = re.search(r"(http://\S+/)", proc.stdout.readline())
        if not m:
            return {"skipped": "the server did not start"}
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=browser_path, args=["--no-sandbox"])
            page = browser.new_page(viewport={"width": 1400, "height": 1300})
            page.goto(m.group(1))
            page.wait_for_function("+document.body.dataset.drawn >= 1", timeout=120_000)
            nu = page.get_by_label("nu", exact=True)

            def timed(action):
                n = int(page.evaluate("document.body.dataset.drawn"))
                action()
                page.wait_for_function(f"+document.body.dataset.drawn > {n}", timeout=60_000)
                ms = page.evaluate("[+document.body.dataset.redrawMs, "
                                   "+document.body.dataset.fetchMs]")
                time.sleep(0.2)
                return ms
            timed(lambda: (nu.fill("50"), nu.press("Enter")))  # warm
            param = [timed(lambda k=k: (nu.fill(str(60 + 10 * k)), nu.press("Enter")))
                     for k in range(repeats)]
            incidence = [timed(lambda k=k: page.locator("#theta-i").fill(str(20 + 3 * k)))
                         for k in range(repeats)]
            browser.close()
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=30)
    out = {"param_ms": statistics.median(r for r, _ in param),
           "param_fetch_ms": statistics.median(f for _, f in param),
           "incidence_ms": statistics.median(r for r, _ in incidence),
           "incidence_fetch_ms": statistics.median(f for _, f in incidence),
           "repeats": repeats}
    out["markdown"] = page_markdown(out)
    return out


def page_markdown(m):
    """The paragraph of the performance study on the page's redraw."""
    if "skipped" in m:
        return f"The page's redraw was not measured: {m['skipped']}."
    return (
        f"In the page (headless chromium, which draws the 3D plot in software, on the same "
        f"2 cores as the server), a parameter typed is redrawn in {m['param_ms']:.0f} ms "
        f"(median of {m['repeats']}; {m['param_fetch_ms']:.0f} ms of it the request), and a "
        f"move of the incidence slider, which asks for the two lobe plots only, in "
        f"{m['incidence_ms']:.0f} ms ({m['incidence_fetch_ms']:.0f} ms the request).")
