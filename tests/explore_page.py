"""Driving the explorer from tests as its users do: the command started as a user starts it
(``python -m mitsuba_brdfs explore ... --port 0 --no-browser``), requests sent over HTTP as
a script or a hostile page sends them, and the page in Debian's headless chromium
(Playwright) under the server's Content-Security-Policy, observed through its DOM and its
network traffic only."""
import http.client
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
from urllib.parse import urlsplit

CHROMIUM = next((p for p in (shutil.which("chromium"), shutil.which("chromium-browser"),
                             "/usr/bin/chromium") if p and os.path.exists(p)), None)
#: the flags of a headless chromium that reaches nothing but what the test serves
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu",
                 "--disable-background-networking"]


class Server:
    """``python -m mitsuba_brdfs explore ARGS`` in its own process (in the folder ``cwd``,
    the one it serves): its printed address (``url``, with the token), ``port``,
    ``token``; ``stderr()`` what it wrote there (to a file: a pipe nobody reads would
    block it once full)."""

    def __init__(self, *args, cwd=None):
        self.err = tempfile.TemporaryFile(mode="w+")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "mitsuba_brdfs", "explore", *args, "--port", "0",
             "--no-browser"], stdout=subprocess.PIPE, stderr=self.err, text=True, cwd=cwd)
        line = self.proc.stdout.readline()
        m = re.search(r"(http://\S+)", line)
        if not m:
            self.proc.kill()
            self.proc.wait()
            raise AssertionError(line + self.stderr())
        self.url = m.group(1)
        parts = urlsplit(self.url)
        self.host, self.port = parts.hostname, parts.port
        self.token = re.search(r"token=([\w-]+)", parts.query).group(1)
        self.line = line

    def request(self, method, path, body=None, headers=None, timeout=120):
        """(status, body bytes) of one request over its own connection. ``headers``
        replace the page's (Host, the token, JSON, the page's Origin); a None value
        leaves that header out."""
        base = {"Host": f"{self.host}:{self.port}", "Authorization": f"token {self.token}",
                "Content-Type": "application/json",
                "Origin": f"http://{self.host}:{self.port}"}
        base.update(headers or {})
        conn = http.client.HTTPConnection(self.host, self.port, timeout=timeout)
        try:
            conn.putrequest(method, path, skip_host=True, skip_accept_encoding=True)
            for k, v in base.items():
                if v is not None:
                    conn.putheader(k, v)
            data = body if isinstance(body, bytes) or body is None else body.encode()
            conn.putheader("Content-Length", str(len(data or b"")))
            conn.endheaders(data)
            r = conn.getresponse()
            return r.status, r.read()
        finally:
            conn.close()

    def raw(self, data, timeout=30):
        """What the server answers to ``data`` sent as is on a socket (b"" if it closes)."""
        with socket.create_connection((self.host, self.port), timeout=timeout) as s:
            try:
                s.sendall(data)
                s.shutdown(socket.SHUT_WR)
            except OSError:  # it answered and closed before reading everything
                pass
            chunks = []
            try:
                while chunk := s.recv(65536):
                    chunks.append(chunk)
            except OSError:
                pass
        return b"".join(chunks)

    def stderr(self):
        self.err.seek(0)
        return self.err.read()

    def rss_mb(self):
        """The server's resident memory (MB)."""
        with open(f"/proc/{self.proc.pid}/status") as f:
            kb = next(int(ln.split()[1]) for ln in f if ln.startswith("VmRSS:"))
        return kb / 1024

    def stop(self):
        """Ctrl-C, as a user stops it; its exit status (130)."""
        if os.environ.get("PROBE_CPU"):
            with open(f"/proc/{self.proc.pid}/stat") as f:
                parts = f.read().rsplit(")", 1)[1].split()
            print("\nSERVER CPU", (int(parts[11]) + int(parts[12])) / os.sysconf("SC_CLK_TCK"))
        self.proc.send_signal(signal.SIGINT)
        try:
            return self.proc.wait(timeout=30)
        finally:
            self.proc.stdout.close()


