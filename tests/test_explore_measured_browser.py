"""Measured data in the explorer's page, in a real headless browser (Debian's chromium,
driven by Playwright), at 1400 px and with the window made 1024 px wide: ``explore
gold.binary ward.bsdf cook_torrance --fit-samples 1000 --fit-evaluations 120`` (a MERL file,
an RGL file, a model; the files written by the test; fits at a small budget), as a user
starts it. One server, one browser, one page.

- every card draws the measured entries beside the model; their panels say they are
  measured data, have no controls, and offer a fit;
- a fit in the page: the model chosen, "Fit" pressed, the other fits wait, the fitted
  model added as a BSDF drawn over the data in every card, the server's summary shown
  (its errors, its budget, the fit-measured command that makes the same fit);
- a fit cancelled from the page ("Cancel fit"): nothing added.

Screenshots of both widths, before and after the fit, are written to pytest's temporary
folder."""
import json
import os

import pytest

from explore_page import (CHROMIUM, Server, launch, measured_files, open_page, resize, settle,
                          traces)

pytest.importorskip("starlette")
playwright = pytest.importorskip("playwright.sync_api")

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(CHROMIUM is None, reason="no chromium (scripts/bootstrap.sh "
                                                          "installs Debian's)")]

#: loaded by the server (--load): while the file ARMED exists and OPEN does not, a fit
#: waits after each evaluation, so that the test cancels it while it runs
GATE = """
import os, time
from mitsuba_brdfs.measured import report

ARMED, OPEN = {armed!r}, {open!r}
_fit_file = report.fit_file

def _gated(*args, progress=None, **kw):
    def step(loss):
        while os.path.exists(ARMED) and not os.path.exists(OPEN):
            time.sleep(0.01)
        progress(loss)
    return _fit_file(*args, progress=step, **kw)

report.fit_file = _gated
"""

LABELS = ["gold.binary", "ward.bsdf", "cook_torrance"]
FITTED = "cook_torrance fit to gold.binary"


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    d = tmp_path_factory.mktemp("explore_measured")
    measured_files(str(d))
    (d / "gate.py").write_text(GATE.format(armed=str(d / "armed"), open=str(d / "open")))
    return d


@pytest.fixture(scope="module")
def server(folder):
    with pytest.MonkeyPatch.context() as env:
        env.setenv("MITSUBA_BRDFS_CACHE", str(folder / "cache"))
        server = Server(str(folder / "gold.binary"), str(folder / "ward.bsdf"), "cook_torrance",
                        "--load", str(folder / "gate.py"), "--fit-samples", "1000",
                        "--fit-evaluations", "120")
    yield server
    assert server.stop() == 130


@pytest.fixture(scope="module")
def page(server):
    """The page at 1400 px in Debian's chromium, for the module."""
    with playwright.sync_playwright() as p:
        browser = launch(p)
        page = open_page(browser, server)
        yield page
        browser.close()


@pytest.fixture(scope="module", params=[1400, 1024])
def shown(request, page, tmp_path_factory):
    resize(page, request.param)
    page.width = request.param
    page.screenshot(path=str(tmp_path_factory.getbasetemp()
                             / f"explore_measured_{request.param}.png"), full_page=True)
    yield page
    assert not page.errors, page.errors


def entries_drawn(page, labels):
    """Every card draws ``labels`` (Plotly's traces, the slices' and spheres' captions)."""
    assert traces(page, "polar", "name") == labels + ["incidence"]
    assert traces(page, "lobe", "name") == labels
    assert traces(page, "slice-h", "name") == labels
    assert traces(page, "slice-d", "name") == labels
    assert traces(page, "albedo", "name")[::2] == labels
    caps = page.locator("#images .tile .cap")
    assert [caps.nth(k).inner_text() for k in range(caps.count())] == labels
    caps = page.locator("#spheres .cap")
    assert [caps.nth(k).inner_text() for k in range(caps.count())] == \
        [f"{x} (32 spp)" for x in labels]
    # every entry has values in every line plot (a measured entry's are measured's eval)
    for div in ("polar", "slice-h", "slice-d"):
        key = "r" if div == "polar" else "y"
        assert all(max(v or 0 for v in t) > 0 for t in traces(page, div, key)[:len(labels)])


def cut_texts(page):
    """The sidebar's names, values and buttons that do not show whole."""
    return page.evaluate("""[...document.querySelectorAll('#entries .label, #entries select,'
      + ' #entries button, #entries .ctl .name, #entries input[type=text]')]
      .filter((e) => e.scrollWidth > e.clientWidth + 1).map((e) => e.textContent || e.value)""")


