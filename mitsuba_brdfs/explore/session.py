"""The explorer's session: the entries shown, and what the API does with them.

``Explorer`` holds the entries and does the work under one lock (Mitsuba objects are
changed and evaluated by one request at a time). Its methods take values already read
from the request (``api``) and raise ``EntryError`` (a value that cannot be used: status
400), ``KeyError`` (no such BSDF: 404) or ``Busy`` (a check is running: 409).

Bounds, so that no request can make the session grow without end: at most
``MAX_ENTRIES`` BSDFs; one ``check`` at a time, run on a copy of the entry outside the lock
(the plots go on meanwhile; an entry without a dictionary is checked as it is, and its
parameters wait for the end) and cancelled between two of its checks by ``cancel_check``;
one ``fit`` of a model to a measured entry at a time (``fitting``), outside the lock too,
cancelled between two evaluations by ``cancel_fit``, its samples kept on the entry (one
set); the caches of ``evaluate`` and the spheres (one per entry) are bounded.
"""
import io
import os
import threading
import time

from .controls import BUILTINS
from .entries import Entry, load, make_entries, plugin_models
from .evaluate import PARTS, evaluate
from .messages import Busy, EntryError, message, shown
from .sphere import PASS_SPP, PASSES, Sphere, displayed
from .xmldict import dict_to_python, dict_to_xml

__all__ = ["PALETTE", "MAX_ENTRIES", "Explorer"]

#: colours given to the BSDFs in turn (the page can change them)
PALETTE = ["#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
           "#17becf"]
#: BSDFs one page shows at most
MAX_ENTRIES = 16


class _Cancelled(Exception):
    pass


