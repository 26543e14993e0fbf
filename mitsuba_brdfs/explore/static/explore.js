// The explorer's page: controls of every BSDF on the left, Plotly plots on the right.
// All numbers come from the server (Mitsuba evaluates the plugins); this script draws them.
"use strict";

const $ = (id) => document.getElementById(id);
const state = { entries: [], passes: 8, data: new Map(), want: new Set(), wantIds: new Set(),
                wantAll: false, sets: [], busy: false, thetaI: null, sphereToken: 0,
                changedAt: null };
const PLOTLY = { displaylogo: false, responsive: true,
                 toImageButtonOptions: { format: "png", scale: 2 } };

// -- talking to the server ------------------------------------------------------------------

async function api(method, url, body) {
  const r = await fetch(url, { method, headers: { "Content-Type": "application/json" },
                               body: body === undefined ? undefined : JSON.stringify(body) });
  const data = await r.json();
  if (!r.ok) throw new Error(data.error || r.statusText);
  return data;
}

function say(text) { $("status").textContent = text || ""; }

function entryError(id, text) {
  const el = document.querySelector(`#entry-${id} .error`);
  if (el) el.textContent = text || "";
}

// -- values and sliders --------------------------------------------------------------------

const SLIDER_STEPS = 1000;
function toSlider(c, v) {
  const [lo, hi] = c.slider;
  const t = c.log ? Math.log(Math.max(v, lo) / lo) / Math.log(hi / lo) : (v - lo) / (hi - lo);
  return Math.round(Math.min(Math.max(t, 0), 1) * SLIDER_STEPS);
}
function fromSlider(c, s) {
  const [lo, hi] = c.slider, t = s / SLIDER_STEPS;
  const v = c.log ? lo * Math.pow(hi / lo, t) : lo + t * (hi - lo);
  return Number(v.toPrecision(4));
}
const fmt = (v) => (typeof v === "number" ? Number(v.toPrecision(4)).toString() : String(v));
const srgb = (x) => (x <= 0.0031308 ? 12.92 * x : 1.055 * Math.pow(x, 1 / 2.4) - 0.055);
const linear = (c) => (c <= 0.04045 ? c / 12.92 : Math.pow((c + 0.055) / 1.055, 2.4));
function toHex(rgb) {
  return "#" + rgb.map((x) => Math.round(Math.min(Math.max(srgb(x), 0), 1) * 255)
    .toString(16).padStart(2, "0")).join("");
}
function fromHex(hex) {
  return [1, 3, 5].map((i) => Number(linear(parseInt(hex.substr(i, 2), 16) / 255).toFixed(4)));
}
const asRgb = (v) => (Array.isArray(v) ? v : [v, v, v]);

// -- the entries' panels -------------------------------------------------------------------

// A parameter goes to the server with the request for its BSDF's plots (one request, in
// the plots' queue; the other entries' plots have not changed). Resolves once drawn.
function setParam(e, name, value, rerender) {
  changed();
  return new Promise((done) => {
    state.sets.push({ e, name, value, rerender, done });
    redraw([], [e.id]);
  });
}

// The answer to a parameter sent: the entry's new state, or the server's refusal.
function applySet(set, data, err) {
  if (err) {
    entryError(set.e.id, err.message);
    renderEntry(set.e, err.message);  // back to the values the server holds
    return;
  }
  entryError(set.e.id, "");
  Object.assign(set.e, data.state);
  if (set.rerender) renderEntry(set.e);
}

