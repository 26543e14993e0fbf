// The plots, drawn from the data the page holds (state.data): eval in the plane of
// incidence (polar) and over the hemisphere (3D), f against theta_h and theta_d, the
// directional albedo (Plotly), the image slices with their colour scale (canvases).

import { state } from "./state.js";
import { $, el, fmt, srgb } from "./values.js";

/* global Plotly */

export const ALL = ["polar", "lobe", "theta_h", "theta_d", "image", "albedo"];

// Nothing on a toolbar reaches the network: no "Share chart..." (Plotly's cloud), no
// "Edit in Chart Studio", no link to plotly.com.
const PLOTLY = { displaylogo: false, responsive: true, showSendToCloud: false,
                 showEditInChartStudio: false, showLink: false, plotlyServerURL: "",
                 toImageButtonOptions: { format: "png", scale: 2 } };
const config = (filename) => ({ ...PLOTLY, toImageButtonOptions:
                                { ...PLOTLY.toImageButtonOptions, filename } });
// A BSDF's name as Plotly's text: Plotly reads tags in it (<a href> becomes a link), and a
// name comes from the user's XML files; the name is shown as written.
const plain = (text) => text.replace(/&/g, "&amp;").replace(/</g, "&lt;").replace(/>/g, "&gt;");
// The legend at the bottom of the figure, below the x axis' title: the plot area's bottom
// margin grows to hold both (automargin), so neither covers the other.
const LEGEND = { orientation: "h", x: 0, xanchor: "left", y: 0, yanchor: "bottom",
                 yref: "container" };
const layout = (extra) => ({ margin: { l: 56, r: 12, t: 16, b: 8 }, showlegend: true,
                             legend: LEGEND, font: { size: 11 }, ...extra });
const DECADES = 4;  // of a log scale below the largest value
const isLog = (card) => $(`log-${card}`).checked;
const finite = (values) => values.filter((v) => v !== null && v > 0);
const largest = (values) => values.reduce((m, v) => (v !== null && v > m ? v : m), 0);

function drawPolar(list, thetaI) {
  const traces = [];
  let top = 0;
  for (const e of list) {
    top = Math.max(top, largest(e.polar.value));
    traces.push({ type: "scatterpolar", mode: "lines", name: plain(e.label), r: e.polar.value,
                  theta: e.polar.theta, line: { color: e.colour, width: 2 } });
  }
  top = top || 1;
  const log = isLog("polar");
  traces.push({ type: "scatterpolar", mode: "lines", name: "incidence",
                r: [log ? top / 10 ** DECADES : 0, top], theta: [-thetaI, -thetaI],
                line: { color: "#999", dash: "dash" } });
  const radial = log ? { type: "log", exponentformat: "power",
                         range: [Math.log10(top) - DECADES, Math.log10(top) + 0.05] }
                     : { range: [0, top * 1.05] };
  Plotly.react("polar", traces, layout({ margin: { l: 30, r: 30, t: 24, b: 8 },
    polar: { sector: [0, 180], domain: { y: [0.14, 1] },
             angularaxis: { rotation: 90, direction: "clockwise", dtick: 15 },
             radialaxis: radial } }), config("polar"));
}

