"""Who may use the explorer's server: the page it served, and scripts given its token.

A server on 127.0.0.1 is reachable by every web page the user's browser opens: a page of
another site can send it "simple" requests (a ``POST`` with ``Content-Type: text/plain``
needs no permission), and through DNS rebinding (a name of the attacker's that resolves to
127.0.0.1) it can read the answers too. Local development servers close this the same way
(Jupyter: a token in the printed address, Host and Origin checks; webpack-dev-server,
CVE-2018-14732, and Vite, CVE-2025-24010: a Host allow-list). ``Guard`` wraps the
application and refuses, with status 403 and one line saying why, before anything runs:

- a ``Host`` header that is not the address served (127.0.0.1, localhost, [::1], the
  ``--host`` name, with the port; bound to every interface, also the machine's names and
  any IP address: DNS rebinding needs a name), or more than one ``Host`` (400);
- an ``/api/`` request without the run's token (the ``token`` query parameter, as
  Jupyter's, or an ``Authorization: token ...`` header, which the page sends);
- a request that changes something (``POST``, ``PATCH``, ``PUT``, ``DELETE``) from
  another origin (``Origin`` or ``Sec-Fetch-Site`` says so), or with a body that is not
  ``Content-Type: application/json`` (a cross-site page can send ``text/plain`` without
  asking, never JSON).

Every answer carries headers that keep the page to itself: a Content-Security-Policy
(scripts, styles, images and requests from this server only: a script injected into the
page could not send the token elsewhere; not in another site's frame),
``Referrer-Policy: no-referrer`` (a link followed from the page does not send its address,
token included) and ``X-Content-Type-Options: nosniff``.

A body larger than ``MAX_BODY`` is refused with 413 as soon as its ``Content-Length`` (or,
sent in chunks, its running size) says so, without reading the rest; one that has not
arrived whole ``BODY_TIMEOUT`` seconds after its head is refused with 408 (a client that
trickles its body holds no place for long).
"""
import asyncio
import ipaddress
import json
import secrets
import socket
from urllib.parse import parse_qs

__all__ = ["MAX_BODY", "BODY_TIMEOUT", "LOOPBACK", "is_loopback", "is_wildcard", "Guard"]

#: largest request body read (bytes); the page's largest is a few hundred bytes
MAX_BODY = 1 << 20
#: seconds a request's body has to arrive whole
BODY_TIMEOUT = 30.0
#: the loopback names a browser on this machine may use for the server
LOOPBACK = ("127.0.0.1", "localhost", "::1")
_CHANGES = ("POST", "PATCH", "PUT", "DELETE")
#: the headers of every answer (see the module)
HEADERS = [(b"content-security-policy",
            b"default-src 'self'; script-src 'self'; style-src 'self' 'unsafe-inline'; "
            b"img-src 'self' data: blob:; connect-src 'self'; frame-ancestors 'none'; "
            b"base-uri 'none'; form-action 'none'"),
           (b"referrer-policy", b"no-referrer"),
           (b"x-content-type-options", b"nosniff")]


def is_wildcard(host):
    return host in ("", "0.0.0.0", "::")


def is_loopback(host):
    """True if ``host`` (a name or an address) is this machine only."""
    if host in LOOPBACK:
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def _split(hostport):
    """"name:port" / "[v6]:port" / "name" -> (lowercase name without brackets, port or
    None); None if it cannot be read."""
    h = hostport.strip().lower()
    if h.startswith("["):
        name, _, rest = h[1:].partition("]")
        port = rest[1:] if rest.startswith(":") else (None if not rest else "x")
    else:
        name, colon, port = h.rpartition(":") if h.count(":") == 1 else (h, "", None)
        name, port = (name, port) if colon else (h, None)
    if port is not None and not (port.isascii() and port.isdigit() and len(port) <= 5):
        return None
    return name, (int(port) if port is not None else None)


