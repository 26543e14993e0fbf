// Values as the page shows them: numbers, sliders (linear or logarithmic), colours, and a
// small helper to build elements.

export const $ = (id) => document.getElementById(id);

// an element with properties and children (strings become text)
export function el(tag, props = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(props)) {
    if (k === "class") e.className = v;
    else if (k === "aria") for (const [a, x] of Object.entries(v)) e.setAttribute(`aria-${a}`, x);
    else e[k] = v;
  }
  e.append(...children);
  return e;
}

export const SLIDER_STEPS = 1000;

export function toSlider(c, v) {
  const [lo, hi] = c.slider;
  const t = c.log ? Math.log(Math.max(v, lo) / lo) / Math.log(hi / lo) : (v - lo) / (hi - lo);
  return Math.round(Math.min(Math.max(t, 0), 1) * SLIDER_STEPS);
}

export function fromSlider(c, s) {
  const [lo, hi] = c.slider, t = s / SLIDER_STEPS;
  const v = c.log ? lo * Math.pow(hi / lo, t) : lo + t * (hi - lo);
  return Number(v.toPrecision(4));
}

export const fmt = (v, digits = 4) => (typeof v === "number"
  ? Number(v.toPrecision(digits)).toString() : String(v));
// r, g, b as a colour's text box shows them: 3 digits each, so that a fitted colour's
// three values fit the sidebar's box
export const rgbText = (v) => v.map((x) => fmt(x, 3)).join(", ");

// linear <-> sRGB, as the server's tone mapping (output.tonemap)
export const srgb = (x) => (x <= 0.0031308 ? 12.92 * x : 1.055 * Math.pow(x, 1 / 2.4) - 0.055);
const linear = (c) => (c <= 0.04045 ? c / 12.92 : Math.pow((c + 0.055) / 1.055, 2.4));

export function toHex(rgb) {
  return "#" + rgb.map((x) => Math.round(Math.min(Math.max(srgb(x), 0), 1) * 255)
    .toString(16).padStart(2, "0")).join("");
}

export function fromHex(hex) {
  return [1, 3, 5].map((i) => Number(linear(parseInt(hex.substr(i, 2), 16) / 255).toFixed(4)));
}

export const asRgb = (v) => (Array.isArray(v) ? v : [v, v, v]);

// -- messages ---------------------------------------------------------------------------

// the status line of the header (a refusal of the server, a failed request)
export function say(text) { $("status").textContent = text || ""; }

// the error line of an entry (its plugin raised, the server refused a value)
export function entryError(id, text) {
  const e = document.querySelector(`#entry-${id} .error`);
  if (e) e.textContent = text || "";
}