// Each lobe is a mesh of its (theta, phi) grid, two triangles a cell: a "surface" trace
// would be resampled by Plotly to a grid 20 times finer, drawn in twice the time. The
// scene has no hover (the points of a lobe have no value to show; without it WebGL draws
// each frame once, not a second time for picking). One lobe is drawn opaque (faster in
// software WebGL); two or more translucent, so that one lobe inside another stays visible.
// On the log scale, the radius is the decades above 1e-4 of the largest value of all.
function drawLobe(list) {
  const traces = [], log = isLog("lobe");
  const top = Math.max(...list.map((e) => largest(e.lobe.value.flat())), 0) || 1;
  const rad = (x) => (x === null || x <= 0 ? 0 : log
    ? Math.max(0, Math.log10(x / top) + DECADES) / DECADES * top : x);
  let extent = 0;
  for (const e of list) {
    const v = e.lobe.value, th = e.lobe.theta, ph = e.lobe.phi, m = ph.length;
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
    traces.push({ type: "mesh3d", name: plain(e.label), x, y, z, i, j, k, color: e.colour,
                  opacity: list.length > 1 ? 0.75 : 1, showlegend: true });
  }
  extent = extent || 1;
  const axis = (title, range) => ({ title: { text: title }, range, nticks: 5,
                                    tickfont: { size: 10 } });
  const ticks = log ? { showticklabels: false } : {};
  Plotly.react("lobe", traces, layout({ margin: { l: 0, r: 0, t: 0, b: 4 },
    scene: { hovermode: false, aspectmode: "manual", aspectratio: { x: 1, y: 1, z: 0.5 },
             domain: { x: [0, 1], y: [0.08, 1] },
             xaxis: { ...axis("x (u)", [-extent, extent]), ...ticks },
             yaxis: { ...axis("y (v)", [-extent, extent]), ...ticks },
             zaxis: { ...axis(log ? "z (n), log" : "z (n)", [0, extent]), ...ticks },
             camera: { eye: { x: 0.45, y: -1.65, z: 0.8 }, center: { x: 0, y: 0, z: -0.2 } } } }),
    config("lobe"));
}

function drawLines(div, card, list, key, xTitle) {
  const traces = list.map((e) => ({
    type: "scatter", mode: "lines", name: plain(e.label), x: e[key].x, y: e[key].value,
    line: { color: e.colour, width: 2 } }));
  let yaxis = { title: { text: "f (luminance)" }, rangemode: "tozero" };
  if (isLog(card)) {
    const top = Math.max(...list.map((e) => largest(e[key].value)), 0) || 1;
    const low = Math.min(...list.map((e) => Math.min(...finite(e[key].value), top)));
    // down to the smallest value drawn (a little below it), at most 8 decades
    const lo = Math.max(Math.log10(top) - 2 * DECADES, Math.log10(low) - 0.3);
    yaxis = { title: { text: "f (luminance), log" }, type: "log", exponentformat: "power",
              range: [Math.min(lo, Math.log10(top) - 1), Math.log10(top) + 0.15] };
  }
  Plotly.react(div, traces, layout({
    xaxis: { title: { text: xTitle }, range: [0, 90], dtick: 15, automargin: true },
    yaxis: { ...yaxis, automargin: true } }), config(div));
}

// One legend entry a BSDF (the dots' meaning is said above the plot).
function drawAlbedo(list) {
  const traces = [];
  for (const e of list) {
    const a = e.albedo;
    traces.push({ type: "scatter", mode: "lines", name: plain(e.label), legendgroup: e.label,
                  x: a.theta, y: a.quadrature, line: { color: e.colour } });
    traces.push({ type: "scatter", mode: "markers", name: `${plain(e.label)}: samples`,
                  legendgroup: e.label, showlegend: false, x: a.theta, y: a.mean,
                  marker: { color: e.colour, size: 5 },
                  error_y: { type: "data", array: a.stderr.map((s) => 3 * s), visible: true } });
  }
  Plotly.react("albedo", traces, layout({
    xaxis: { title: { text: "incidence \u03b8i (deg)" }, range: [0, 90], dtick: 15, automargin: true },
    yaxis: { title: { text: "albedo (luminance)" }, rangemode: "tozero", automargin: true } }),
    config("albedo"));
}

// A tile per entry in a container, kept in the entries' order; others removed.
export function tiles(box, prefix, list) {
  const keep = new Set(list.map((e) => `${prefix}-${e.id}`));
  for (const t of [...box.children]) if (!keep.has(t.id)) t.remove();
  return list.map((e) => {
    let t = $(`${prefix}-${e.id}`);
    if (!t) t = el("div", { id: `${prefix}-${e.id}`, class: "tile" });
    box.append(t);  // (moved to the end: the entries' order)
    return t;
  });
}

