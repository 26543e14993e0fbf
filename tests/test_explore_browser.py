"""The explorer's page in a real headless browser (Debian's chromium, driven by Playwright).

The command is started as a user starts it (``python -m mitsuba_brdfs explore ... --port 0
--no-browser``) with four BSDFs, one of them from an XML file, and the page opened at the
printed address (with its token), under the server's Content-Security-Policy. The page is
observed as a user sees it, through its DOM, Plotly's data on the plot elements and its
network traffic: it has no hooks for tests. One server, one browser and one page serve the
module: the layout's tests look at the page first (at 1400 px, then with the window made
1024 px wide), then the controls' tests change it in turn.

- every card at 1400 and 1024 px: drawn, nothing clipped, no legend over an axis title,
  no truncated name or value, no horizontal scrollbar, log scales, the slices' colour scale;
- the controls: a parameter typed redraws its BSDF only, a value out of range is refused in
  the page, paired parameters set one at a time, add / export / remove, the check one at a
  time and cancelled, the export and the check each in its own area;
- what a hostile page can do: nothing (another origin's POST, a DNS-rebinding name).

Screenshots of both widths are written to pytest's temporary folder."""
import contextlib
import io
import json
import os
import threading
from http.server import BaseHTTPRequestHandler, HTTPServer

import pytest

import user_bsdf
from explore_page import CHROMIUM, Server, launch, open_page, plotted, resize, settle, traces
from mitsuba_brdfs.__main__ import main

pytest.importorskip("starlette")
playwright = pytest.importorskip("playwright.sync_api")

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(CHROMIUM is None, reason="no chromium (scripts/bootstrap.sh "
                                                          "installs Debian's)")]

#: the user's plugin (``user_bsdf``) as ``gated``: its methods wait while the file ARMED
#: exists and OPEN does not, so a check of it runs until the test lets it go
GATE = """
import os, time

def HOOK():
    while os.path.exists({armed!r}) and not os.path.exists({open!r}):
        time.sleep(0.01)
"""


#: a BSDF's name with markup, as a user's XML file may give it
MARKUP = '<a href="https://evil.example/">x</a><b>B</b> & co'


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """The folder served: nickel.xml (the Ngan et al. ward preset, as ``presets show``
    writes it), gated.py, named.xml (a lambert named ``MARKUP``)."""
    d = tmp_path_factory.mktemp("explore_page")
    xml = io.StringIO()
    with contextlib.redirect_stdout(xml):
        assert main(["presets", "show", "nickel", "--model", "ward", "--xml"]) == 0
    (d / "nickel.xml").write_text(xml.getvalue())
    user_bsdf.write(d / "gated.py", "gated",
                    hook=GATE.format(armed=str(d / "armed"), open=str(d / "open")))
    (d / "named.xml").write_text('<bsdf version="3.0.0" type="lambert" id="' + MARKUP.replace(
        "&", "&amp;").replace("<", "&lt;").replace('"', "&quot;") + '"/>')
    return d


LABELS = ["ward (nickel.xml)", "ashikhmin_shirley", "roughplastic", "cook_torrance"]


@pytest.fixture(scope="module")
def server(folder):
    """One server for the module, serving ``folder``."""
    server = Server(str(folder / "nickel.xml"), "ashikhmin_shirley", "roughplastic",
                    "cook_torrance", "-p", "ashikhmin_shirley:nu=20",
                    "-p", "ashikhmin_shirley:nv=1000", "--load", str(folder / "gated.py"),
                    cwd=str(folder))
    yield server
    assert server.stop() == 130


@pytest.fixture(scope="module")
def browser():
    """One chromium for the module (Playwright's sync API runs one at a time), where the
    name evil.example.com resolves to this machine, as a DNS-rebinding attacker makes it."""
    with playwright.sync_playwright() as p:
        b = launch(p, "--host-resolver-rules=MAP evil.example.com 127.0.0.1")
        yield b
        b.close()


@pytest.fixture(scope="module")
def page(browser, server):
    """The page at 1400 px, for the whole module; what it logs is kept (``open_page``)."""
    page = open_page(browser, server)
    yield page
    page.context.close()


