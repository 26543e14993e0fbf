// Measured entries and fits: what the panel of a measured entry says (it has no
// parameters), its "Fit" form (a model of this package fitted on the server to the
// entry's samples, added as an entry), and what a fitted entry's panel says of its fit.
// One fit runs at a time: its button becomes "Cancel fit", the others wait.

import { state } from "./state.js";
import { api } from "./server.js";
import { el, entryError, fmt } from "./values.js";

const pct = (x) => `${x >= 0 ? "+" : ""}${(100 * x).toFixed(0)} %`;
const count = (n) => n.toLocaleString("en-US");

// The fit buttons follow the fit running (as the check buttons follow the check).
export function fitButtons() {
  for (const b of document.querySelectorAll("button.fit")) {
    const id = +b.dataset.id, running = state.fit;
    b.textContent = running && running.id === id ? "Cancel fit" : "Fit";
    b.disabled = !!running && running.id !== id;
    b.title = running && running.id !== id
      ? `one fit at a time: ${running.model}'s fit to ${running.label} is running`
      : running ? "stop the fit (after the evaluation under way)"
                : "fit the chosen model to this measured data, on the server";
  }
}

// One line of a fit's result: its error on held-out samples, the albedo against the data's.
export function fitSummary(f) {
  const a = f.albedo;
  const albedo = a.thetas.map((t, k) => `${t}\u00b0 ${fmt(a.fitted[k])} ` +
    `(${a.measured[k] > 0 ? pct(a.fitted[k] / a.measured[k] - 1) : "data 0"})`).join(", ");
  return [
    `fit error: relative RMS of f cos ${fmt(f.heldout_rms_max)} on ${count(f.heldout)} ` +
      "held-out samples (0: exact, 1: as far off as black)",
    `albedo at ${albedo} against the data's`,
    `${f.evaluations} evaluations in ${f.seconds.toFixed(1)} s, on ${count(f.samples)} of ` +
      `the file's ${count(f.usable)} samples within 80\u00b0 (a random subset, for speed)`,
    ...(f.warning ? [`note: ${f.warning}`] : []),
  ];
}

// What a fitted entry's panel says of its fit.
export function fitInfo(e) {
  const f = e.fit;
  return el("div", { class: "fitinfo" },
            el("div", {}, `${f.model} fitted to ${f.to}`),
            ...fitSummary(f).map((line) => el("div", { class: "note" }, line)));
}

// Cancel the fit running. This page's own fit may not have reached the server yet (its
// request is under way): asked again until the server has it or it has ended.
async function cancel(e, out) {
  const mine = state.fit.mine;
  if (mine) out.textContent = "cancelling: the evaluation under way ends first\u2026";
  for (let tries = 0; tries < 50; tries++) {
    let r;
    try { r = await api("DELETE", "/api/fit"); }
    catch (err) { entryError(e.id, err.message); return; }
    if (r.cancelled !== null || !mine || !state.fit) break;
    await new Promise((done) => setTimeout(done, 100));
  }
  if (!mine) { state.fit = null; fitButtons(); }  // (another page's fit)
}

async function fit(e, model, out, added) {
  if (state.fit) { await cancel(e, out); return; }  // the button of the fit running
  state.fit = { id: e.id, label: e.label, model, mine: true };
  fitButtons();
  out.className = "output fitting";
  out.textContent = `fitting ${model} to ${e.label} on the server\u2026 (at most ` +
                    `${state.fitEvaluations} evaluations; \u201cCancel fit\u201d stops it)`;
  try {
    const r = await api("POST", `/api/fit/${e.id}`, { model });
    if (r.cancelled) out.textContent = "fit cancelled";
    else {
      out.replaceChildren(el("b", {}, `${model}: `), fitSummary(r.fit)[0]);
      added(r.entry);
    }
  } catch (err) {
    out.textContent = "";
    entryError(e.id, err.message);
  }
  state.fit = null;
  fitButtons();
}

// The panel of a measured entry: what it is, and the form fitting a model to it.
// `added(entry)` shows a fitted entry.
export function measuredPanel(e, out, added) {
  const m = e.measured;
  const about = el("div", { class: "measured" }, el("div", {}, m.text),
                   el("div", { class: "note" }, `file: ${m.file}`),
                   ...(m.note ? [el("div", { class: "note" }, m.note)] : []));
  const choose = el("select", { aria: { label: `model to fit to ${e.label}` },
                                title: "a model of this package" });
  for (const name of state.fitModels) choose.add(new Option(name, name, false, name === "ward"));
  const go = el("button", { class: "fit" });
  go.dataset.id = e.id;
  go.addEventListener("click", () => fit(e, choose.value, out, added));
  const note = el("div", { class: "note" },
                  `a fit takes up to ${count(state.fitSamples)} random samples of the file (a ` +
                  `reduced set, for speed; its error is measured on as many others) and ` +
                  `adds the fitted model as a BSDF, drawn over the data`);
  return [about, el("div", { class: "actions" }, "fit a model:", choose, go), note];
}