function sliceTile(t) {
  const canvas = el("canvas", { aria: { label: "f \u03c0 over \u03b8h (across) and \u03b8d (up)" } });
  const link = el("a", { class: "png", textContent: "PNG" });
  link.addEventListener("click", () => {
    link.href = canvas.toDataURL("image/png");
    link.download = `slice-${t.dataset.label}.png`;
  });
  t.append(
    el("div", { class: "slice" },
       el("span", { class: "ytitle" }, "\u03b8d (deg)"),
       el("span", { class: "yticks" }, el("span", {}, "90"), el("span", {}, "45"), el("span", {}, "0")),
       canvas,
       el("span", { class: "xticks" }, el("span", {}, "0"), el("span", {}, "45"), el("span", {}, "90")),
       el("span", { class: "xtitle" }, "\u03b8h (deg)")),
    el("div", { class: "cap" }), link);
}

// The image slices: pixels as the server sends them (8-bit sRGB of f pi at the exposure),
// row 0 (theta_d = 0) at the bottom, theta_h = 0 on the left.
function drawImages(list) {
  tiles($("images"), "image", list).forEach((t, n) => {
    const e = list[n];
    if (!t.querySelector("canvas")) sliceTile(t);
    t.dataset.label = e.label;
    const cap = t.querySelector(".cap");
    cap.textContent = e.error ? `${e.label}: ${e.error}` : e.label;
    cap.style.color = e.colour;
    if (e.error) return;
    const rows = e.image, h = rows.length, w = rows[0].length;
    const canvas = t.querySelector("canvas");
    canvas.width = w; canvas.height = h;
    const ctx = canvas.getContext("2d");
    const img = ctx.createImageData(w, h);
    for (let i = 0; i < h; i++) {
      const row = rows[h - 1 - i];
      for (let j = 0; j < w; j++) {
        const k = 4 * (i * w + j);
        img.data[k] = row[j][0]; img.data[k + 1] = row[j][1]; img.data[k + 2] = row[j][2];
        img.data[k + 3] = 255;
      }
    }
    ctx.putImageData(img, 0, 0);
  });
  drawScale();
}

// The colour scale of the slices: f pi from 0 (black, at the bottom) to 2^-exposure
// (white); more is drawn white. Ticks at even values; the grey is the sRGB of the value.
export function drawScale() {
  const box = $("scale"), exposure = +$("exposure").value, top = Math.pow(2, -exposure);
  const h = 192;
  box.replaceChildren(el("figcaption", { class: "title" }, "f \u03c0"));
  const canvas = el("canvas", { width: 1, height: h });
  const ctx = canvas.getContext("2d"), img = ctx.createImageData(1, h);
  for (let i = 0; i < h; i++) {
    const g = Math.round(srgb(1 - i / (h - 1)) * 255);
    img.data.set([g, g, g, 255], 4 * i);
  }
  ctx.putImageData(img, 0, 0);
  const ticks = el("div", { class: "ticks" });
  for (const f of [0, 0.25, 0.5, 0.75, 1]) {
    const label = f === 1 ? `\u2265 ${fmt(top)}` : fmt(f * top);
    ticks.append(el("span", { style: `top: ${(1 - f) * 100}%` }, label));
  }
  box.append(canvas, ticks);
}

// Draw the plots named in `parts` from the data held, for the visible entries.
export function draw(parts) {
  const shown = state.entries.filter((e) => e.visible && state.data.has(e.id))
    .map((e) => ({ ...state.data.get(e.id), id: e.id, label: e.label, colour: e.colour }));
  const list = shown.filter((e) => !e.error);
  if (parts.includes("polar")) drawPolar(list, state.thetaI ?? +$("theta-i").value);
  if (parts.includes("lobe")) drawLobe(list);
  if (parts.includes("theta_h")) drawLines("slice-h", "theta-h", list, "theta_h", "\u03b8h (deg)");
  if (parts.includes("theta_d")) drawLines("slice-d", "theta-d", list, "theta_d", "\u03b8d (deg)");
  if (parts.includes("albedo")) drawAlbedo(list);
  if (parts.includes("image")) drawImages(shown);
  return shown;
}
