// The spheres rendered by Mitsuba: pass after pass for every visible entry, each shown as
// it arrives (its caption says the samples per pixel); #spheres is aria-busy meanwhile. A
// change starts a new run, which stops the passes of the previous one.

import { state } from "./state.js";
import { png } from "./server.js";
import { tiles } from "./plots.js";
import { $, el } from "./values.js";

// Stop the passes under way (the one being rendered ends first).
export function stopSpheres() { state.sphereRun++; }

// Wait for the pass being fetched to end (before removing its entry).
export async function spheresStopped() {
  stopSpheres();
  await state.sphereFetch?.catch(() => {});
}

export async function refineSpheres() {
  const run = ++state.sphereRun;
  const box = $("spheres");
  box.setAttribute("aria-busy", "true");
  const shown = state.entries.filter((e) => e.visible);
  tiles(box, "sphere", shown).forEach((t, n) => {
    const e = shown[n];
    if (!t.querySelector("img")) {
      t.append(el("img", { alt: `the sphere of ${e.label}` }), el("div", { class: "cap" }),
               el("a", { class: "png", textContent: "PNG" }));
    }
    const cap = t.querySelector(".cap");
    cap.style.color = e.colour;
    cap.textContent = e.label;
  });
  const q = `theta=${$("light-theta").value}&phi=${$("light-phi").value}` +
            `&exposure=${$("exposure").value}`;
  const failed = new Set();
  // the passes each sphere has: the server keeps a sphere's mean, so a sphere that did not
  // change (the exposure moved, another one was added) is at its last pass at once
  const have = new Map(shown.map((e) => [e.id, 0]));
  for (let round = 0; round < 2 * state.passes; round++) {
    const due = shown.filter((e) => !failed.has(e.id) && have.get(e.id) < state.passes);
    if (!due.length) break;
    for (const e of due) {
      if (run !== state.sphereRun) return;
      const t = $(`sphere-${e.id}`), cap = t.querySelector(".cap");
      try {
        state.sphereFetch = png(`/api/sphere/${e.id}?pass=${have.get(e.id)}&${q}`);
        const { blob, passes } = await state.sphereFetch;
        const url = URL.createObjectURL(blob);
        if (run !== state.sphereRun) { URL.revokeObjectURL(url); return; }
        const img = t.querySelector("img"), link = t.querySelector("a.png");
        if (img.src) URL.revokeObjectURL(img.src);
        img.src = url;
        link.href = url; link.download = `sphere-${e.label}.png`;
        have.set(e.id, passes);
        cap.textContent = `${e.label} (${passes * state.passSpp} spp)`;
      } catch (err) {
        failed.add(e.id);
        cap.textContent = `${e.label}: ${err.message}`;
      }
    }
  }
  if (run === state.sphereRun) box.setAttribute("aria-busy", "false");
}