class Guard:
    """ASGI middleware: the checks of the module, then ``app``.

    ``host``, ``port``: what the server is bound to; ``token``: the run's token (made here
    when None: ``self.token``)."""

    def __init__(self, app, host, port, token=None, max_body=MAX_BODY,
                 body_timeout=BODY_TIMEOUT):
        self.app, self.port, self.max_body = app, port, max_body
        self.body_timeout = body_timeout
        self.token = token or secrets.token_urlsafe(24)
        self.names = set(LOOPBACK) | {host.strip("[]").lower()}
        self.any_address = is_wildcard(host)
        if self.any_address:
            for n in {socket.gethostname(), socket.getfqdn()}:
                self.names.add(n.lower())

    def host_ok(self, header):
        """True if the ``Host`` header names this server."""
        parts = _split(header or "")
        if parts is None:
            return False
        name, port = parts
        if (port or 80) != self.port:
            return False
        if name in self.names:
            return True
        if self.any_address:
            try:
                ipaddress.ip_address(name)
                return True
            except ValueError:
                return False
        return False

    def token_ok(self, scope, headers):
        given = parse_qs(scope.get("query_string", b"").decode("latin-1")).get("token", [])
        auth = headers.get("authorization", "")
        if auth.lower().startswith("token "):
            given.append(auth[6:].strip())
        return any(secrets.compare_digest(t.encode("utf-8", "replace"),
                                          self.token.encode()) for t in given)

    def refusal(self, scope, headers):
        """(status, one line) of a refused request, or None."""
        host = headers.get("host")
        if sum(k == b"host" for k, _ in scope.get("headers", [])) > 1:
            return 400, "refused: the request has more than one Host header"
        if not self.host_ok(host):
            return 403, (f"refused: the Host {json.dumps(host)[:80]} is not this server's "
                         f"address (open the address explore printed)")
        if scope["path"].startswith("/api/") and not self.token_ok(scope, headers):
            return 403, ("refused: this request lacks the token of the address explore "
                         "printed (...?token=...; scripts pass it the same way)")
        method = scope["method"]
        if method in _CHANGES:
            origin = headers.get("origin")
            if origin is not None and origin.lower() != f"http://{host.lower()}":
                return 403, (f"refused: a change requested by another site "
                             f"({json.dumps(origin)[:80]})")
            if headers.get("sec-fetch-site") in ("cross-site", "same-site"):
                return 403, "refused: a change requested by another site"
        if method in ("POST", "PATCH", "PUT"):
            kind = headers.get("content-type", "").split(";")[0].strip().lower()
            if kind != "application/json":
                return 403, (f"refused: a change must be sent as application/json (got "
                             f"{json.dumps(kind or 'no Content-Type')[:60]})")
        length = headers.get("content-length")
        if length is not None:
            if not (length.isascii() and length.isdigit()):
                return 400, "refused: the Content-Length is not a number"
            if int(length) > self.max_body:
                return 413, (f"refused: the body is larger than {self.max_body} bytes")
        return None

    async def __call__(self, scope, receive, send):
        if scope["type"] == "websocket":  # none is served: refused at once
            await receive()
            return await send({"type": "websocket.close", "code": 1008})
        if scope["type"] != "http":  # the server's start and end (lifespan)
            return await self.app(scope, receive, send)
        headers = {k.decode("latin-1").lower(): v.decode("latin-1")
                   for k, v in scope.get("headers", [])}
        plain_send = send

        async def send(message):
            if message["type"] == "http.response.start":
                message = {**message, "headers": [*message.get("headers", ()), *HEADERS]}
            await plain_send(message)
        refused = self.refusal(scope, headers)
        if refused is None:
            body, refused = await self._body(receive)
        if refused is not None:
            return await _answer(send, *refused)
        sent = False

        async def replay():
            nonlocal sent
            if not sent:
                sent = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()
        return await self.app(scope, replay, send)

    async def _body(self, receive):
        """(the whole body, None), or (None, (413 or 408, why)) once it grows past the
        limit or takes longer than ``body_timeout``."""
        try:
            return await asyncio.wait_for(self._read(receive), self.body_timeout)
        except asyncio.TimeoutError:
            return None, (408, f"refused: the body did not arrive whole within "
                               f"{self.body_timeout:g} s")

    async def _read(self, receive):
        chunks, size = [], 0
        while True:
            msg = await receive()
            if msg["type"] == "http.disconnect":
                return b"", (400, "the client went away")
            chunk = msg.get("body", b"")
            size += len(chunk)
            if size > self.max_body:
                return None, (413, f"refused: the body is larger than {self.max_body} bytes")
            chunks.append(chunk)
            if not msg.get("more_body", False):
                return b"".join(chunks), None


async def _answer(send, status, text):
    body = json.dumps({"error": text}).encode()
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/json"),
                            (b"content-length", str(len(body)).encode()),
                            (b"connection", b"close")]})
    await send({"type": "http.response.body", "body": body})
