"""The explorer's web application: the page, its scripts, and a small JSON API.

``Explorer`` holds the entries and does the work (under one lock: Mitsuba objects are
changed and evaluated by one request at a time); ``app(explorer)`` is the Starlette
application that serves it. Requests:

- ``GET /``, ``/static/...``: the page, and Plotly's script from the installed ``plotly``;
- ``GET /api/state``: the entries with their controls, the plugin names the page offers;
- ``POST /api/entries`` ``{"spec"}``: add the BSDFs of a SPEC; ``DELETE /api/entries/ID``;
- ``PATCH /api/entries/ID`` ``{"name", "value"}`` (``"value": null``: back to the default),
  ``{"colour"}``, ``{"visible"}``;
- ``POST /api/plots`` ``{"theta_i", "theta_h", "theta_d", "exposure", "parts", "ids",
  "set"}``: the data of the plots named in ``parts`` (default: all) for the visible entries
  of ``ids`` (default: all; the page asks for the entry whose parameter changed) (an entry
  that raises gets ``{"error"}``, the others their data); ``"set": {"id", "name", "value"}``
  first changes a parameter as ``PATCH`` does and returns the entry's new state as
  ``"state"`` (one request for a change and its plots);
- ``GET /api/sphere/ID?pass=K&theta=&phi=&exposure=``: pass K of the sphere, a PNG;
- ``GET /api/export/ID``: the entry as XML and as ``mi.load_dict`` source;
- ``POST /api/check/ID``: the ``check`` suite (quick settings) on a copy of the entry.

A value the page sends that cannot be used is answered with status 400 and
``{"error": message}`` naming the BSDF, the parameter and its range.
"""
import io
import json
import os
import threading

import numpy as np

from . import entries as E
from .evaluate import PARTS, evaluate
from .sphere import PASSES, Sphere

__all__ = ["PALETTE", "Explorer", "app", "plotly_js"]

STATIC = os.path.join(os.path.dirname(os.path.abspath(__file__)), "static")
#: colours given to the BSDFs in turn (the page can change them)
PALETTE = ["#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
           "#17becf"]


def plotly_js():
    """The path of ``plotly.min.js`` in the installed ``plotly`` package."""
    import plotly
    path = os.path.join(os.path.dirname(plotly.__file__), "package_data", "plotly.min.js")
    if not os.path.isfile(path):
        raise ImportError(f"plotly is installed without its plotly.min.js ({path})")
    return path


class Explorer:
    """The entries of one session, and what the API does with them."""

    def __init__(self, entries=(), variant="llvm_ad_rgb", specs=()):
        self.entries = {e.id: e for e in entries}
        self.variant = variant
        self.lock = threading.Lock()
        self.spheres = {}
        self.next_id = max(self.entries, default=-1) + 1
        self.offered = sorted(set(specs) | set(_ours()) | set(E.BUILTINS))

    def _entry(self, ident):
        try:
            return self.entries[int(ident)]
        except (KeyError, ValueError):
            raise KeyError(f"no BSDF {ident}") from None

    def state(self):
        with self.lock:
            return {"variant": self.variant, "plugins": self.offered, "passes": PASSES,
                    "entries": [e.state() for e in self.entries.values()]}

    def add(self, spec, params=None):
        spec = str(spec).strip()
        if not spec:
            raise E.EntryError("add: name a plugin (e.g. roughplastic) or an XML file")
        with self.lock:
            try:
                new = E.make_entries(spec, params or {}, self.next_id, PALETTE)
            except (ValueError, RuntimeError, OSError) as e:
                raise E.EntryError(str(e)) from None
            for e in new:
                self.entries[e.id] = e
            self.next_id += len(new)
            if spec not in self.offered and not os.path.isfile(spec):
                self.offered = sorted(set(self.offered) | {spec})
            return [e.state() for e in new]

    def remove(self, ident):
        with self.lock:
            e = self._entry(ident)
            del self.entries[e.id]
            self.spheres.pop(e.id, None)

    def patch(self, ident, body):
        with self.lock:
            e = self._entry(ident)
            if "colour" in body:
                e.colour = str(body["colour"])
            if "visible" in body:
                e.visible = bool(body["visible"])
            if "name" in body:
                e.set(body["name"], body.get("value"))
            return e.state()

    def plots(self, body):
        args = {k: _angle(body, k, d, lo, hi) for k, d, lo, hi in
                (("theta_i", 45, 0, 89.9), ("theta_h", 30, 0, 90), ("theta_d", 30, 0, 90),
                 ("exposure", 0, -10, 10))}
        parts = body.get("parts", list(PARTS))
        if not isinstance(parts, list) or not set(parts) <= set(PARTS):
            raise E.EntryError(f"parts must be a list of {', '.join(PARTS)}")
        ids = body.get("ids")
        if ids is not None and (not isinstance(ids, list) or
                                not all(isinstance(i, int) for i in ids)):
            raise E.EntryError("ids must be a list of entry numbers")
        change = body.get("set")
        if change is not None and (not isinstance(change, dict) or "name" not in change):
            raise E.EntryError('set must be {"id", "name", "value"}')
        changed = {} if change is None else {"state": self.patch(
            change.get("id"), {"name": change["name"], "value": change.get("value")})}
        out = []
        with self.lock:
            for e in self.entries.values():
                if not e.visible or (ids is not None and e.id not in ids):
                    continue
                try:
                    data = evaluate(e.bsdf, **args, parts=parts)
                except Exception as ex:  # a user's plugin that raises: said in its place
                    data = {"error": E._message(ex, e.label)}
                out.append({"id": e.id, "label": e.label, "colour": e.colour, **data})
        return {"entries": out, **args, **changed}

    def sphere(self, ident, index, theta, phi, exposure):
        """Pass ``index`` of the entry's sphere as PNG bytes."""
        from ..output import tonemap
        with self.lock:
            e = self._entry(ident)
            s = self.spheres.get(e.id)
            if s is None or s.bsdf is not e.bsdf:
                s = self.spheres[e.id] = Sphere(e.bsdf)
            try:
                img, n = s.render_pass(index, e.version, (theta, phi))
            except Exception as ex:
                raise E.EntryError(E._message(ex, e.label)) from None
        from PIL import Image
        buf = io.BytesIO()
        Image.fromarray(tonemap(img, exposure)).save(buf, format="PNG")
        return buf.getvalue(), n

    def export(self, ident):
        with self.lock:
            e = self._entry(ident)
            if e.props is None:
                raise E.EntryError(f"{e.label}: its XML could not be read as a dictionary; "
                                   f"edit {e.source} itself")
            props = dict(e.props)
        return {"xml": E.dict_to_xml(props), "python": E.dict_to_python(props)}

    def check(self, ident):
        """The check suite (quick settings) on a fresh copy of the entry (the page's
        requests go on meanwhile), as ``check --json`` gives it."""
        from ..validate import suite
        with self.lock:
            e = self._entry(ident)
            props, bsdf, label = (dict(e.props) if e.props else None), e.bsdf, e.label
        if props is not None:
            bsdf = E._load(props, label)
        results = suite.run(bsdf, suite.SETTINGS["quick"], label)
        return E.jsonable({"label": label, "passed": all(r.passed for r in results),
                          "checks": [r.as_dict() for r in results]})


