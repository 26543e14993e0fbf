"""Only the page that ``explore`` served can use it: requests as a hostile page sends them
(another site's simple POST, a DNS-rebinding name in ``Host``), scripts without the token,
oversized and malformed bodies. Each refusal is a 4xx with one line saying why, and nothing
changed. (In the browser: tests/test_explore_browser.py; over a thousand random requests:
tests/test_explore_fuzz.py.)"""
import contextlib
import json
import socket
import threading
import time

import pytest

pytest.importorskip("starlette")
pytest.importorskip("httpx2")
from starlette.testclient import TestClient  # noqa: E402

from explore_page import Server  # noqa: E402
from mitsuba_brdfs import variant  # noqa: E402
from mitsuba_brdfs.explore.entries import make_entries  # noqa: E402
from mitsuba_brdfs.explore.guard import MAX_BODY  # noqa: E402
from mitsuba_brdfs.explore.server import app  # noqa: E402
from mitsuba_brdfs.explore.session import MAX_ENTRIES, PALETTE, Explorer  # noqa: E402

TOKEN = "s3cret-token"
PAGE = "http://127.0.0.1:8765"
OURS = {"Authorization": f"token {TOKEN}", "Origin": PAGE, "Content-Type": "application/json"}


@pytest.fixture
def client():
    found = make_entries("lambert", {}, 0, PALETTE)
    found += make_entries("ashikhmin_shirley", {}, 1, PALETTE)
    return TestClient(app(Explorer(found), "127.0.0.1", 8765, TOKEN), base_url=PAGE)


def _state(client):
    r = client.get("/api/state", headers=OURS)
    assert r.status_code == 200, r.text
    return r.json()


def _refused(r, status, *words):
    assert r.status_code == status, (r.status_code, r.text)
    error = r.json()["error"]
    assert "\n" not in error and all(w in error for w in words), error


def test_a_foreign_host_is_refused_dns_rebinding(client):
    """A name of an attacker's that resolves to 127.0.0.1 makes the browser send it as
    Host: refused for the page and the API alike, even with the token."""
    for path in ("/", "/api/state", "/api/export/1", "/static/main.js"):
        r = client.get(path, headers={**OURS, "Host": "evil.example.com:8765"})
        _refused(r, 403, "evil.example.com", "not this server's address")
    _refused(client.get("/api/state", headers={**OURS, "Host": "127.0.0.1:9999"}), 403)
    _refused(client.get("/api/state", headers={**OURS, "Host": "127.0.0.1.evil.com:8765"}), 403)
    for host in ("127.0.0.1:8765", "localhost:8765", "LOCALHOST:8765", "[::1]:8765"):
        assert client.get("/api/state", headers={**OURS, "Host": host}).status_code == 200
    # two Host headers (a browser sends one; a parser may keep either): refused
    for hosts in (["evil.example.com:8765", "127.0.0.1:8765"],
                  ["127.0.0.1:8765", "evil.example.com:8765"]):
        headers = [(k, v) for k, v in OURS.items()] + [("Host", h) for h in hosts]
        _refused(client.get("/api/state", headers=headers), 400, "more than one Host")


