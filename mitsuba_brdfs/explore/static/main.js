// The explorer page, part 4 of 4 (loaded last): the spheres (passes shown as they
// arrive), adding entries and start-up.
"use strict";

// -- the spheres: passes, each shown as it arrives -----------------------------------------

async function refineSpheres(since = performance.now()) {
  const token = ++state.sphereToken;
  const box = $("spheres");
  const shown = state.entries.filter((e) => e.visible);
  const keep = new Set(shown.map((e) => `sphere-${e.id}`));
  for (const t of [...box.children]) if (!keep.has(t.id)) t.remove();
  for (const e of shown) {
    const t = tile(box, `sphere-${e.id}`, e);
    if (!t.querySelector("img")) t.innerHTML = `<img alt=""><div class="cap"></div>`;
    const cap = t.querySelector(".cap");
    cap.style.color = e.colour;
    cap.textContent = e.label;
  }
  const q = `theta=${angle("light-theta")}&phi=${angle("light-phi")}&exposure=${angle("exposure")}`;
  for (let k = 0; k < state.passes; k++) {
    for (const e of shown) {
      if (token !== state.sphereToken) return;
      const t = $(`sphere-${e.id}`);
      try {
        state.sphereFetch = fetch(`/api/sphere/${e.id}?pass=${k}&${q}`, { headers: AUTH });
        const r = await state.sphereFetch;
        if (!r.ok) throw new Error((await r.json()).error);
        const url = URL.createObjectURL(await r.blob());
        const img = t.querySelector("img");
        if (img.src) URL.revokeObjectURL(img.src);
        img.src = url;
        img.dataset.passes = String(k + 1);
        let link = t.querySelector("a");
        if (!link) { link = document.createElement("a"); link.textContent = " PNG"; t.querySelector(".cap").after(link); }
        link.href = url; link.download = `sphere-${e.label}.png`;
        t.querySelector(".cap").textContent = `${e.label} (${(k + 1) * 4} spp)`;
      } catch (err) {
        t.querySelector(".cap").textContent = `${e.label}: ${err.message}`;
      }
    }
    if (k === 0 && shown.length) {
      const b = document.body.dataset;
      b.sphereMs = String(Math.round(performance.now() - since));
      b.sphered = String((+b.sphered || 0) + 1);
    }
  }
}

// -- start ---------------------------------------------------------------------------------

async function addSpec(spec) {
  try {
    const added = await api("POST", "/api/entries", { spec });
    for (const e of added) { state.entries.push(e); renderEntry(e); }
    say("");
    redraw();
  } catch (err) { say(err.message); }
}

//: the plots a slider changes (the exposure changes the sphere's too)
const AFFECTS = { "theta-i": ["polar", "lobe"], "theta-h": ["theta_d"], "theta-d": ["theta_h"],
                  "exposure": ["image"] };

async function start() {
  const s = await api("GET", "/api/state");
  state.entries = s.entries;
  state.passes = s.passes;
  $("variant").textContent = s.variant;
  for (const p of s.plugins) $("plugins").append(new Option(p, p));
  for (const e of state.entries) renderEntry(e);
  for (const id of ["theta-i", "theta-h", "theta-d", "exposure", "light-theta", "light-phi"]) {
    $(id).addEventListener("input", () => {
      $(`${id}-out`).textContent = $(id).value + (id === "exposure" ? "" : "\u00b0");
      if (id.startsWith("light")) refineSpheres(); else { changed(); redraw(AFFECTS[id]); }
    });
  }
  $("log").addEventListener("change", () => draw(["polar", "lobe", "theta_h", "theta_d"]));
  $("add-form").addEventListener("submit", (ev) => {
    ev.preventDefault();
    addSpec($("add-spec").value.trim());
  });
  redraw();
}

start().catch((err) => say(err.message));
