// Asking the server for the plots' data and drawing them: one request in flight at a time,
// each asking only for what changed since (the incidence slider: the lobes of every BSDF;
// a parameter: every plot of its BSDF, and the parameter goes with that request).
// While data are asked for or drawn, #plots is aria-busy; then the spheres refine.

import { state } from "./state.js";
import { api } from "./server.js";
import { ALL, draw } from "./plots.js";
import { refineSpheres, stopSpheres } from "./spheres.js";
import { $, entryError, say } from "./values.js";

const busy = (on) => $("plots").setAttribute("aria-busy", on ? "true" : "false");

// Ask for the plots `parts` of the entries `ids` (all: null).
export function redraw(parts = ALL, ids = null) {
  for (const p of parts) state.want.parts.add(p);
  if (ids) for (const id of ids) state.want.ids.add(id); else state.want.all = true;
  busy(true);
  stopSpheres();  // the spheres wait: the plots go first
  if (!state.busy) fetchAndDraw();
}

// Send a parameter with the request for its entry's plots. Resolves with the entry's new
// state (already in state.entries); rejects with the server's refusal (nothing changed).
export function setParam(entry, name, value) {
  return new Promise((done, fail) => {
    state.sets.push({ entry, name, value, done, fail });
    redraw([], [entry.id]);
  });
}

// A slider's change: its latest value once the previous one is applied; `applied(state,
// error)` after each.
export function slideParam(entry, name, value, applied) {
  const key = `${entry.id}/${name}`;
  const q = state.sliding.get(key);
  if (q) { q.value = value; q.again = true; return; }
  const item = { value, again: false };
  state.sliding.set(key, item);
  (async () => {
    do {
      item.again = false;
      try { applied(await setParam(entry, name, item.value), null); }
      catch (err) { applied(null, err); }
    } while (item.again);
    state.sliding.delete(key);
  })();
}

const lacksData = (e) => {
  const d = state.data.get(e.id);
  return !d || d.error || ALL.some((p) => !(p in d));
};

function nextRequest() {
  const set = state.sets.shift();
  const want = { parts: [...state.want.parts], ids: [...state.want.ids], all: state.want.all };
  state.want.parts.clear(); state.want.ids.clear(); state.want.all = false;
  let parts = want.parts, ids = want.all ? undefined : want.ids;
  if (set) {  // a parameter: every plot of its entry
    parts = ALL;
    if (ids && !ids.includes(set.entry.id)) ids.push(set.entry.id);
  }
  if (state.entries.some((e) => e.visible && lacksData(e))) { parts = ALL; ids = undefined; }
  const body = { theta_i: +$("theta-i").value, theta_h: +$("theta-h").value,
                 theta_d: +$("theta-d").value, exposure: +$("exposure").value, parts, ids,
                 set: set ? { id: set.entry.id, name: set.name, value: set.value } : null };
  return { set, want, body };
}

async function fetchAndDraw() {
  state.busy = true;
  try {
    while (state.want.parts.size || state.want.ids.size || state.want.all || state.sets.length) {
      const { set, want, body } = nextRequest();
      if (!set && !body.parts.length) continue;
      let data;
      try {
        data = await api("POST", "/api/plots", body);
      } catch (err) {
        if (!set) throw err;
        set.fail(err);  // refused: nothing changed; what else was wished stays wished
        if (want.parts.length) redraw(want.parts, want.all ? null : want.ids);
        continue;
      }
      if (set) Object.assign(set.entry, data.state);
      state.thetaI = body.theta_i;
      for (const x of data.entries) {
        const old = state.data.get(x.id);
        state.data.set(x.id, x.error || !old || old.error ? x : { ...old, ...x });
      }
      for (const e of draw(body.parts)) entryError(e.id, e.error || "");
      if (set) set.done(data.state);
    }
  } catch (err) {
    say(err.message);
    for (const set of state.sets.splice(0)) set.fail(err);
  }
  state.busy = false;
  busy(false);
  refineSpheres();
}