def test_measured_entries_in_every_card(shown, server):
    """The MERL and RGL files are drawn in every card beside the model; their panels say
    what they are, have no controls, and offer the package's models to fit. (At 1024 px
    the fit made at 1400 px is there too.)"""
    state = json.loads(server.request("GET", "/api/state")[1])
    labels = [e["label"] for e in state["entries"]]
    assert labels[:3] == LABELS
    entries_drawn(shown, labels)
    for k, kind in ((0, "a MERL file"), (1, "an RGL file")):
        panel = shown.locator(f"#entry-{k}")
        text = panel.locator(".measured").inner_text()
        assert "measured data" in text and kind in text and "no parameters" in text
        assert panel.locator(".controls").count() == 0
        options = panel.locator("select option")
        names = [options.nth(j).inner_text() for j in range(options.count())]
        assert "cook_torrance" in names and "ward" in names and len(names) == 9
        assert panel.locator("button.fit").inner_text() == "Fit"
        assert "1,000 random samples of the file and at most 300 evaluations (120 for the " \
            "fit" in panel.inner_text()
    assert "converted by to-rgl" in shown.locator("#entry-0").inner_text()
    assert "explore: gold.binary: converted by to-rgl" in server.stderr()  # and where to
    assert shown.locator("#entry-2 .controls").count() == 1  # the model keeps its controls
    assert shown.evaluate("document.documentElement.scrollWidth <= window.innerWidth")
    assert shown.evaluate("(() => { const s = document.getElementById('entries');"
                          " return s.scrollWidth <= s.clientWidth; })()")
    assert not cut_texts(shown)


def test_a_fit_in_the_page(shown, server, tmp_path_factory):
    """cook_torrance fitted to the MERL file from the page: while it runs its button offers
    to cancel and the other file's waits; the fitted model is added as a BSDF drawn over
    the data in every card, with the summary the server made (fit-measured's: its errors,
    its budget, the command that makes the same fit). (At 1024 px the fit of the first
    width is there already: the page shows it.)"""
    panel = shown.locator("#entry-0")
    if shown.width == 1400:
        panel.locator("select").select_option("cook_torrance")
        panel.locator("button.fit").click()
        # the buttons follow at once (before the server answers)
        assert panel.locator("button.fit").inner_text() == "Cancel fit"
        other = shown.locator("#entry-1 button.fit")
        assert other.is_disabled() and "running" in other.get_attribute("title")
        assert "at most 300 evaluations" in panel.locator(".output.fitted").inner_text()
        shown.wait_for_selector("#entry-3", timeout=120_000)
        settle(shown)
        assert not other.is_disabled() and other.inner_text() == "Fit"
        assert panel.locator(".output.fitted").inner_text().startswith(
            "cook_torrance: fit error")
    entries_drawn(shown, LABELS + [FITTED])
    state = json.loads(server.request("GET", "/api/state")[1])
    fit = next(e["fit"] for e in state["entries"] if e["label"] == FITTED)
    assert fit["relative_rms_max"] < 0.02 and fit["evaluations"] <= 300
    info = shown.locator("#entry-3 .fitinfo").inner_text()
    shown_error = info.split("relative RMS of f cos ")[1].split(" ")[0]
    assert float(shown_error) == pytest.approx(fit["relative_rms_max"], rel=1e-2)
    assert "cook_torrance fitted to gold.binary" in info and "held-out samples" in info
    assert f"{fit['evaluations']} evaluations in" in info and "at most 300" in info
    assert "1,000 of the file's" in info
    assert "the same fit as: python -m mitsuba_brdfs fit-measured " in info
    assert "--model cook_torrance --samples 1000 --evaluations 120 --seed 0" in info
    assert shown.locator("#entry-3 .controls .ctl").count() >= 5
    assert not cut_texts(shown)  # the fitted values (float32's digits) show whole
    shown.screenshot(path=str(tmp_path_factory.getbasetemp()
                              / f"explore_measured_fit_{shown.width}.png"), full_page=True)


def test_a_fit_cancelled_in_the_page(page, folder):
    """"Cancel fit" stops the fit after the evaluation under way: nothing is added. (The
    MERL file's, whose samples the page's first fit read: its data are not read again.)"""
    before = page.locator("#entries .entry").count()
    panel = page.locator("#entry-0")
    panel.locator("select").select_option("cook_torrance")
    (folder / "armed").write_text("")
    try:
        panel.locator("button.fit").click()
        assert panel.locator("button.fit").inner_text() == "Cancel fit"
        panel.locator("button.fit").click()
        page.wait_for_function("() => document.querySelector('#entry-0 .output.fitted')"
                               ".textContent.startsWith('cancelling')")
    finally:
        (folder / "open").write_text("")
    page.wait_for_function("() => document.querySelector('#entry-0 .output.fitted')"
                           ".textContent === 'fit cancelled'", timeout=120_000)
    assert panel.locator("button.fit").inner_text() == "Fit"
    assert page.locator("#entries .entry").count() == before
    os.remove(folder / "armed")
    os.remove(folder / "open")
    assert not page.errors, page.errors