# -- the layout of every card, at two widths ---------------------------------------------------

@pytest.fixture(scope="module", params=[1400, 1024])
def shown(request, page, tmp_path_factory):
    """The page at rest at a width, and its screenshot; no error in its console."""
    resize(page, request.param)
    page.screenshot(path=str(tmp_path_factory.getbasetemp() / f"explore_{request.param}.png"),
                    full_page=True)
    yield page
    assert not page.errors, page.errors


def overlaps(page, div):
    """The texts of a Plotly plot that its legend covers, and those outside the plot."""
    return page.evaluate("""(div) => {
      const gd = document.getElementById(div), box = gd.getBoundingClientRect();
      const leg = gd.querySelector('.legend').getBoundingClientRect();
      const hit = (r, s) => !(r.right <= s.left || r.left >= s.right || r.bottom <= s.top ||
                              r.top >= s.bottom);
      const texts = [...gd.querySelectorAll('text')].filter((t) => t.textContent.trim() &&
        t.getBoundingClientRect().width > 0);
      return {
        covered: texts.filter((t) => !t.closest('.legend') && hit(t.getBoundingClientRect(), leg))
          .map((t) => t.textContent),
        outside: texts.filter((t) => { const r = t.getBoundingClientRect();
          return r.left < box.left - 1 || r.right > box.right + 1 || r.top < box.top - 1 ||
                 r.bottom > box.bottom + 1; }).map((t) => t.textContent),
      };
    }""", div)


def test_polar_card(shown):
    assert traces(shown, "polar", "name") == LABELS + ["incidence"]
    assert len(set(traces(shown, "polar", "line.color"))) == 5
    assert overlaps(shown, "polar") == {"covered": [], "outside": []}


def test_lobe_card_is_not_clipped(shown):
    """The 3D scene's drawing (axes, ticks, titles) stays inside its viewport: the rows and
    columns along its edges are blank. Its log scale shows the small lobes."""
    assert traces(shown, "lobe", "name") == LABELS
    rect = shown.evaluate("""() => { const gd = document.getElementById('lobe');
      const s = gd._fullLayout._size, d = gd._fullLayout.scene.domain;
      return [s.l + d.x[0] * s.w, s.t + (1 - d.y[1]) * s.h, s.l + d.x[1] * s.w,
              s.t + (1 - d.y[0]) * s.h]; }""")
    import io
    import numpy as np
    from PIL import Image
    shown.mouse.move(0, 0)  # no toolbar shown over the plot
    img = np.asarray(Image.open(io.BytesIO(shown.locator("#lobe").screenshot())).convert("L"))
    x0, y0, x1, y1 = (int(round(v)) for v in rect)
    scene = img[y0:y1, x0:x1]
    edges = np.concatenate([scene[:3].ravel(), scene[-3:].ravel(), scene[:, :3].ravel(),
                            scene[:, -3:].ravel()])
    assert edges.min() > 235, "the 3D scene is drawn up to its edge: clipped"
    legend = shown.evaluate("document.querySelector('#lobe .legend').getBoundingClientRect()"
                            ".top - document.getElementById('lobe').getBoundingClientRect().top")
    assert legend >= y1 - 1, "the legend covers the 3D scene"
    # the log scale: radii of the decades above 1e-4 of the largest, so the weak lobes grow
    ratio = ("(() => { const d = document.getElementById('lobe').data;"
             " const r = (t) => Math.max(...t.x.map((x, i) => Math.hypot(x, t.y[i], t.z[i])));"
             " return r(d[2]) / r(d[0]); })()")
    linear = shown.evaluate(ratio)
    shown.locator("#log-lobe").check()
    log = shown.evaluate(ratio)
    shown.locator("#log-lobe").uncheck()
    assert log > 3 * linear, (linear, log)


@pytest.mark.parametrize("div, card, key", [("slice-h", "theta-h", "theta_h"),
                                            ("slice-d", "theta-d", "theta_d")])