def launch(playwright, *extra):
    """Debian's chromium, headless, through Playwright (``extra``: more flags)."""
    return playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS + list(extra))


# -- the page in the browser ---------------------------------------------------------------

#: the page at rest: its plots drawn (``#plots`` no longer aria-busy) and every sphere at
#: its last pass (``#spheres`` no longer aria-busy). Waits are given functions, not
#: strings: the server's Content-Security-Policy forbids evaluating strings as script,
#: and the page is opened under it
SETTLED = ("() => document.querySelector('#plots').getAttribute('aria-busy') === 'false' && "
           "document.querySelector('#spheres').getAttribute('aria-busy') === 'false'")


def open_page(browser, server, width=1400, height=900):
    """The printed address in a new context of ``browser`` (``launch``), under the
    server's Content-Security-Policy, once the page is at rest. What it logs is kept:
    ``page.errors`` (its console's errors, its uncaught exceptions), ``page.logged``
    (every console message), ``page.requests`` (every URL it asked for)."""
    page = browser.new_page(viewport={"width": width, "height": height})
    page.errors, page.logged, page.requests = [], [], []
    page.on("console", lambda m: (page.logged.append(m.text),
                                  m.type == "error" and page.errors.append(m.text)))
    page.on("pageerror", lambda e: page.errors.append(str(e)))
    page.on("request", lambda r: page.requests.append(r.url))
    page.goto(server.url)
    settle(page)
    return page


def settle(page, timeout=120_000):
    page.wait_for_function(SETTLED, timeout=timeout)


def plotted(page):
    """Wait for the plots to be drawn again after a change (#plots aria-busy, then not)."""
    page.wait_for_function("() => document.querySelector('#plots').getAttribute('aria-busy') "
                           "=== 'false'", timeout=60_000)


def resize(page, width, height=900):
    """The window made ``width`` px wide, as a user drags it: once every plot has followed
    (Plotly's responsive plots redraw at their new size) and the page is at rest."""
    if page.viewport_size == {"width": width, "height": height}:
        return
    page.set_viewport_size({"width": width, "height": height})
    page.wait_for_function("""() => [...document.querySelectorAll('.js-plotly-plot')].every(
      (gd) => gd._fullLayout && Math.abs(gd._fullLayout.width - gd.clientWidth) <= 1)""",
                           timeout=60_000)
    settle(page)


def traces(page, div, key=None):
    """The traces of a Plotly plot (its ``data``, which Plotly keeps on the element)."""
    expr = f"document.getElementById('{div}').data"
    if key:
        expr += f".map((t) => t.{key})"
    return page.evaluate(expr)


# -- measured files the tests write ----------------------------------------------------------

#: the RGL file's source, and the small resolution it is written at (83 kB)
RGL_SOURCE = ["ward", "-p", "specular_reflectance=0.3,0.2,0.1",
              "-p", "diffuse_reflectance=0.2,0.3,0.5", "-p", "alpha_u=0.15",
              "-p", "alpha_v=0.15"]
RGL_RESOLUTION = ["--theta-i", "8", "--grid", "24", "--vndf", "16", "--ndf", "32"]
#: the MERL file: Ngan et al.'s Cook-Torrance fit of gold-paint, at 30 x 30 x 60 bins (1.3 MB)
MERL_DIMS = (30, 30, 60)


def measured_files(folder):
    """(an RGL file, a MERL file) written into ``folder`` as a user writes them: ``to-rgl``
    of a ``ward`` at a small resolution, and a MERL file of a Cook-Torrance BRDF
    (``checks.merl_file``)."""
    import contextlib
    import io
    from checks import merl_file
    from mitsuba_brdfs import presets
    from mitsuba_brdfs.__main__ import main
    rgl, binary = os.path.join(folder, "ward.bsdf"), os.path.join(folder, "gold.binary")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        status = main(["to-rgl", *RGL_SOURCE, *RGL_RESOLUTION, "--no-compare", "-o", rgl])
    assert status == 0
    merl_file(binary, presets.ngan2005("cook_torrance", "gold-paint"), MERL_DIMS)
    return rgl, binary
