// The explorer page, part 3 of 4: the Plotly plots (polar, 3D lobe, half/difference
// angle slices, albedo) and the redraw scheduling.
"use strict";

// -- plots ---------------------------------------------------------------------------------

const angle = (id) => +$(id).value;
const isLog = () => $("log").checked;
// The legend goes below each plot: above, it hid the polar plot's +-15 deg tick labels.
// Below an x axis title, the legend goes lower (LOW).
const LOW = { orientation: "h", x: 0, y: -0.25, yanchor: "top" };
const layout = (extra) => ({ margin: { l: 48, r: 10, t: 20, b: 40 }, showlegend: true,
  legend: { orientation: "h", x: 0, y: -0.12, yanchor: "top" }, font: { size: 11 }, ...extra });

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
// One lobe is drawn opaque (faster in software WebGL); two or more translucent, so that
// one lobe inside another stays visible.
function drawLobe(list) {
  const traces = [], shown = list.filter((e) => !e.error).length;
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
                  opacity: shown > 1 ? 0.75 : 1, showlegend: true });
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
  Plotly.react(div, traces, layout({ legend: LOW, xaxis: { title: { text: xTitle }, range: [0, 90] },
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
  Plotly.react("albedo", traces, layout({ legend: LOW, xaxis: { title: { text: "incidence (deg)" }, range: [0, 90] },
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