class Explorer:
    """The entries of one session, and what the API does with them."""

    def __init__(self, entries=(), variant="llvm_ad_rgb", specs=(), fit_samples=None,
                 fit_evaluations=None):
        from . import fitting
        self.entries = {e.id: e for e in entries}
        self.variant = variant
        self.lock = threading.Lock()
        self.spheres = {}
        self.next_id = max(self.entries, default=-1) + 1
        self.offered = sorted(set(specs) | set(plugin_models()) | set(BUILTINS))
        self._check = None  # (entry id, label, cancel event) of the check running
        self._check_lock = threading.Lock()
        self._fit = None    # (entry id, label, model, cancel event) of the fit running
        self._fit_lock = threading.Lock()
        self.fit_models = sorted(plugin_models())
        #: the budget of a fit (``fitting.budget``; by default ``fitting``'s)
        self.fit_budget = fitting.budget(
            fitting.SAMPLES if fit_samples is None else fit_samples,
            fitting.EVALUATIONS if fit_evaluations is None else fit_evaluations)

    def entry(self, ident):
        """The entry numbered ``ident`` (an int, or its digits); KeyError if there is none."""
        if isinstance(ident, str) and ident.isascii() and ident.isdigit() and len(ident) < 10:
            ident = int(ident)
        if type(ident) is not int:
            raise EntryError(f"a BSDF is named by its number (got {shown(ident)})")
        try:
            return self.entries[ident]
        except KeyError:
            raise KeyError(f"no BSDF {ident}") from None

    def state(self):
        with self.lock:
            running = self._check
            return {"variant": self.variant, "plugins": self.offered, "passes": PASSES,
                    "pass_spp": PASS_SPP,
                    "max_entries": MAX_ENTRIES,
                    "check": running and {"id": running[0], "label": running[1]},
                    "fit": self._fit and {"id": self._fit[0], "label": self._fit[1],
                                          "model": self._fit[2]},
                    "fit_models": self.fit_models,
                    "fit_budget": self.fit_budget,
                    "entries": [e.state() for e in self.entries.values()]}

    def add(self, spec):
        """Add the BSDFs of SPEC (a plugin name or an XML file); their states."""
        if not spec:
            raise EntryError("add: name a plugin (e.g. roughplastic) or an XML file")
        with self.lock:
            if len(self.entries) >= MAX_ENTRIES:
                raise EntryError(f"add {spec}: the page shows at most {MAX_ENTRIES} BSDFs; "
                                 f"remove one first")
            try:
                new = make_entries(spec, {}, self.next_id, PALETTE)
            except (ValueError, RuntimeError, OSError) as e:
                raise EntryError(str(e)) from None
            new = new[:MAX_ENTRIES - len(self.entries)]
            for e in new:
                self.entries[e.id] = e
            self.next_id += len(new)
            # a plugin's name is offered from now on; a file's, in any of its spellings, not
            if spec not in self.offered and not (spec.lower().endswith(".xml")
                                                 or os.path.exists(spec)):
                self.offered = sorted(set(self.offered) | {spec})
            return [e.state() for e in new]

    def remove(self, ident):
        with self.lock:
            e = self.entry(ident)
            del self.entries[e.id]
            self.spheres.pop(e.id, None)
            return {"removed": e.id}

    def patch(self, ident, param=None, colour=None, visible=None):
        """Change the entry: a parameter (``param`` = (name, value); value None: back to
        its default), its colour, whether it is drawn. Nothing changes if the parameter is
        refused."""
        with self.lock:
            e = self.entry(ident)
            running = self._check
            if param is not None and e.props is None and running and running[0] == e.id:
                # checked as it is (no dictionary to copy it from): it must not change
                raise Busy(f"{e.label}: its check is running on it as it is; change its "
                           f"parameters after it (or cancel it)")
            if param is not None:
                e.set(*param)
            if colour is not None:
                e.colour = colour
            if visible is not None:
                e.visible = visible
            return e.state()

    def plots(self, theta_i, theta_h, theta_d, exposure, parts=PARTS, ids=None, change=None):
        """The data of the plots named in ``parts`` for the visible entries of ``ids`` (all
        when None), after the parameter change ``change`` = (id, name, value) if given."""
        angles = {"theta_i": theta_i, "theta_h": theta_h, "theta_d": theta_d,
                  "exposure": exposure}
        changed = {} if change is None else {"state": self.patch(change[0], change[1:])}
        out = []
        with self.lock:
            for e in self.entries.values():
                if not e.visible or (ids is not None and e.id not in ids):
                    continue
                try:
                    data = evaluate(e.bsdf, **angles, parts=parts)
                except Exception as ex:  # noqa: BLE001 (a user's plugin that raises)
                    data = {"error": message(ex, e.label)}
                out.append({"id": e.id, "label": e.label, "colour": e.colour, **data})
        return {"entries": out, **angles, **changed}

    def sphere(self, ident, index, theta, phi, exposure):
        """The entry's sphere after at least ``index`` + 1 passes, where one more pass gets
        it there (``Sphere.render_pass``), as (PNG bytes, passes in it)."""
        with self.lock:
            e = self.entry(ident)
            s = self.spheres.get(e.id)
            if s is None or s.bsdf is not e.bsdf:
                s = self.spheres[e.id] = Sphere(e.bsdf)
            try:
                img, n = s.render_pass(index, e.version, (theta, phi))
            except Exception as ex:  # noqa: BLE001 (a user's plugin that raises)
                raise EntryError(message(ex, e.label)) from None
        from PIL import Image
        buf = io.BytesIO()
        Image.fromarray(displayed(img, exposure)).save(buf, format="PNG")
        return buf.getvalue(), n

    def export(self, ident):
        with self.lock:
            e = self.entry(ident)
            if e.props is None:
                raise EntryError(f"{e.label}: its XML could not be read as a dictionary; "
                                 f"edit {e.source} itself")
            props = dict(e.props)
        return {"xml": dict_to_xml(props), "python": dict_to_python(props)}

    def check(self, ident):
        """The check suite (quick settings) on a fresh copy of the entry: the entry's ``id``,
        ``label``, ``cancelled`` and what ``check --json`` says of a BSDF
        (``validate.results.bsdf_record``, its ``name`` the label). One at a time
        (``Busy``); ``{"cancelled": True, ...}`` when ``cancel_check`` stopped it."""
        from ..validate import suite
        from ..validate.results import bsdf_record
        cancel = threading.Event()
        with self.lock:
            e = self.entry(ident)
            props, bsdf, label = (dict(e.props) if e.props else None), e.bsdf, e.label
            with self._check_lock:
                if self._check is not None:
                    raise Busy(f"check: one runs at a time, and {self._check[1]}'s is "
                               f"running; wait for it or cancel it")
                self._check = (e.id, label, cancel)

        def stop_if_cancelled(result=None):
            if cancel.is_set():
                raise _Cancelled
        t0 = time.perf_counter()
        try:
            if props is not None:
                bsdf = load(props, label)
            results = suite.run(bsdf, suite.SETTINGS["quick"], label,
                                on_result=stop_if_cancelled)
        except _Cancelled:
            return {"id": e.id, "label": label, "cancelled": True}
        finally:
            with self._check_lock:
                self._check = None
        return {"id": e.id, "label": label, "cancelled": False,
                **bsdf_record(label, results, time.perf_counter() - t0)}

    def cancel_check(self):
        """Stop the check that runs (after the check of the suite under way); the label of
        the BSDF it was checking, or None."""
        with self._check_lock:
            if self._check is None:
                return {"cancelled": None}
            self._check[2].set()
            return {"cancelled": self._check[1]}

    def fit(self, ident, model):
        """Fit this package's plugin ``model`` to the measured entry ``ident`` as
        ``fit-measured`` does, within the session's budget (``fitting``), outside the lock
        (the page's other requests go on), one fit at a time (``Busy``); the fitted model
        becomes an entry. Returns {"cancelled": True, ...} when ``cancel_fit`` stopped it,
        else {"cancelled": False, "fit": the summary, "entry": the new entry's state}."""
        from . import fitting
        if model not in self.fit_models:
            raise EntryError(f"fit: {shown(model)} is not a model of this package (one of "
                             f"{', '.join(self.fit_models)})")
        if "_ad_" not in self.variant or "rgb" not in self.variant:
            raise EntryError(f"fit: a fit needs an RGB variant with automatic "
                             f"differentiation (explore --variant llvm_ad_rgb), not "
                             f"{self.variant}")
        cancel = threading.Event()
        with self.lock:
            e = self.entry(ident)
            if e.measured is None:
                raise EntryError(f"fit: {e.label} is not measured data; a model is fitted "
                                 f"to a measured file's entry (explore FILE.bsdf or "
                                 f"FILE.binary)")
            if len(self.entries) >= MAX_ENTRIES:
                raise EntryError(f"fit: the page shows at most {MAX_ENTRIES} BSDFs; remove "
                                 f"one first")
            info, label, fit_data = dict(e.measured), e.label, e.fit_data
            with self._fit_lock:
                if self._fit is not None:
                    raise Busy(f"fit: one runs at a time, and {self._fit[2]}'s fit to "
                               f"{self._fit[1]} is running; wait for it or cancel it")
                self._fit = (e.id, label, model, cancel)

        def stop_if_cancelled(loss=None):
            if cancel.is_set():
                raise _Cancelled
        budget = self.fit_budget
        try:
            if fit_data is None:
                fit_data = fitting.data(info, budget["samples"])
                e.fit_data = fit_data
            stop_if_cancelled()
            props, summary = fitting.fit(model, fit_data, label, stop_if_cancelled,
                                         budget["evaluations"])
        except _Cancelled:
            return {"id": e.id, "label": label, "model": model, "cancelled": True}
        except ValueError as ex:
            raise EntryError(message(ex, label)) from None
        finally:
            with self._fit_lock:
                self._fit = None
        with self.lock:
            if len(self.entries) >= MAX_ENTRIES:
                raise EntryError(f"fit: the page shows at most {MAX_ENTRIES} BSDFs; remove "
                                 f"one first")
            new = Entry(self.next_id, f"{model} fit to {label}", props,
                        load(dict(props), model), PALETTE[self.next_id % len(PALETTE)],
                        fit={**summary, "id": e.id})
            self.entries[new.id] = new
            self.next_id += 1
            return {"id": e.id, "label": label, "model": model, "cancelled": False,
                    "fit": new.fit, "entry": new.state()}

    def cancel_fit(self):
        """Stop the fit that runs (after the evaluation under way); the label of the
        measured entry it was fitting, or None."""
        with self._fit_lock:
            if self._fit is None:
                return {"cancelled": None}
            self._fit[3].set()
            return {"cancelled": self._fit[1]}