def test_another_sites_simple_post_changes_nothing(client):
    """What any web page can send without asking: a POST with Content-Type text/plain and
    its own Origin. Neither adds a BSDF, with or without the token."""
    before = _state(client)
    body = json.dumps({"spec": "ward"})
    for headers in ({"Content-Type": "text/plain", "Origin": "http://evil.example.com"},
                    {**OURS, "Content-Type": "text/plain", "Origin": "http://evil.example.com"},
                    {**OURS, "Content-Type": "text/plain"},
                    {**OURS, "Content-Type": "application/x-www-form-urlencoded"},
                    {**OURS, "Origin": "http://evil.example.com"},
                    {**OURS, "Content-Type": "application/json", "Origin": "null"},
                    {**OURS, "Content-Type": "application/json", "Sec-Fetch-Site": "cross-site"}):
        r = client.post("/api/entries", content=body, headers=headers)
        assert r.status_code == 403 and r.json()["error"].startswith("refused: "), r.text
    for method, path, payload in (("PATCH", "/api/entries/1", {"name": "nu", "value": 5}),
                                  ("DELETE", "/api/entries/0", None),
                                  ("POST", "/api/check/0", {})):
        r = client.request(method, path, json=payload,
                           headers={**OURS, "Origin": "http://evil.example.com"})
        _refused(r, 403, "another site", "evil.example.com")
    assert _state(client) == before
    # the page's own request (same origin, JSON) is taken
    r = client.post("/api/entries", content=body, headers=OURS)
    assert r.status_code == 200 and r.json()[0]["label"] == "ward"


def test_the_api_asks_for_the_token(client):
    """Scripts pass the token as the page does: ``?token=`` or ``Authorization: token``.
    The page and its scripts hold no data and are served without it."""
    for headers in ({}, {"Authorization": "token wrong"}, {"Authorization": f"Bearer {TOKEN}"}):
        _refused(client.get("/api/state", headers=headers), 403, "token", "explore printed")
    _refused(client.get("/api/state?token=wrong"), 403, "token")
    assert client.get(f"/api/state?token={TOKEN}").status_code == 200
    r = client.get("/api/export/1", headers={"Authorization": f"token {TOKEN}"})
    assert r.status_code == 200
    assert client.get("/").status_code == 200 and client.get("/static/main.js").status_code == 200


def test_every_answer_keeps_the_page_to_itself(client):
    """The page's address holds the token: no Referer takes it to another site, and the
    page's scripts, styles, images and requests are this server's only (an injected script
    could not send the token out); no other site may frame it. (In the browser, the page
    works under these: tests/test_explore_browser.py, whose pages log no violation.)"""
    for r in (client.get("/"), client.get("/static/main.js"),
              client.get("/api/state", headers=OURS), client.get("/api/state"),
              client.get("/api/nothing", headers=OURS)):
        policy = r.headers["content-security-policy"]
        assert "default-src 'self'" in policy and "connect-src 'self'" in policy
        assert "frame-ancestors 'none'" in policy and "unsafe-eval" not in policy
        assert r.headers["referrer-policy"] == "no-referrer"
        assert r.headers["x-content-type-options"] == "nosniff"


def test_a_body_over_the_limit_is_refused(client):
    before = _state(client)
    r = client.post("/api/plots", content=b" " * (MAX_BODY + 1), headers=OURS)
    _refused(r, 413, str(MAX_BODY))
    assert client.post("/api/plots", content=b" " * 1000 + b"{}", headers=OURS).status_code == 200
    assert _state(client) == before