function control(e, c) {
  const div = document.createElement("div");
  div.className = "ctl" + (c.set ? "" : " unset");
  div.title = (c.doc || "") + (c.range ? ` Range: ${c.range}.` : "");
  const name = document.createElement("span");
  name.className = "name";
  name.textContent = c.name;
  div.append(name);
  let main = document.createElement("span"), side = document.createElement("span");
  if (c.kind === "float" || c.kind === "int") {
    main = document.createElement("input");
    main.type = "range"; main.min = 0; main.max = SLIDER_STEPS;
    const slider = c.slider || [c.lo, c.hi];
    const cc = { ...c, slider };
    main.value = toSlider(cc, c.value ?? slider[0]);
    side = document.createElement("input");
    side.type = "text"; side.value = c.value === null ? "" : fmt(c.value);
    side.setAttribute("aria-label", c.name);
    main.addEventListener("input", () => {
      let v = fromSlider(cc, +main.value);
      if (c.kind === "int") v = Math.round(v);
      side.value = fmt(v);
      queueParam(e, c.name, v);
    });
    side.addEventListener("change", () => setParam(e, c.name, side.value.trim(), true));
  } else if (c.kind === "colour") {
    main.className = "colour";
    const pick = document.createElement("input");
    pick.type = "color";
    const text = document.createElement("input");
    text.type = "text";
    text.setAttribute("aria-label", c.name);
    const rgb = asRgb(c.value ?? 0);
    pick.value = toHex(rgb);
    pick.disabled = c.hi > 1;
    text.value = Array.isArray(c.value) ? c.value.map(fmt).join(", ") : fmt(c.value ?? 0);
    pick.addEventListener("input", () => {
      const v = fromHex(pick.value);
      text.value = v.map(fmt).join(", ");
      queueParam(e, c.name, v);
    });
    text.addEventListener("change", () => setParam(e, c.name, text.value.trim(), true));
    main.append(pick, text);
  } else if (c.kind === "choice") {
    main = document.createElement("select");
    for (const ch of c.choices) main.add(new Option(ch, ch, false, ch === c.value));
    main.addEventListener("change", () => setParam(e, c.name, main.value, true));
  } else if (c.kind === "bool") {
    main = document.createElement("input");
    main.type = "checkbox"; main.checked = !!c.value;
    main.addEventListener("change", () => setParam(e, c.name, main.checked, true));
  } else {
    main.textContent = `${c.value} (a texture: set it in XML)`;
    main.className = "note";
  }
  div.append(main, side);
  const reset = document.createElement("button");
  reset.className = "reset"; reset.textContent = "\u21ba"; reset.title = "back to the default";
  reset.disabled = !c.set || !e.exportable;
  reset.addEventListener("click", () => setParam(e, c.name, null, true));
  div.append(reset);
  return div;
}

// a slider sends its latest value once the previous one has been applied
const pending = new Map();
function queueParam(e, name, value) {
  const key = `${e.id}/${name}`;
  const q = pending.get(key);
  if (q) { q.value = value; q.again = true; return; }
  const item = { value, again: false };
  pending.set(key, item);
  (async () => {
    do {
      item.again = false;
      await setParam(e, name, item.value, false);
    } while (item.again);
    pending.delete(key);
  })();
}

function renderEntry(e, error) {
  let sec = $(`entry-${e.id}`);
  if (!sec) {
    sec = document.createElement("section");
    sec.id = `entry-${e.id}`;
    sec.className = "entry";
    $("entries").append(sec);
  }
  sec.style.borderLeftColor = e.colour;
  sec.innerHTML = "";
  const head = document.createElement("div");
  head.className = "head";
  const colour = document.createElement("input");
  colour.type = "color"; colour.value = e.colour; colour.title = "colour in the plots";
  colour.addEventListener("input", async () => {
    e.colour = colour.value; sec.style.borderLeftColor = e.colour;
    draw(ALL);
    refineSpheres();
    await api("PATCH", `/api/entries/${e.id}`, { colour: e.colour });
  });
  const shown = document.createElement("input");
  shown.type = "checkbox"; shown.checked = e.visible; shown.title = "draw it";
  shown.addEventListener("change", async () => {
    e.visible = shown.checked;
    await api("PATCH", `/api/entries/${e.id}`, { visible: e.visible });
    redraw();
  });
  const label = document.createElement("span");
  label.className = "label"; label.textContent = e.label; label.title = e.plugin;
  const remove = document.createElement("button");
  remove.textContent = "\u00d7"; remove.title = "remove this BSDF";
  remove.addEventListener("click", async () => {
    state.sphereToken++;  // the spheres' passes stop; the one under way ends first
    await state.sphereFetch?.catch(() => {});
    await api("DELETE", `/api/entries/${e.id}`);
    state.entries = state.entries.filter((x) => x.id !== e.id);
    state.data.delete(e.id);
    sec.remove();
    draw(ALL);
    refineSpheres();
  });
  head.append(colour, shown, label, remove);
  const err = document.createElement("div");
  err.className = "error"; err.textContent = error || "";
  sec.append(head, err);
  for (const c of e.controls) sec.append(control(e, c));
  const actions = document.createElement("div");
  actions.className = "actions";
  const out = document.createElement("div");
  const exp = document.createElement("button");
  exp.textContent = "Export"; exp.disabled = !e.exportable;
  exp.addEventListener("click", () => showExport(e, out));
  const chk = document.createElement("button");
  chk.textContent = "Check";
  chk.title = "run the check suite (quick settings) on this BSDF";
  chk.addEventListener("click", () => runCheck(e, out, chk));
  actions.append(exp, chk);
  sec.append(actions, out);
}

