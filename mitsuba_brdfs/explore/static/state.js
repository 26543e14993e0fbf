// The explorer page, part 1 of 4 (loaded first): shared state, Plotly config, talking to
// the server, values and sliders. Plain scripts share one global scope, loaded in order
// from index.html: state.js, entries.js, plots.js, main.js.
"use strict";

const $ = (id) => document.getElementById(id);
const state = { entries: [], passes: 8, data: new Map(), want: new Set(), wantIds: new Set(),
                wantAll: false, sets: [], busy: false, thetaI: null, sphereToken: 0,
                changedAt: null };
// Nothing on a toolbar reaches the network: no "Share chart..." (Plotly's cloud), no
// "Edit in Chart Studio", no link to plotly.com.
const PLOTLY = { displaylogo: false, responsive: true, showSendToCloud: false,
                 showEditInChartStudio: false, showLink: false, plotlyServerURL: "",
                 toImageButtonOptions: { format: "png", scale: 2 } };

// -- talking to the server ------------------------------------------------------------------

// the run's token, from the address explore printed (?token=...), sent with every request
const TOKEN = new URLSearchParams(location.search).get("token") || "";
const AUTH = { Authorization: `token ${TOKEN}` };

async function api(method, url, body) {
  const r = await fetch(url, { method, headers: { "Content-Type": "application/json", ...AUTH },
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

