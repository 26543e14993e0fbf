"""The explorer's web application (Starlette): the page, its scripts, and a small JSON API.

``app(explorer, host, port, token)`` serves an ``Explorer`` (``session``) behind ``Guard``
(``guard``: the Host allow-list, the token, same-origin JSON for changes, the body limit).
Requests (every ``/api/`` one with the token; bodies read by ``api``):

- ``GET /``, ``/static/...``: the page, and Plotly's script from the installed ``plotly``;
- ``GET /api/state``: the entries with their controls, the plugin names the page offers,
  the check running;
- ``POST /api/entries`` ``{"spec"}``: add the BSDFs of a SPEC; ``DELETE /api/entries/ID``;
- ``PATCH /api/entries/ID`` ``{"name", "value"}`` (``"value": null``: back to the default),
  ``{"colour": "#rrggbb"}``, ``{"visible": true|false}``;
- ``POST /api/plots`` ``{"theta_i", "theta_h", "theta_d", "exposure", "parts", "ids",
  "set"}``: the data of the plots named in ``parts`` (default: all) for the visible entries
  of ``ids`` (default: all; the page asks for the entry whose parameter changed) (an entry
  that raises gets ``{"error"}``, the others their data); ``"set": {"id", "name", "value"}``
  first changes a parameter as ``PATCH`` does and returns the entry's new state as
  ``"state"`` (one request for a change and its plots);
- ``GET /api/sphere/ID?pass=K&theta=&phi=&exposure=``: the sphere after at least K + 1
  passes, where one more pass gets it there (``sphere.Sphere.render_pass``), a PNG (its
  passes in ``X-Passes``);
- ``GET /api/export/ID``: the entry as XML and as ``mi.load_dict`` source;
- ``POST /api/check/ID``: the ``check`` suite (quick settings) on a copy of the entry, one
  at a time (409 while another runs); ``DELETE /api/check``: cancel it;
- ``POST /api/fit/ID`` ``{"model"}``: fit one of this package's models to the measured
  entry (``fitting``), added as an entry, one at a time (409 while another runs);
  ``DELETE /api/fit``: cancel it.

A request that cannot be used is answered with a 4xx status and ``{"error": one line}``
naming what was wrong (the BSDF, the parameter and its range), and changes nothing.

``config(application)`` is how uvicorn serves it: HTTP/1.1 by h11 whatever else is
installed, at most ``MAX_CONNECTIONS`` connections (more get 503 at once), and a connection
that takes longer than ``HEAD_TIMEOUT`` to send the head of a request (its line and
headers) is closed, as it waits, so that idle or trickling connections cannot hold every
place (uvicorn has a keep-alive timeout between requests, none for a head that never ends).
"""
import json
import os

from . import api
from .guard import Guard
from ..output import jsonable
from .messages import Busy, EntryError

__all__ = ["STATIC", "MAX_CONNECTIONS", "HEAD_TIMEOUT", "plotly_js", "app", "config"]

STATIC = os.path.join(os.path.dirname(os.path.abspath(__file__)), "static")
#: connections served at once; more are answered 503 at once
MAX_CONNECTIONS = 128
#: seconds a connection has to send the head of its next request
HEAD_TIMEOUT = 10.0


def plotly_js():
    """The path of ``plotly.min.js`` in the installed ``plotly`` package."""
    import plotly
    path = os.path.join(os.path.dirname(plotly.__file__), "package_data", "plotly.min.js")
    if not os.path.isfile(path):
        raise ImportError(f"plotly is installed without its plotly.min.js ({path})")
    return path