function copyButton(textarea) {
  const b = document.createElement("button");
  b.textContent = "Copy";
  b.addEventListener("click", async () => {
    try { await navigator.clipboard.writeText(textarea.value); }
    catch (err) { textarea.select(); document.execCommand("copy"); }
    b.textContent = "Copied";
    setTimeout(() => (b.textContent = "Copy"), 1200);
  });
  return b;
}

async function showExport(e, out) {
  try {
    const x = await api("GET", `/api/export/${e.id}`);
    out.className = "export"; out.innerHTML = "";
    for (const [title, text] of [["Mitsuba XML", x.xml], ["load_dict", x.python]]) {
      const t = document.createElement("textarea");
      t.value = text; t.readOnly = true;
      const row = document.createElement("div");
      row.className = "row";
      row.append(title, copyButton(t));
      out.append(row, t);
    }
  } catch (err) { entryError(e.id, err.message); }
}

async function runCheck(e, out, button) {
  button.disabled = true;
  out.className = "check"; out.textContent = "running the checks\u2026";
  try {
    const r = await api("POST", `/api/check/${e.id}`);
    const rows = r.checks.map((c) => `<tr><td class="${c.status}">${c.status}</td>` +
      `<td>${c.name}</td><td>${c.message.replace(/</g, "&lt;")}</td></tr>`).join("");
    out.innerHTML = `<b class="${r.passed ? "PASS" : "FAIL"}">${r.passed ? "PASS" : "FAIL"}` +
      `</b> (check, quick settings)<table>${rows}</table>`;
  } catch (err) { out.textContent = ""; entryError(e.id, err.message); }
  button.disabled = false;
}

// -- plots ---------------------------------------------------------------------------------

const angle = (id) => +$(id).value;
const isLog = () => $("log").checked;
const layout = (extra) => ({ margin: { l: 48, r: 10, t: 30, b: 40 }, showlegend: true,
  legend: { orientation: "h", y: 1.02, yanchor: "bottom" }, font: { size: 11 }, ...extra });

function drawPolar(list, thetaI) {
  const traces = [];
  let top = 0;
  for (const e of list) {
    if (e.error) continue;
    top = Math.max(top, ...e.polar.value.filter((v) => v !== null));
    traces.push({ type: "scatterpolar", mode: "lines", name: e.label, r: e.polar.value,
                  theta: e.polar.theta, line: { color: e.colour, width: 2 } });
  }
  top = top || 1;
  traces.push({ type: "scatterpolar", mode: "lines", name: "incidence", r: [0, top],
                theta: [-thetaI, -thetaI], line: { color: "#999", dash: "dash" } });
  const radial = isLog() ? { type: "log", range: [Math.log10(top) - 4, Math.log10(top) + 0.05] }
                         : { range: [0, top * 1.05] };
  Plotly.react("polar", traces, layout({ polar: { sector: [0, 180],
    angularaxis: { rotation: 90, direction: "clockwise", dtick: 15 }, radialaxis: radial } }),
    { ...PLOTLY, toImageButtonOptions: { ...PLOTLY.toImageButtonOptions, filename: "polar" } });
}

// Each lobe is a mesh of its (theta, phi) grid, two triangles a cell: a "surface" trace
// would be resampled by Plotly to a grid 20 times finer, drawn in twice the time. The
// scene has no hover (the points of a lobe have no value to show; without it WebGL draws
// each frame once, not a second time for picking).
function drawLobe(list) {
  const traces = [];
  let extent = 0;
  for (const e of list) {
    if (e.error) continue;
    const v = e.lobe.value, th = e.lobe.theta, ph = e.lobe.phi, m = ph.length;
    const top = Math.max(...v.flat().filter((x) => x !== null)) || 1;
    const rad = (x) => (x === null ? 0 : isLog() ? Math.max(0, Math.log10(x / top) + 4) / 4 * top : x);
    const x = [], y = [], z = [], i = [], j = [], k = [];
    for (let a = 0; a < th.length; a++) {
      const st = Math.sin(th[a] * Math.PI / 180), ct = Math.cos(th[a] * Math.PI / 180);
      for (let b = 0; b < m; b++) {
        const r = rad(v[a][b]), p = ph[b] * Math.PI / 180;
        x.push(r * st * Math.cos(p)); y.push(r * st * Math.sin(p)); z.push(r * ct);
        extent = Math.max(extent, r);
        if (a > 0 && b > 0) {  // the cell whose far corner is (a, b)
          const c = (a - 1) * m + b - 1;
          i.push(c, c + 1); j.push(c + 1, c + m + 1); k.push(c + m, c + m);
        }
      }
    }
    traces.push({ type: "mesh3d", name: e.label, x, y, z, i, j, k, color: e.colour,
                  opacity: 0.75, showlegend: true });
  }
  Plotly.react("lobe", traces, layout({ margin: { l: 0, r: 0, t: 0, b: 0 },
    scene: { hovermode: false, aspectmode: "manual", aspectratio: { x: 1, y: 1, z: 0.5 },
             xaxis: { range: [-extent, extent] }, yaxis: { range: [-extent, extent] },
             zaxis: { range: [0, extent] }, camera: { eye: { x: 0.1, y: -1.25, z: 0.55 } } } }),
    { ...PLOTLY, toImageButtonOptions: { ...PLOTLY.toImageButtonOptions, filename: "lobe" } });
}