def test_slice_cards_have_log_scales(shown, div, card, key):
    """f against theta_h / theta_d on a log scale by default (a 4000 spike at grazing does
    not flatten the others), linear at a click; the legend covers no axis title."""
    assert traces(shown, div, "name") == LABELS
    layout = f"document.getElementById('{div}').layout.yaxis"
    assert shown.evaluate(f"{layout}.type") == "log"
    lo, hi = shown.evaluate(f"{layout}.range")
    values = [v for t in traces(shown, div, "y") for v in t if v]
    assert 10 ** lo <= sorted(values)[len(values) // 10] and 10 ** hi >= max(values)
    assert overlaps(shown, div) == {"covered": [], "outside": []}
    shown.locator(f"#log-{card}").uncheck()
    assert shown.evaluate(f"{layout}.type") == "linear"
    shown.locator(f"#log-{card}").check()


def test_albedo_card(shown):
    names = traces(shown, "albedo", "name")
    assert names[::2] == LABELS and len(names) == 8
    assert traces(shown, "albedo", "showlegend")[1::2] == [False] * 4  # one entry a BSDF
    assert overlaps(shown, "albedo") == {"covered": [], "outside": []}


def test_image_slices_card(shown):
    """A slice per BSDF with its axes, 0 at the lower left; one colour scale from 0 at the
    bottom to the value drawn white, which follows the exposure."""
    tiles = shown.locator("#images .tile")
    assert tiles.count() == 4
    assert [tiles.nth(k).locator(".cap").inner_text() for k in range(4)] == LABELS
    for k in range(4):
        t = tiles.nth(k)
        y = t.locator(".yticks span")
        x = t.locator(".xticks span")
        assert y.last.inner_text() == "0" and x.first.inner_text() == "0"
        assert y.last.bounding_box()["y"] > y.first.bounding_box()["y"]  # 0 at the bottom
        assert x.first.bounding_box()["x"] < x.last.bounding_box()["x"]  # 0 on the left
        assert "\u03b8d" in t.locator(".ytitle").inner_text()
        assert "\u03b8h" in t.locator(".xtitle").inner_text()
    ticks = shown.locator("#scale .ticks span")
    assert ticks.first.inner_text() == "0" and ticks.last.inner_text() == "\u2265 1"
    assert ticks.first.bounding_box()["y"] > ticks.last.bounding_box()["y"]
    shown.locator("#exposure").fill("1")
    assert shown.locator("#scale .ticks span").last.inner_text() == "\u2265 0.5"
    plotted(shown)
    shown.locator("#exposure").fill("0")
    settle(shown)


def test_spheres_card(shown):
    """Every sphere at its last pass, on a dark grey (its outline shows where it is
    unlit)."""
    import io
    import numpy as np
    from PIL import Image
    from mitsuba_brdfs.explore.sphere import BACKGROUND
    caps = shown.locator("#spheres .cap")
    assert [caps.nth(k).inner_text() for k in range(4)] == [f"{x} (32 spp)" for x in LABELS]
    assert shown.evaluate("[...document.querySelectorAll('#spheres img')].every("
                          "(i) => i.complete && i.naturalWidth === 192)")
    img = np.asarray(Image.open(io.BytesIO(shown.locator("#spheres img").first.screenshot()))
                     .convert("RGB")).astype(int)
    assert (np.abs(img[[2, 2, -3, -3], [2, -3, 2, -3]] - BACKGROUND) <= 2).all()
    assert img.max() > 4 * BACKGROUND


def test_sidebar_shows_names_and_values_whole(shown):
    """No horizontal scrollbar (page or sidebar); every parameter's name and every value
    (RGB triples included) shown whole; each label once."""
    assert shown.evaluate("document.documentElement.scrollWidth <= window.innerWidth")
    assert shown.evaluate("(() => { const s = document.getElementById('entries');"
                          " return s.scrollWidth <= s.clientWidth; })()")
    cut = shown.evaluate("""[...document.querySelectorAll('#entries .ctl .name, '
      + '#entries input[type=text], #entries .label, #entries select')]
      .filter((e) => e.scrollWidth > e.clientWidth + 1)
      .map((e) => e.textContent || e.value)""")
    assert not cut, cut
    labels = shown.locator("#entries .label")
    assert [labels.nth(k).inner_text() for k in range(4)] == LABELS
    rgb = shown.get_by_label("specular_reflectance", exact=True).first.input_value()
    assert rgb == "0.204, 0.154, 0.0946"
    # tooltips are plain text (no reStructuredText)
    titles = shown.evaluate("[...document.querySelectorAll('#entries [title]')].map(e => e.title)")
    assert titles and not [t for t in titles if "``" in t or ":math:" in t]


# -- the controls ------------------------------------------------------------------------------

@pytest.fixture
def controls(page):
    """The page, back at 1400 px, that the tests below change in turn (each makes no
    assumption on what the others changed); each checks the console's errors."""
    resize(page, 1400)
    return page


def polar_names(page, names):
    page.wait_for_function("(names) => JSON.stringify(document.getElementById('polar').data"
                           ".map((t) => t.name)) === JSON.stringify(names)", arg=names)


def test_controls_redraw_their_bsdf_and_refusals_are_said(controls):
    page = controls
    page.errors.clear()
    polar = "document.getElementById('polar').data[{}].r"
    before = [page.evaluate(polar.format(k)) for k in range(4)]
    nu = page.get_by_label("nu", exact=True)
    nu.fill("400")
    nu.press("Enter")
    plotted(page)
    after = [page.evaluate(polar.format(k)) for k in range(4)]
    assert after[0] == before[0] and after[2] == before[2] and after[1] != before[1]
    assert max(filter(None, after[1])) > 2 * max(filter(None, before[1]))
    # the incidence slider moves the specular peaks
    page.locator("#theta-i").fill("70")
    plotted(page)
    assert traces(page, "polar")[4]["theta"][0] == -70
    page.locator("#theta-i").fill("45")
    plotted(page)
    assert not page.errors, page.errors
    # a value out of range: refused in the page, the server's value shown again
    nu.fill("-5")
    nu.press("Enter")
    page.wait_for_function(
        "() => document.querySelector('#entry-1 .error').textContent.includes('[0, 1e6]')")
    assert nu.input_value() == "400"
    settle(page)
    assert page.errors == ["Failed to load resource: the server responded with a status of "
                           "400 (Bad Request)"], page.errors
    page.errors.clear()


def test_paired_parameters_from_the_page(controls):
    """alpha_u typed alone: alpha_v takes it, the exponents go out of use, the page says
    which parametrisation is in use; then alpha_v alone keeps alpha_u."""
    page = controls
    entry = page.locator("#entry-1")
    nu = entry.get_by_label("nu", exact=True)
    nu.fill("50")
    nu.press("Enter")
    plotted(page)
    page.wait_for_function("() => document.querySelector('#entry-1 .param').textContent"
                           ".startsWith('in use: nu, nv')")
    assert "inactive" in entry.locator(".ctl[data-name=alpha_u]").get_attribute("class")
    before = traces(page, "polar")[1]["r"]
    au = entry.get_by_label("alpha_u", exact=True)
    au.fill("0.3")
    au.press("Enter")
    plotted(page)
    page.wait_for_function("() => document.querySelector('#entry-1 .param').textContent"
                           ".startsWith('in use: alpha_u + alpha_v')")
    assert entry.get_by_label("alpha_v", exact=True).input_value() == "0.3"
    assert "inactive" in entry.locator(".ctl[data-name=nu]").get_attribute("class")
    assert entry.locator(".error").inner_text() == ""
    assert traces(page, "polar")[1]["r"] != before
    av = entry.get_by_label("alpha_v", exact=True)
    av.fill("0.05")
    av.press("Enter")
    plotted(page)
    page.wait_for_function("() => document.querySelector('#entry-1 [aria-label=alpha_v]').value"
                           " === '0.05'")
    assert entry.get_by_label("alpha_u", exact=True).input_value() == "0.3"
    assert entry.locator(".error").inner_text() == ""
    page.locator("#entry-1 .actions button", has_text="Export").click()
    page.wait_for_selector("#entry-1 textarea")
    xml = page.locator("#entry-1 textarea").first.input_value()
    assert 'name="alpha_u" value="0.3"' in xml and 'name="alpha_v" value="0.05"' in xml
    assert 'name="nu"' not in xml
    assert not page.errors, page.errors


def test_add_export_remove_and_the_check_one_at_a_time(controls, folder, tmp_path_factory):
    """A BSDF added in the page and checked: while its check runs the others' Check buttons
    wait and the page says that one check runs at a time; "Cancel check" stops it. A check
    run to its end beside an export: each keeps its own area, both shown."""
    page = controls
    page.locator("#add-spec").fill("gated")
    page.locator("#add-form button").click()
    polar_names(page, LABELS + ["gated", "incidence"])
    page.get_by_label("draw gated").uncheck()  # not drawn: only the check calls it now
    polar_names(page, LABELS + ["incidence"])
    settle(page)
    (folder / "armed").write_text("")
    try:
        page.locator("#entry-4 button.check").click()
        page.wait_for_function("() => document.querySelector('#entry-4 button.check')"
                               ".textContent === 'Cancel check'")
        out = page.locator("#entry-4 .output.check")
        assert "One check runs at a time" in out.inner_text()
        other = page.locator("#entry-0 button.check")
        assert other.is_disabled() and "gated's is running" in other.get_attribute("title")
        page.locator("#entry-4 button.check").click()
        page.wait_for_function("() => document.querySelector('#entry-4 .output.check')"
                               ".textContent.startsWith('cancelling')")
    finally:
        (folder / "open").write_text("")
    page.wait_for_function("() => document.querySelector('#entry-4 .output.check')"
                           ".textContent === 'check cancelled'", timeout=120_000)
    assert not other.is_disabled() and other.inner_text() == "Check"
    os.remove(folder / "armed")
    os.remove(folder / "open")
    # a check that runs to its end, after an export: both shown, each in its own area
    entry = page.locator("#entry-2")
    entry.locator(".actions button", has_text="Export").click()
    page.wait_for_selector("#entry-2 .output.export textarea")
    entry.locator("button.check").click()
    page.wait_for_function("() => document.querySelector('#entry-2 .output.check b')",
                           timeout=120_000)
    assert entry.locator(".output.check b").inner_text() in ("PASS", "FAIL")
    assert entry.locator(".output.check tr").count() >= 5
    for area in (".output.export textarea", ".output.check table"):
        assert entry.locator(area).first.is_visible(), area
    assert 'type="roughplastic"' in entry.locator(".output.export textarea").first.input_value()
    entry.screenshot(path=str(tmp_path_factory.getbasetemp() / "explore_export_check.png"))
    page.get_by_label("remove gated").click()
    page.wait_for_function("() => !document.getElementById('entry-4')")
    polar_names(page, LABELS + ["incidence"])
    assert not page.errors, page.errors


def test_page_stays_local_and_has_no_cloud_button(page, server):
    """No toolbar button uploads a chart ("Share chart...", Chart Studio), and the page
    requested nothing outside the local server (every request since it opened)."""
    buttons = page.evaluate("[...document.querySelectorAll('.modebar-btn')]"
                            ".map(b => (b.getAttribute('data-title') || '') + '|'"
                            " + (b.getAttribute('href') || ''))")
    links = page.evaluate("[...document.querySelectorAll('a[href^=http]')].map(a => a.href)")
    assert buttons, "no Plotly toolbar found"
    assert not [b for b in buttons if "share" in b.lower() or "cloud" in b.lower()
                or "chart studio" in b.lower() or "plotly.com" in b]
    assert not [u for u in links if not u.startswith("http://127.0.0.1")]
    outside = [u for u in page.requests
               if not u.startswith(("http://127.0.0.1:", "blob:", "data:"))]
    assert any("/api/sphere/" in u for u in page.requests) and not outside, outside
    # without its token the page loads and says what is missing
    bare = page.context.browser.new_page()
    bare.goto(server.url.split("?")[0])
    bare.wait_for_function("() => document.getElementById('status').textContent"
                           ".includes('token')")
    bare.context.close()


# -- what a hostile page can do --------------------------------------------------------------

class _Hostile(BaseHTTPRequestHandler):
    """Another site's page: it posts to the explorer as any page may, without asking."""
    target = ""

    def do_GET(self):  # noqa: N802 (http.server's name)
        page = f"""<!doctype html><script>
          fetch({json.dumps(self.target)}, {{method: "POST", mode: "no-cors",
            headers: {{"Content-Type": "text/plain"}}, body: '{{"spec": "ward"}}'}})
            .then(() => document.title = "sent", () => document.title = "sent");
        </script>"""
        self.send_response(200)
        self.send_header("Content-Type", "text/html")
        self.end_headers()
        self.wfile.write(page.encode())

    def log_message(self, *args):
        pass


def labels(server):
    status, body = server.request("GET", "/api/state")
    assert status == 200
    return [e["label"] for e in json.loads(body)["entries"]]


def test_a_hostile_page_changes_nothing(browser, server):
    """Another origin's page sends a simple POST (text/plain, its own Origin) with the token
    even: nothing is added. A DNS-rebinding name (evil.example.com resolving to 127.0.0.1)
    reads nothing: the Host is refused, page and API."""
    before = labels(server)
    hostile = HTTPServer(("127.0.0.1", 0), _Hostile)
    _Hostile.target = f"http://127.0.0.1:{server.port}/api/entries"
    threading.Thread(target=hostile.serve_forever, daemon=True).start()
    page = browser.new_page()
    try:
        page.goto(f"http://127.0.0.1:{hostile.server_port}/")
        page.wait_for_function("() => document.title === 'sent'")
        # the same with the token in the address, as if it had leaked
        _Hostile.target += f"?token={server.token}"
        page.goto(f"http://127.0.0.1:{hostile.server_port}/")
        page.wait_for_function("() => document.title === 'sent'")
        # DNS rebinding: the attacker's name, now resolving to the explorer
        rebound = page.goto(f"http://evil.example.com:{server.port}/?token={server.token}")
        assert rebound.status == 403 and b"not this server's address" in rebound.body()
        answer = page.evaluate("fetch('/api/state?token=' + new URLSearchParams("
                               "location.search).get('token')).then(r => r.status)")
        assert answer == 403
    finally:
        page.context.close()
        hostile.shutdown()
    assert labels(server) == before


def test_a_name_with_markup_is_shown_as_written(controls):
    """A BSDF's name comes from the user's XML file (named.xml, added from the page);
    Plotly reads tags in its texts (an <a href> becomes a link to another site): the plots
    show the name as written."""
    page = controls
    page.locator("#add-spec").fill("named.xml")
    page.locator("#add-form button").click()
    escaped = MARKUP.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    polar_names(page, LABELS + [f"{escaped} (named.xml)", "incidence"])
    settle(page)
    links = page.evaluate("[...document.querySelectorAll('#plots a')].map((a) => "
                          "a.getAttribute('href') || a.getAttribute('xlink:href') || '')")
    assert not [u for u in links if "evil.example" in u], links
    legend = page.evaluate("[...document.querySelectorAll('#polar .legendtext')]"
                           ".map((t) => t.textContent)")
    assert f"{MARKUP} (named.xml)" in legend, legend
    page.get_by_label(f"remove {MARKUP} (named.xml)").click()
    polar_names(page, LABELS + ["incidence"])
    assert not page.errors, page.errors


def test_the_page_works_under_its_content_security_policy(page):
    """The page ran under the policy the server sends (this server's scripts, styles,
    images and requests only; no string evaluated as script) through every test of the
    module: every plot and sphere is drawn and the browser reported no violation."""
    settle(page)
    drawn = page.evaluate("['polar', 'lobe', 'slice-h', 'slice-d', 'albedo'].map((d) => "
                          "(document.getElementById(d).data || []).length)")
    assert min(drawn) >= len(LABELS), drawn
    assert page.evaluate("[...document.querySelectorAll('#spheres img')].filter((i) => "
                         "i.naturalWidth > 0).length") == len(LABELS)
    assert page.logged and not [t for t in page.logged if "Content Security Policy" in t
                                or "Refused to" in t], page.logged
