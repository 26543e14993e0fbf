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

// The lines of a fit's result, as fit-measured reports the same fit (the server's summary
// is fit-measured's): its errors, its albedo against the data's, its budget, its warnings.
export function fitSummary(f) {
  const num = (x) => (typeof x === "number" ? fmt(x, 3) : String(x));
  const rms = f.relative_rms.map(num).join(", ");
  const rel = f.albedo.relative_difference.map(
    (row) => row.reduce((a, b) => (Math.abs(b) > Math.abs(a) ? b : a), 0));
  const b = f.budget;
  return [
    `fit error: relative RMS of f cos ${num(f.relative_rms_max)} (R, G, B: ${rms}) on the ` +
      `${count(f.samples)} samples fitted; loss ${num(f.holdout_loss)} on ` +
      `${count(f.holdout_samples)} held-out samples (0: exact, 1: as far off as black)`,
    `albedo against the data's at ${f.albedo.thetas.map((t) => `${t}\u00b0`).join(" / ")}: ` +
      `${rel.map(pct).join(" / ")} (the channel furthest off)`,
    `${f.evaluations} evaluations in ${f.seconds_total.toFixed(1)} s (budget: ${b.evaluations} ` +
      `a stage, at most ${b.most} with the albedo constraint's stages), on ` +
      `${count(f.samples)} of the file's ${count(f.bins)} samples within 80\u00b0`,
    `the same fit as: ${f.command}`,
    ...(f.negative_values ? [`note: ${count(f.negative_values)} of the data's values are ` +
                              "negative (out-of-gamut colours): kept"] : []),
    ...f.warnings.map((w) => `warning: ${w}`),
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
  out.textContent = `fitting ${model} to ${e.label} on the server\u2026 (at most ` +
                    `${state.fitBudget.most} evaluations; \u201cCancel fit\u201d stops it)`;
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

// The panel of a measured entry: what it is, the form fitting a model to it and the area
// of the fit's result. `added(entry)` shows a fitted entry.
export function measuredPanel(e, added) {
  const out = el("div", { class: "output fitted" });
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
  const b = state.fitBudget;
  const note = el("div", { class: "note" },
                  `a fit is fit-measured's with a smaller budget, for speed: ` +
                  `${count(b.samples)} random samples of the file and at most ${b.most} ` +
                  `evaluations (${b.evaluations} for the fit, the rest for the stages of the ` +
                  `albedo constraint where it runs); it adds the fitted model as a BSDF, ` +
                  `drawn over the data`);
  return [about, el("div", { class: "actions" }, "fit a model:", choose, go), note, out];
}