function drawLines(div, list, key, xTitle) {
  const traces = list.filter((e) => !e.error).map((e) => ({
    type: "scatter", mode: "lines", name: e.label, x: e[key].x, y: e[key].value,
    line: { color: e.colour, width: 2 } }));
  Plotly.react(div, traces, layout({ xaxis: { title: { text: xTitle }, range: [0, 90] },
    yaxis: { title: { text: "f (luminance)" }, type: isLog() ? "log" : "linear" } }),
    { ...PLOTLY, toImageButtonOptions: { ...PLOTLY.toImageButtonOptions, filename: div } });
}

function drawAlbedo(list) {
  const traces = [];
  for (const e of list) {
    if (e.error) continue;
    const a = e.albedo;
    traces.push({ type: "scatter", mode: "lines", name: `${e.label}: quadrature`, x: a.theta,
                  y: a.quadrature, line: { color: e.colour } });
    traces.push({ type: "scatter", mode: "markers", name: `${e.label}: samples`, x: a.theta,
                  y: a.mean, marker: { color: e.colour, size: 5 },
                  error_y: { type: "data", array: a.stderr.map((s) => 3 * s), visible: true } });
  }
  Plotly.react("albedo", traces, layout({ xaxis: { title: { text: "incidence (deg)" }, range: [0, 90] },
    yaxis: { title: { text: "albedo (luminance)" }, rangemode: "tozero" } }),
    { ...PLOTLY, toImageButtonOptions: { ...PLOTLY.toImageButtonOptions, filename: "albedo" } });
}

function tile(container, id, e) {
  let t = $(id);
  if (!t) {
    t = document.createElement("div");
    t.id = id; t.className = "tile";
    container.append(t);
  }
  return t;
}

// The image slices are drawn into canvases (one per BSDF): pixels as the server sends
// them (8-bit sRGB of f pi), row 0 (theta_d = 0) at the bottom.
function drawImages(list) {
  const box = $("images");
  const keep = new Set(list.map((e) => `image-${e.id}`));
  for (const t of [...box.children]) if (!keep.has(t.id)) t.remove();
  for (const e of list) {
    const t = tile(box, `image-${e.id}`, e);
    if (!t.querySelector("canvas")) {
      t.innerHTML = `<div class="slice"><span class="ylabel">\u03b8d 0\u2192 90\u00b0</span>` +
        `<canvas></canvas></div><div class="xlabel">\u03b8h 0\u2192 90\u00b0</div>` +
        `<div class="cap"></div><a class="png">PNG</a>`;
      const link = t.querySelector("a.png");
      link.addEventListener("click", () => {
        link.href = t.querySelector("canvas").toDataURL("image/png");
        link.download = `slice-${t.dataset.label}.png`;
      });
    }
    t.dataset.label = e.label;
    const cap = t.querySelector(".cap");
    cap.textContent = e.error ? `${e.label}: ${e.error}` : e.label;
    cap.style.color = e.colour;
    if (e.error) continue;
    const rows = e.image, n = rows.length, m = rows[0].length;
    const canvas = t.querySelector("canvas");
    canvas.width = m; canvas.height = n;
    const ctx = canvas.getContext("2d");
    const img = ctx.createImageData(m, n);
    for (let i = 0; i < n; i++) {
      const row = rows[n - 1 - i];
      for (let j = 0; j < m; j++) {
        const k = 4 * (i * m + j);
        img.data[k] = row[j][0]; img.data[k + 1] = row[j][1]; img.data[k + 2] = row[j][2];
        img.data[k + 3] = 255;
      }
    }
    ctx.putImageData(img, 0, 0);
  }
}