@pytest.mark.parametrize("method, path, body, status, words", [
    ("POST", "/api/plots", b"[" * 10_000 + b"]" * 10_000, 400, ["nested too deeply"]),
    ("POST", "/api/plots", b'{"theta_i": ' + b"1" * 400 + b"}", 400, ["theta_i", "[0, 89.9]"]),
    ("POST", "/api/plots", b'{"theta_i": ' + b"1" * 5000 + b"}", 400, ["not JSON"]),
    ("POST", "/api/plots", b'{"theta_i": NaN}', 400, ["NaN", "JSON"]),
    ("POST", "/api/plots", b'{"theta_i": "45"}', 400, ["theta_i", "a number"]),
    ("POST", "/api/plots", b'{"theta_i": true}', 400, ["theta_i", "a number"]),
    ("POST", "/api/plots", b'{"set": {"id": [0]}}', 400, ['set must be {"id", "name", "value"}']),
    ("POST", "/api/plots", b'{"set": {"id": [0], "name": "nu", "value": 1}}', 400,
     ["a BSDF is named by its number"]),
    ("POST", "/api/plots", b'{"set": {"id": 0, "name": ["nu"], "value": 1}}', 400, ["name"]),
    ("POST", "/api/plots", b'{"set": {"id": 9, "name": "nu", "value": 1}}', 404, ["no BSDF 9"]),
    ("POST", "/api/plots", b'{"thetai": 30}', 400, ["unknown field 'thetai'", "theta_i"]),
    ("POST", "/api/plots", b'{"parts": "polar"}', 400, ["parts must be a list"]),
    ("POST", "/api/plots", b'{"ids": [true]}', 400, ["ids"]),
    ("POST", "/api/plots", b"\xff\xfe\x00garbage", 400, ["not JSON"]),
    ("POST", "/api/plots", b"[1, 2]", 400, ["JSON object"]),
    ("PATCH", "/api/entries/0", b'{"visible": "no"}', 400, ["visible must be true or false"]),
    ("PATCH", "/api/entries/0", b'{"colour": {"r": 1}}', 400, ["colour must be a colour #rrggbb"]),
    ("PATCH", "/api/entries/0", b'{"colour": "' + b"x" * (1 << 19) + b'"}', 400, ["#rrggbb"]),
    ("PATCH", "/api/entries/0", b'{"colour": "red; background: url(x)"}', 400, ["#rrggbb"]),
    ("PATCH", "/api/entries/0", b'{"name": "reflectance", "value": {"type": "rgb"}}', 400,
     ["value must be"]),
    ("PATCH", "/api/entries/0", b'{"name": "reflectance", "value": [1, 2, 3, 4]}', 400,
     ["value must be"]),
    ("PATCH", "/api/entries/0", b'{"name": "reflectance", "value": [0.1, NaN, 0]}', 400, ["NaN"]),
    ("PATCH", "/api/entries/0", b'{"name": "reflectance", "value": "0.1, nan, 0"}', 400,
     ["reflectance", "[0, 1]"]),
    ("PATCH", "/api/entries/0", b'{"value": 0.3}', 400, ['"name"']),
    ("PATCH", "/api/entries/0", b"{}", 400, ["nothing to change"]),
    ("PATCH", "/api/entries/abc", b'{"visible": true}', 400, ["a BSDF is named by its number"]),
    ("PATCH", "/api/entries/99", b'{"visible": true}', 404, ["no BSDF 99"]),
    ("POST", "/api/entries", b'{"spec": 3}', 400, ["spec must be a string"]),
    ("POST", "/api/entries", b'{"spec": "no_such_plugin"}', 400, ["unknown plugin"]),
    ("POST", "/api/entries", b'{"spec": "x\\u0000.xml"}', 400, ["not a plugin name"]),
    ("POST", "/api/entries", b'{"spec": "a\\u0000b"}', 400, ["not a plugin name"]),
    ("POST", "/api/entries", b'{"spec": "\\ud800"}', 400, ["not a plugin name"]),
    ("POST", "/api/entries", b'{"spec": "scenes/\\ud800.xml"}', 400, ["not a plugin name"]),
    ("GET", "/api/sphere/0?theta=nan", None, 400, ["theta must be a number in [0, 180]"]),
    ("GET", "/api/sphere/0?pass=x", None, 400, ["pass must be an integer"]),
    ("GET", "/api/sphere/0?pass=" + "9" * 400, None, 400, ["pass must be an integer"]),
    ("GET", "/api/sphere/0?theta=1e400", None, 400, ["theta", "[0, 180]"]),
    ("GET", "/api/sphere/0?colour=red", None, 400, ["unknown query parameter 'colour'"]),
    ("GET", "/api/sphere/7", None, 404, ["no BSDF 7"]),
    ("GET", "/api/nothing", None, 404, ["no such address"]),
    ("PUT", "/api/state", b"{}", 405, ["PUT"]),
])
def test_malformed_requests_get_a_4xx_and_change_nothing(client, method, path, body,
                                                          status, words):
    before = _state(client)
    r = client.request(method, path, content=body, headers={**OURS, "Content-Type":
                                                            "application/json"})
    _refused(r, status, *words)
    assert _state(client) == before


