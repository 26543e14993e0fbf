"""The picture of docs/explore.md's measured data: the explorer with a MERL file and an RGL
file, and a model fitted to the MERL file in the page.

The files are written here, as the tests write theirs: a full-size MERL file (90 x 90 x
180 bins) of Mitsuba's ``roughplastic`` (GGX, alpha 0.1, an orange diffuse layer), which
none of this package's models is, and an RGL file ``to-rgl`` writes of Mitsuba's gold
``roughconductor`` (alpha 0.2). ``explore`` is started as a user starts it, the page
opened in Debian's headless chromium (Playwright), ``cook_torrance`` fitted to the MERL file from
its panel, and the page saved at 1400 px.

    python scripts/explore_measured_png.py docs/explore_measured.png
"""
import os
import re
import subprocess
import sys
import tempfile

import mitsuba as mi

mi.set_variant("llvm_ad_rgb")

import mitsuba_brdfs  # noqa: E402,F401  (registers the plugins)
from mitsuba_brdfs.measured import merl  # noqa: E402

#: the page at rest (a function: the page's Content-Security-Policy forbids evaluating
#: strings as script)
SETTLED = ("() => document.querySelector('#plots').getAttribute('aria-busy') === 'false' && "
           "document.querySelector('#spheres').getAttribute('aria-busy') === 'false'")


def main(out):
    from playwright.sync_api import sync_playwright
    folder = tempfile.mkdtemp()
    binary = os.path.join(folder, "orange-plastic.binary")
    plastic = mi.load_dict({"type": "roughplastic", "distribution": "ggx", "alpha": 0.1,
                            "diffuse_reflectance": {"type": "rgb", "value": [0.7, 0.25, 0.05]}})
    merl.write(binary, merl.from_bsdf(plastic))
    rgl = os.path.join(folder, "gold.bsdf")
    subprocess.run([sys.executable, "-m", "mitsuba_brdfs", "to-rgl", "roughconductor",
                    "-p", "material=Au", "-p", "alpha=0.2", "--no-compare", "-o", rgl],
                   check=True, capture_output=True)
    env = dict(os.environ, MITSUBA_BRDFS_CACHE=os.path.join(folder, "cache"))
    server = subprocess.Popen([sys.executable, "-m", "mitsuba_brdfs", "explore", binary, rgl,
                               "--port", "0", "--no-browser"], stdout=subprocess.PIPE,
                              text=True, env=env)
    try:
        url = re.search(r"(http://\S+)", server.stdout.readline()).group(1)
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=[
                "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking"])
            page = browser.new_page(viewport={"width": 1400, "height": 1200})
            page.goto(url)
            page.wait_for_function(SETTLED, timeout=120_000)
            panel = page.locator("#entry-0")
            panel.locator("select").select_option("cook_torrance")
            panel.locator("button.fit").click()
            page.wait_for_selector("#entry-2", timeout=120_000)
            page.wait_for_function(SETTLED, timeout=120_000)
            page.mouse.move(0, 0)
            page.screenshot(path=out)
            browser.close()
    finally:
        server.terminate()
        server.wait()


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "explore_measured.png")
