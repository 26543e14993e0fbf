"""The explorer's page in a real headless browser (Debian's chromium, driven by Playwright).

The command is started as a user starts it (``python -m mitsuba_brdfs explore ...
--port 0 --no-browser``); the page must load without console errors, draw its plots,
redraw when a control moves, and show both BSDFs it was given. A screenshot is written
to pytest's temporary folder."""
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import pytest

pytest.importorskip("starlette")
playwright = pytest.importorskip("playwright.sync_api")

CHROMIUM = next((p for p in (shutil.which("chromium"), shutil.which("chromium-browser"),
                             "/usr/bin/chromium") if p and os.path.exists(p)), None)
pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(CHROMIUM is None, reason="no chromium (scripts/bootstrap.sh "
                                                          "installs Debian's)")]


@pytest.fixture
def server():
    proc = subprocess.Popen(
        [sys.executable, "-m", "mitsuba_brdfs", "explore", "lambert", "ashikhmin_shirley",
         "-p", "ashikhmin_shirley:nu=20", "--port", "0", "--no-browser"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    line = proc.stdout.readline()
    m = re.search(r"(http://\S+)", line)
    assert m, line + (proc.stdout.read() if proc.poll() is not None else "")
    yield m.group(1)
    proc.send_signal(signal.SIGINT)  # Ctrl-C stops it, as every command: status 130
    assert proc.wait(timeout=30) == 130


def _drawn(page):
    return int(page.evaluate("document.body.dataset.drawn || 0"))


def _wait_redrawn(page, before):
    page.wait_for_function(f"(+document.body.dataset.drawn || 0) > {before}", timeout=60_000)


def test_page_draws_overlays_and_follows_controls(server, tmp_path):
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1400, "height": 1300})
        errors = []
        page.on("console", lambda m: m.type == "error" and errors.append(m.text))
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(server)
        _wait_redrawn(page, 0)

        # both BSDFs are drawn, each in its colour, in every plot
        names = page.evaluate("document.getElementById('polar').data.map(t => t.name)")
        assert names == ["lambert", "ashikhmin_shirley", "incidence"]
        for plot in ("lobe", "slice-h", "slice-d"):
            assert page.evaluate(f"document.getElementById('{plot}').data.length") == 2
        assert page.evaluate("document.getElementById('albedo').data.length") == 4
        assert page.locator("#images .tile").count() == 2
        colours = page.evaluate(
            "document.getElementById('polar').data.slice(0, 2).map(t => t.line.color)")
        assert len(set(colours)) == 2
        page.wait_for_function(
            "[...document.querySelectorAll('#spheres img')].filter("
            "i => i.complete && i.naturalWidth > 0).length == 2", timeout=60_000)

        # typing a new exponent redraws the lobe of that BSDF only
        polar = "document.getElementById('polar').data[{}].r"
        before = [page.evaluate(polar.format(k)) for k in (0, 1)]
        n = _drawn(page)
        nu = page.get_by_label("nu", exact=True)
        nu.fill("400")
        nu.press("Enter")
        _wait_redrawn(page, n)
        after = [page.evaluate(polar.format(k)) for k in (0, 1)]
        assert after[0] == before[0] and after[1] != before[1]
        assert max(filter(None, after[1])) > 2 * max(filter(None, before[1]))

        # moving the incidence slider moves the specular peak
        n = _drawn(page)
        page.locator("#theta-i").fill("70")
        _wait_redrawn(page, n)
        page.wait_for_function("document.getElementById('polar').data[2].theta[0] == -70")

        assert not errors, errors
        # a value out of range is refused in the page (the browser logs the request's
        # status 400, nothing else); the server stays up
        n = _drawn(page)
        nu.fill("-5")
        nu.press("Enter")
        page.wait_for_function(
            "document.querySelector('#entry-1 .error').textContent.includes('[0, 1e6]')")
        assert nu.input_value() == "400"  # the value the server holds is shown again
        page.locator("#theta-i").fill("30")
        _wait_redrawn(page, n)

        # a BSDF added, exported and removed in the page
        n = _drawn(page)
        page.locator("#add-spec").fill("roughplastic")
        page.locator("#add-form button").click()
        _wait_redrawn(page, n)
        names = page.evaluate("document.getElementById('polar').data.map(t => t.name)")
        assert names == ["lambert", "ashikhmin_shirley", "roughplastic", "incidence"]
        page.locator("#entry-1 .actions button", has_text="Export").click()
        page.wait_for_selector("#entry-1 textarea")
        xml = page.locator("#entry-1 textarea").first.input_value()
        assert '<bsdf type="ashikhmin_shirley">' in xml and 'name="nu" value="400"' in xml
        page.screenshot(path=str(tmp_path / "explore.png"), full_page=True)
        page.locator("#entry-2 .head button").click()
        page.wait_for_function("document.getElementById('polar').data.length == 3")
        browser.close()
    assert errors == ["Failed to load resource: the server responded with a status of 400 "
                      "(Bad Request)"], errors


def test_page_stays_local_and_has_no_cloud_button(server):
    """No toolbar button uploads a chart ("Share chart...", Chart Studio), and loading and
    redrawing the page requests nothing outside the local server."""
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1400, "height": 1300})
        urls = []
        page.on("request", lambda r: urls.append(r.url))
        page.goto(server)
        _wait_redrawn(page, 0)
        before = _drawn(page)
        page.fill("#theta-i", "45")
        page.dispatch_event("#theta-i", "input")
        _wait_redrawn(page, before)
        buttons = page.evaluate("[...document.querySelectorAll('.modebar-btn')]"
                                ".map(b => (b.getAttribute('data-title') || '') + '|'"
                                " + (b.getAttribute('href') || ''))")
        links = page.evaluate("[...document.querySelectorAll('a[href^=http]')].map(a => a.href)")
        browser.close()
    assert buttons, "no Plotly toolbar found"
    assert not [b for b in buttons if re.search(r"share|cloud|chart studio|plotly\.com", b, re.I)]
    assert not [u for u in links if not u.startswith("http://127.0.0.1")]
    outside = [u for u in urls if not re.match(r"(http://127\.0\.0\.1[:/]|blob:|data:)", u)]
    assert urls and not outside, outside