def test_the_entries_are_bounded(client):
    for _ in range(MAX_ENTRIES - 2):
        r = client.post("/api/entries", json={"spec": "lambert"}, headers=OURS)
        assert r.status_code == 200
    r = client.post("/api/entries", json={"spec": "lambert"}, headers=OURS)
    _refused(r, 400, f"at most {MAX_ENTRIES} BSDFs", "remove one first")
    assert len(_state(client)["entries"]) == MAX_ENTRIES


def test_beyond_loopback_warns_and_takes_the_machines_addresses():
    """``--host 0.0.0.0``: a warning; the printed address works; an IP address in Host is
    taken (DNS rebinding needs a name), an unknown name is not."""
    server = Server("lambert", "--host", "0.0.0.0")
    try:
        assert server.host == "127.0.0.1" and "?token=" in server.url
        status, body = server.request("GET", f"/api/state?token={server.token}",
                                      headers={"Authorization": None})
        assert status == 200 and json.loads(body)["entries"][0]["label"] == "lambert"
        assert server.request("GET", "/api/state",
                              headers={"Host": f"10.1.2.3:{server.port}"})[0] == 200
        status, body = server.request("GET", "/api/state",
                                      headers={"Host": f"evil.example.com:{server.port}"})
        assert status == 403 and b"not this server's address" in body
        assert server.request("GET", "/api/state", headers={"Authorization": None})[0] == 403
    finally:
        assert server.stop() == 130
    err = server.stderr()
    assert "warning: --host 0.0.0.0 serves beyond this machine" in err and "token" in err


def _head(server, extra):
    return (f"POST /api/plots HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\n"
            f"Authorization: token {server.token}\r\nContent-Type: application/json\r\n"
            + extra + "\r\n").encode()


