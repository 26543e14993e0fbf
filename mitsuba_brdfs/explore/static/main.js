// The explorer's page (ES modules, loaded from index.html): start-up, the global sliders,
// adding BSDFs. The page's state is in state.js; talking to the server in server.js; the
// entries' panels in entries.js (a measured entry's fit in fit.js); the plots in plots.js
// and their requests in redraw.js; the spheres in spheres.js; values and small helpers in
// values.js.

import { state } from "./state.js";
import { api } from "./server.js";
import { renderEntry } from "./entries.js";
import { draw, drawScale } from "./plots.js";
import { redraw } from "./redraw.js";
import { refineSpheres } from "./spheres.js";
import { $, say } from "./values.js";

// the plots a slider changes (the exposure changes the sphere's too)
const AFFECTS = { "theta-i": ["polar", "lobe"], "theta-h": ["theta_d"], "theta-d": ["theta_h"],
                  "exposure": ["image"] };
// the plots a log checkbox redraws (from the data held)
const LOG = { "log-polar": ["polar"], "log-lobe": ["lobe"], "log-theta-h": ["theta_h"],
              "log-theta-d": ["theta_d"] };

async function addSpec(spec) {
  try {
    const added = await api("POST", "/api/entries", { spec });
    for (const e of added) { state.entries.push(e); renderEntry(e); }
    say("");
    redraw();
  } catch (err) { say(err.message); }
}

async function start() {
  if (!state.token) {
    say("this address lacks its token: open the address explore printed (\u2026/?token=\u2026)");
  }
  const s = await api("GET", "/api/state");
  Object.assign(state, { variant: s.variant, passes: s.passes, passSpp: s.pass_spp,
                         maxEntries: s.max_entries, entries: s.entries, check: s.check,
                         fit: s.fit, fitModels: s.fit_models,
                         fitBudget: s.fit_budget });
  $("variant").textContent = s.variant;
  for (const p of s.plugins) $("plugins").append(new Option(p, p));
  for (const e of state.entries) renderEntry(e);
  for (const id of ["theta-i", "theta-h", "theta-d", "exposure", "light-theta", "light-phi"]) {
    $(id).addEventListener("input", () => {
      $(`${id}-out`).textContent = $(id).value + (id === "exposure" ? "" : "\u00b0");
      if (id.startsWith("light")) refineSpheres(); else redraw(AFFECTS[id]);
      if (id === "exposure") drawScale();
    });
  }
  for (const [id, parts] of Object.entries(LOG)) {
    $(id).addEventListener("change", () => draw(parts));
  }
  $("add-form").addEventListener("submit", (ev) => {
    ev.preventDefault();
    addSpec($("add-spec").value.trim());
  });
  redraw();
}

start().catch((err) => say(err.message));