// The page keeps the latest data of every plot of every BSDF and asks the server only for
// the plots that a change affects (the incidence slider: the lobes of every BSDF; a
// parameter: every plot of its BSDF).
const ALL = ["polar", "lobe", "theta_h", "theta_d", "image", "albedo"];

// The time of the change being drawn: the page records how long it takes to show it
// (data-redraw-ms: until the frame with every plot drawn is painted, WebGL included;
// data-fetch-ms: of it, waiting for the server; data-script-ms: the plots' scripts;
// data-sphere-ms: to the first pass of every sphere).
function changed() { state.changedAt ??= performance.now(); }

function redraw(parts = ALL, ids = null) {
  for (const p of parts) state.want.add(p);
  if (ids) for (const id of ids) state.wantIds.add(id); else state.wantAll = true;
  state.sphereToken++;  // the sphere's passes wait: the plots go first
  if (!state.busy) fetchAndDraw();
}

function lacksData(e) {
  const d = state.data.get(e.id);
  return !d || d.error || ALL.some((p) => !(p in d));
}

async function fetchAndDraw() {
  state.busy = true;
  try {
    while (state.want.size || state.sets.length) {
      const set = state.sets.shift(), wanted = [[...state.want], [...state.wantIds],
                                                state.wantAll];
      let [parts, ids] = [wanted[0], state.wantAll ? undefined : wanted[1]];
      state.want.clear(); state.wantIds.clear(); state.wantAll = false;
      if (set) {  // a parameter: every plot of its entry
        parts = ALL;
        if (ids && !ids.includes(set.e.id)) ids.push(set.e.id);
      }
      if (state.entries.some((e) => e.visible && lacksData(e))) { parts = ALL; ids = undefined; }
      const body = { theta_i: angle("theta-i"), theta_h: angle("theta-h"),
                     theta_d: angle("theta-d"), exposure: angle("exposure"), parts, ids,
                     set: set && { id: set.e.id, name: set.name, value: set.value } };
      const t0 = performance.now(), since = state.changedAt ?? t0;
      state.changedAt = null;
      let data;
      try {
        data = await api("POST", "/api/plots", body);
      } catch (err) {
        if (!set) throw err;
        applySet(set, null, err);  // refused: nothing changed, the other wishes stay
        if (wanted[0].length) redraw(wanted[0], wanted[2] ? null : wanted[1]);
        set.done();
        continue;
      }
      const t1 = performance.now();
      if (set) applySet(set, data);
      state.thetaI = body.theta_i;
      for (const x of data.entries) {
        const old = state.data.get(x.id);
        state.data.set(x.id, x.error || !old || old.error ? x : { ...old, ...x });
      }
      draw(parts);
      const drawn = performance.now();
      state.sphereSince = since;
      // the frame that shows the plots, once painted (a task after its animation frame)
      requestAnimationFrame(() => setTimeout(() => {
        const b = document.body.dataset, t2 = performance.now();
        b.redrawMs = String(Math.round(t2 - since));
        b.fetchMs = String(Math.round(t1 - since));
        b.scriptMs = String(Math.round(drawn - t1));
        b.drawn = String((+b.drawn || 0) + 1);
      }));
      if (set) set.done();
    }
  } catch (err) {
    say(err.message);
    for (const set of state.sets.splice(0)) set.done();
  }
  state.busy = false;
  const since = state.sphereSince;
  state.sphereSince = undefined;
  refineSpheres(since);
}

function draw(parts) {
  const list = state.entries.filter((e) => e.visible && state.data.has(e.id))
    .map((e) => ({ ...state.data.get(e.id), label: e.label, colour: e.colour }));
  for (const e of list) entryError(e.id, e.error || "");
  if (parts.includes("polar")) drawPolar(list, state.thetaI ?? angle("theta-i"));
  if (parts.includes("lobe")) drawLobe(list);
  if (parts.includes("theta_h")) drawLines("slice-h", list, "theta_h", "\u03b8h (deg)");
  if (parts.includes("theta_d")) drawLines("slice-d", list, "theta_d", "\u03b8d (deg)");
  if (parts.includes("albedo")) drawAlbedo(list);
  if (parts.includes("image")) drawImages(list);
}

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
        state.sphereFetch = fetch(`/api/sphere/${e.id}?pass=${k}&${q}`);
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