def test_on_loopback_no_warning_and_big_bodies_are_not_read():
    """Over real HTTP: a body announced larger than the limit is refused before it is sent;
    one sent in chunks is refused as soon as it passes the limit, while its end has not
    been sent (were the server waiting for it, the socket would time out)."""
    server = Server("lambert")
    try:
        assert server.url.startswith("http://127.0.0.1:") and "/?token=" in server.url
        assert server.request("GET", f"/api/state?token={server.token}",
                              headers={"Authorization": None})[0] == 200
        reply = server.raw(_head(server, f"Content-Length: {100 * MAX_BODY}\r\n") + b"{",
                           timeout=30)
        assert reply.startswith(b"HTTP/1.1 413 "), reply[:200]
        chunk = b"10000\r\n" + b" " * 65536 + b"\r\n"  # no last chunk: never ends
        with socket.create_connection((server.host, server.port), timeout=30) as s:
            s.sendall(_head(server, "Transfer-Encoding: chunked\r\n"))
            for _ in range(MAX_BODY // 65536 + 1):  # just past the limit
                s.sendall(chunk)
            reply = b""
            while b"}" not in reply and (part := s.recv(4096)):
                reply += part
        assert reply.startswith(b"HTTP/1.1 413 ") and str(MAX_BODY).encode() in reply, reply
        assert server.request("POST", "/api/plots", b'{"parts": ["polar"]}')[0] == 200
    finally:
        assert server.stop() == 130
    assert "warning" not in server.stderr()


# -- connections that never finish a request -----------------------------------------------

class _SlowState(Explorer):
    """An explorer whose state takes ``delay`` seconds to answer (a long request)."""
    delay = 0.0

    def state(self):
        time.sleep(self.delay)
        return super().state()


@contextlib.contextmanager
def _serving(head_timeout, body_timeout):
    """The application served by uvicorn as ``explore`` serves it, in a thread, with short
    timeouts; yields (port, explorer)."""
    import uvicorn
    from mitsuba_brdfs.explore.command import bind
    from mitsuba_brdfs.explore.server import config
    sock = bind("127.0.0.1", 0)
    port = sock.getsockname()[1]
    explorer = _SlowState(make_entries("lambert", {}, 0, PALETTE))
    application = app(explorer, "127.0.0.1", port, TOKEN)
    application.body_timeout = body_timeout
    server = uvicorn.Server(config(application, head_timeout=head_timeout))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    try:
        deadline = time.monotonic() + 30
        while not server.started and time.monotonic() < deadline:
            time.sleep(0.01)
        yield port, explorer
    finally:
        server.should_exit = True
        thread.join(timeout=30)
        sock.close()


def _get_state(port, timeout=30):
    """(status, connection header) of the page's GET /api/state over a new connection."""
    import http.client
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    try:
        conn.request("GET", "/api/state", headers={"Authorization": f"token {TOKEN}"})
        r = conn.getresponse()
        r.read()
        return r.status
    finally:
        conn.close()


def _closed_by_server(s, deadline):
    """True once the server closed ``s`` (it reads end of file) before ``deadline``."""
    s.settimeout(max(0.01, deadline - time.monotonic()))
    try:
        while s.recv(4096):
            pass
        return True
    except OSError:  # the timeout: still open
        return False


def test_idle_and_trickling_connections_do_not_lock_the_page_out():
    """Connections that send no request, or its head a byte at a time, would otherwise be
    held for ever, and at the connection limit every further request (the page's) gets
    503: the server closes each once the head is late; a request that takes long to
    answer is not cut."""
    from mitsuba_brdfs.explore.server import MAX_CONNECTIONS
    with _serving(head_timeout=0.5, body_timeout=30) as (port, explorer):
        held = []
        for k in range(MAX_CONNECTIONS):
            s = socket.create_connection(("127.0.0.1", port), timeout=30)
            if k % 2:
                s.sendall(f"GET /api/state HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n".encode())
            held.append(s)
        deadline = time.monotonic() + 30
        trickle = socket.create_connection(("127.0.0.1", port), timeout=30)
        closed = False
        for byte in b"GET /api/state HTTP/1.1\r\nX: " + b"a" * 1000:
            try:
                trickle.sendall(bytes([byte]))
            except OSError:
                closed = True
                break
            if _closed_by_server(trickle, time.monotonic() + 0.05):
                closed = True
                break
        assert closed, "a head sent a byte at a time kept its connection for ever"
        assert all(_closed_by_server(s, deadline) for s in held)
        for s in held + [trickle]:
            s.close()
        assert _get_state(port) == 200
        explorer.delay = 1.5  # three head timeouts: an answer that takes long is not cut
        assert _get_state(port) == 200


def test_a_trickled_body_is_refused_with_408():
    with _serving(head_timeout=30, body_timeout=0.5) as (port, _):
        with socket.create_connection(("127.0.0.1", port), timeout=30) as s:
            s.sendall((f"POST /api/plots HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
                       f"Authorization: token {TOKEN}\r\nContent-Type: application/json\r\n"
                       f"Content-Length: 100\r\n\r\n{{").encode())
            reply = b""
            while b"}" not in reply and (part := s.recv(4096)):
                reply += part
        assert reply.startswith(b"HTTP/1.1 408 ") and b"did not arrive whole" in reply, reply
        assert _get_state(port) == 200


# -- the files the page may have loaded --------------------------------------------------------

LAMBERT_XML = '<bsdf version="3.0.0" type="lambert" id="mine"><rgb name="reflectance" ' \
              'value="0.25"/></bsdf>'


def test_the_page_loads_files_of_the_folder_served_only(client, tmp_path, monkeypatch):
    """A file named from the page is one of the folder explore runs in (not hidden) or a
    scene of the package; any other path, existing or not, is refused with the same line,
    so the page learns nothing of the rest of the machine (here: /etc/passwd, a file beside
    the folder, a link out of it, a folder given with .., a hidden folder)."""
    served, outside = tmp_path / "served", tmp_path / "outside"
    (served / ".hidden").mkdir(parents=True)
    outside.mkdir()
    for d in (served, served / ".hidden", outside):
        (d / "a.xml").write_text(LAMBERT_XML)
    (served / "link.xml").symlink_to(outside / "a.xml")
    monkeypatch.chdir(served)
    monkeypatch.setattr(variant, "_NOTED", set())  # the note on the scene's copy: said here
    before = _state(client)
    for spec in ("/etc/passwd", "/etc/no_such_file.xml", str(outside / "a.xml"),
                 "../outside/a.xml", "link.xml", ".hidden/a.xml", str(served / ".hidden" /
                                                                      "a.xml")):
        r = client.post("/api/entries", json={"spec": spec}, headers=OURS)
        _refused(r, 400, "the files of the folder explore runs in", "command line")
    assert _state(client) == before
    for spec in ("a.xml", str(served / "a.xml"), "scenes/as_sphere.xml"):
        r = client.post("/api/entries", json={"spec": spec}, headers=OURS)
        assert r.status_code == 200, (spec, r.text)
        client.delete(f"/api/entries/{r.json()[0]['id']}", headers=OURS)


def test_the_plugins_offered_do_not_grow_with_spellings_of_a_file(client, tmp_path,
                                                                   monkeypatch):
    """A scene of the package named from another folder, in ever new spellings, added
    and removed: the names the page offers stay the plugins'."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(variant, "_NOTED", set())
    offered = _state(client)["plugins"]
    for k in range(1, 4):
        r = client.post("/api/entries", json={"spec": "scenes/" + "./" * k + "as_sphere.xml"},
                        headers=OURS)
        assert r.status_code == 200, r.text
        client.delete(f"/api/entries/{r.json()[0]['id']}", headers=OURS)
    assert _state(client)["plugins"] == offered


def test_a_bsdf_checked_without_a_copy_keeps_its_parameters_meanwhile(monkeypatch):
    """A BSDF of an XML file that its dictionary does not give again (a textured one) is
    checked as it is, not as a copy: a change of its parameters while its check runs would
    give the check a BSDF changing under it (false FAILs), so it waits (409)."""
    import os
    from mitsuba_brdfs.paths import SCENES
    from mitsuba_brdfs.validate import suite
    (entry,) = [e for e in make_entries(os.path.join(SCENES, "fig3_polished.xml"), {}, 0,
                                        PALETTE) if e.props is None][:1]
    client = TestClient(app(Explorer([entry]), "127.0.0.1", 8765, TOKEN), base_url=PAGE)
    running, release = threading.Event(), threading.Event()

    def held(*args, **kwargs):
        running.set()
        assert release.wait(60)
        return []
    monkeypatch.setattr(suite, "run", held)
    checking = threading.Thread(target=client.post, args=(f"/api/check/{entry.id}",),
                                kwargs={"headers": OURS})
    checking.start()
    try:
        assert running.wait(60)
        name = entry.controls[0]["name"]
        before = _state(client)
        for r in (client.patch(f"/api/entries/{entry.id}", json={"name": name, "value": 0.5},
                               headers=OURS),
                  client.post("/api/plots", json={"set": {"id": entry.id, "name": name,
                                                          "value": 0.5}}, headers=OURS)):
            _refused(r, 409, "check", "after it")
        assert _state(client)["entries"] == before["entries"]
        assert client.patch(f"/api/entries/{entry.id}", json={"visible": False},
                            headers=OURS).status_code == 200
    finally:
        release.set()
        checking.join(60)
    r = client.patch(f"/api/entries/{entry.id}", json={"name": name, "value": 0.5}, headers=OURS)
    assert r.status_code == 200, r.text