def app(explorer, host="127.0.0.1", port=8765, token=None):
    """The Starlette application serving ``explorer`` at ``host``:``port``, behind its
    ``Guard`` (whose ``token`` is that of the printed address; made when None)."""
    from starlette.applications import Starlette
    from starlette.concurrency import run_in_threadpool
    from starlette.requests import Request
    from starlette.responses import FileResponse, JSONResponse, Response
    from starlette.routing import Mount, Route
    from starlette.staticfiles import StaticFiles

    class JSON(JSONResponse):
        def render(self, content):  # as check --json writes it (``output.jsonable``)
            return json.dumps(jsonable(content), allow_nan=False,
                              separators=(",", ":")).encode()

    def endpoint(fn, fields=api.NONE):
        """A route: the body read with ``fields``, ``fn(request, values)`` run in a thread,
        its errors as 4xx answers."""
        async def run(request: Request):
            try:
                body = api.read(api.decode(await request.body()), fields)
                out = await run_in_threadpool(fn, request, body)
            except EntryError as e:
                return JSON({"error": str(e)}, 400)
            except KeyError as e:
                return JSON({"error": str(e.args[0])}, 404)
            except Busy as e:
                return JSON({"error": str(e)}, 409)
            return out if isinstance(out, Response) else JSON(out)
        return run

    def ident(request):
        return request.path_params["ident"]

    def sphere(request, body):
        index, theta, phi, exposure = api.sphere_query(request.query_params)
        png, n = explorer.sphere(ident(request), index, theta, phi, exposure)
        return Response(png, media_type="image/png", headers={"X-Passes": str(n),
                                                               "Cache-Control": "no-store"})

    def plots(request, b):
        return explorer.plots(b["theta_i"], b["theta_h"], b["theta_d"], b["exposure"],
                              b["parts"], b["ids"], b["set"])

    def patch(request, b):
        if b["value"] is not None and b["name"] is None:
            raise EntryError('"value" is sent with the "name" of its parameter')
        if all(b[k] is None for k in ("name", "colour", "visible")):
            raise EntryError('nothing to change: send {"name", "value"}, {"colour"} or '
                             '{"visible"}')
        param = None if b["name"] is None else (b["name"], b["value"])
        return explorer.patch(ident(request), param, b["colour"], b["visible"])

    def remove(request, b):
        return explorer.remove(ident(request))

    routes = [
        Route("/", lambda r: FileResponse(os.path.join(STATIC, "index.html"))),
        Route("/static/plotly.min.js", lambda r: FileResponse(plotly_js())),
        Mount("/static", StaticFiles(directory=STATIC)),
        Route("/api/state", endpoint(lambda r, b: explorer.state())),
        Route("/api/entries", endpoint(lambda r, b: explorer.add(b["spec"]), api.ADD),
              methods=["POST"]),
        Route("/api/entries/{ident}", endpoint(patch, api.PATCH), methods=["PATCH"]),
        Route("/api/entries/{ident}", endpoint(remove), methods=["DELETE"]),
        Route("/api/plots", endpoint(plots, api.PLOTS), methods=["POST"]),
        Route("/api/sphere/{ident}", endpoint(sphere)),
        Route("/api/export/{ident}", endpoint(lambda r, b: explorer.export(ident(r)))),
        Route("/api/check/{ident}", endpoint(lambda r, b: explorer.check(ident(r))),
              methods=["POST"]),
        Route("/api/check", endpoint(lambda r, b: explorer.cancel_check()),
              methods=["DELETE"]),
        Route("/api/fit/{ident}", endpoint(lambda r, b: explorer.fit(ident(r), b["model"]),
                                           api.FIT), methods=["POST"]),
        Route("/api/fit", endpoint(lambda r, b: explorer.cancel_fit()), methods=["DELETE"]),
    ]

    async def not_found(request, exc):
        return JSON({"error": f"no such address: {request.url.path[:80]}"}, 404)

    async def not_allowed(request, exc):
        return JSON({"error": f"{request.method} is not a request of "
                              f"{request.url.path[:80]}"}, 405)

    return Guard(Starlette(routes=routes, exception_handlers={404: not_found,
                                                               405: not_allowed}),
                 host, port, token)


def config(application, head_timeout=HEAD_TIMEOUT):
    """The ``uvicorn.Config`` serving ``application`` (see the module)."""
    import uvicorn
    return uvicorn.Config(application, http=_protocol(head_timeout), log_level="warning",
                          timeout_graceful_shutdown=2, limit_concurrency=MAX_CONNECTIONS)


def _protocol(head_timeout):
    """uvicorn's h11 protocol, closing a connection whose request head is not complete
    ``head_timeout`` seconds after the connection opened or its last answer was sent."""
    import h11
    from uvicorn.protocols.http.h11_impl import H11Protocol

    class Protocol(H11Protocol):
        _head_timer = None

        def connection_made(self, transport):
            super().connection_made(transport)
            self._watch_head()

        def data_received(self, data):
            super().data_received(data)
            self._watch_head()

        def on_response_complete(self):
            super().on_response_complete()
            self._watch_head()

        def connection_lost(self, exc):
            if self._head_timer is not None:
                self._head_timer.cancel()
                self._head_timer = None
            super().connection_lost(exc)

        def _watch_head(self):
            """A timer while the connection waits for a request's head (h11: the client
            IDLE); none while a request is read or answered."""
            waiting = self.conn.their_state is h11.IDLE and not self.transport.is_closing()
            if waiting and self._head_timer is None:
                self._head_timer = self.loop.call_later(head_timeout, self._too_slow)
            elif not waiting and self._head_timer is not None:
                self._head_timer.cancel()
                self._head_timer = None

        def _too_slow(self):
            self._head_timer = None
            if not self.transport.is_closing():
                self.transport.close()
    return Protocol