def _ours():
    return list(E._plugin_models())


def _angle(body, key, default, lo, hi):
    try:
        x = float(body.get(key, default))
    except (TypeError, ValueError):
        raise E.EntryError(f"{key} must be a number in [{lo}, {hi}]") from None
    if not np.isfinite(x) or x < lo or x > hi:
        raise E.EntryError(f"{key} must be in [{lo}, {hi}] (got {x:g})")
    return x


def app(explorer):
    """The Starlette application serving ``explorer``."""
    from starlette.applications import Starlette
    from starlette.concurrency import run_in_threadpool
    from starlette.requests import Request
    from starlette.responses import FileResponse, JSONResponse, Response
    from starlette.routing import Mount, Route
    from starlette.staticfiles import StaticFiles

    def guarded(fn):
        async def endpoint(request: Request):
            raw = await request.body()
            try:
                body = json.loads(raw) if raw.strip() else {}
            except ValueError:
                body = None
            if body is not None and not isinstance(body, dict):
                body = None
            if body is None:
                return JSONResponse({"error": "the request's body is not a JSON object"}, 400)
            try:
                out = await run_in_threadpool(fn, request, body)
            except E.EntryError as e:
                return JSONResponse({"error": str(e)}, 400)
            except KeyError as e:
                return JSONResponse({"error": str(e.args[0])}, 404)
            return out if isinstance(out, Response) else JSONResponse(out)
        return endpoint

    def sphere(request, body):
        q = request.query_params
        try:
            index = int(q.get("pass", 0))
            light = [_angle(q, "theta", 45, 0, 180), _angle(q, "phi", 135, -360, 360)]
        except ValueError:
            raise E.EntryError("pass must be an integer") from None
        png, n = explorer.sphere(request.path_params["ident"], max(index, 0), *light,
                                 _angle(q, "exposure", 0, -10, 10))
        return Response(png, media_type="image/png", headers={"X-Passes": str(n),
                                                               "Cache-Control": "no-store"})

    def entry(request, body):
        ident = request.path_params["ident"]
        if request.method == "DELETE":
            explorer.remove(ident)
            return {"removed": int(ident)}
        return explorer.patch(ident, body)

    routes = [
        Route("/", lambda r: FileResponse(os.path.join(STATIC, "index.html"))),
        Route("/static/plotly.min.js", lambda r: FileResponse(plotly_js())),
        Mount("/static", StaticFiles(directory=STATIC)),
        Route("/api/state", guarded(lambda r, b: explorer.state())),
        Route("/api/entries", guarded(lambda r, b: explorer.add(b.get("spec", ""))),
              methods=["POST"]),
        Route("/api/entries/{ident}", guarded(entry), methods=["PATCH", "DELETE"]),
        Route("/api/plots", guarded(lambda r, b: explorer.plots(b)), methods=["POST"]),
        Route("/api/sphere/{ident}", guarded(sphere)),
        Route("/api/export/{ident}",
              guarded(lambda r, b: explorer.export(r.path_params["ident"]))),
        Route("/api/check/{ident}",
              guarded(lambda r, b: explorer.check(r.path_params["ident"])), methods=["POST"]),
    ]
    return Starlette(routes=routes)
