// The entries' panels on the left, one per BSDF: its colour, visibility and name, its
// controls (one per parameter; which parametrisation is in use), its export and check; a
// measured entry's fit form and a fitted entry's result (fit.js).

import { state } from "./state.js";
import { api } from "./server.js";
import { ALL, draw } from "./plots.js";
import { redraw, setParam, slideParam } from "./redraw.js";
import { refineSpheres, spheresStopped } from "./spheres.js";
import { fitButtons, fitInfo, measuredPanel } from "./fit.js";
import { $, SLIDER_STEPS, asRgb, el, entryError, fmt, fromHex, fromSlider, rgbText, toHex,
         toSlider } from "./values.js";

// -- controls ----------------------------------------------------------------------------

function tooltip(e, c) {
  let text = c.doc || "";
  if (c.range) text += `${text ? " " : ""}Range: ${c.range}.`;
  const instead = e.controls.filter((x) => x.active && c.alternatives.includes(x.name));
  if (!c.active) {
    text += (instead.length
      ? ` Not in use: the plugin takes ${instead.map((x) => x.name).join(", ")} instead now;` +
        " setting it switches."
      : " Not in use with these settings (the plugin does not read it now).");
  }
  return text.trim();
}

// What changed in the entry besides the value of control `name` (then the panel is drawn
// again: a partner took a value, an alternative went out of use).
function changedBesides(before, after, name) {
  const strip = (cs) => JSON.stringify(cs.map((c) => (c.name === name ? { ...c, value: 0 } : c)));
  return strip(before) !== strip(after);
}

// A change sent: the panel follows the server's answer (on a refusal, the values it holds).
async function send(e, name, value, { slide = false } = {}) {
  const before = e.controls;
  const applied = (s, err) => {
    if (err) { renderEntry(e, err.message); return; }
    entryError(e.id, "");
    if (!slide || changedBesides(before, s.controls, name)) renderEntry(e);
  };
  if (slide) { slideParam(e, name, value, applied); return; }
  try { applied(await setParam(e, name, value), null); } catch (err) { applied(null, err); }
}

function numberControl(e, c) {
  const slider = { ...c, slider: c.slider || [c.lo, c.hi] };
  const range = el("input", { type: "range", min: 0, max: SLIDER_STEPS, title: tooltip(e, c),
                              aria: { label: `${c.name} slider` } });
  range.value = toSlider(slider, c.value ?? slider.slider[0]);
  const text = el("input", { type: "text", value: c.value === null ? "" : fmt(c.value),
                             title: tooltip(e, c), aria: { label: c.name } });
  range.addEventListener("input", () => {
    let v = fromSlider(slider, +range.value);
    if (c.kind === "int") v = Math.round(v);
    text.value = fmt(v);
    send(e, c.name, v, { slide: true });
  });
  text.addEventListener("change", () => send(e, c.name, text.value.trim()));
  return [range, text];
}

function colourControl(e, c) {
  const pick = el("input", { type: "color", value: toHex(asRgb(c.value ?? 0)),
                             title: "pick a colour", aria: { label: `${c.name} colour` } });
  pick.disabled = c.hi === null || c.hi > 1;
  const text = el("input", { type: "text", title: tooltip(e, c), aria: { label: c.name },
                             value: Array.isArray(c.value) ? rgbText(c.value)
                                                           : fmt(c.value ?? 0) });
  pick.addEventListener("input", () => {
    const v = fromHex(pick.value);
    text.value = rgbText(v);
    send(e, c.name, v, { slide: true });
  });
  text.addEventListener("change", () => send(e, c.name, text.value.trim()));
  return [el("span", { class: "colour wide" }, pick, text)];
}

function control(e, c) {
  const row = el("div", { class: `ctl${c.set ? "" : " unset"}${c.active ? "" : " inactive"}` });
  row.dataset.name = c.name;
  const name = el("span", { class: "name", title: tooltip(e, c) }, c.name);
  let widgets;
  if (c.kind === "float" || c.kind === "int") widgets = numberControl(e, c);
  else if (c.kind === "colour") widgets = colourControl(e, c);
  else if (c.kind === "choice") {
    const select = el("select", { class: "wide", title: tooltip(e, c), aria: { label: c.name } });
    for (const ch of c.choices) select.add(new Option(ch, ch, false, ch === c.value));
    select.addEventListener("change", () => send(e, c.name, select.value));
    widgets = [select];
  } else if (c.kind === "bool") {
    const box = el("input", { type: "checkbox", checked: !!c.value, title: tooltip(e, c),
                              aria: { label: c.name } });
    box.addEventListener("change", () => send(e, c.name, box.checked));
    widgets = [el("span", { class: "wide" }, box)];
  } else {
    widgets = [el("span", { class: "note wide" }, `${c.value} (a texture: set it in XML)`)];
  }
  const reset = el("button", { class: "reset", textContent: "\u21ba",
                               title: "back to the default" });
  reset.disabled = !c.set || !e.exportable;
  reset.addEventListener("click", () => send(e, c.name, null));
  row.append(name, ...widgets, reset);
  return row;
}

// "in use: nu, nv (or alpha_u + alpha_v, or alpha)": the parametrisation in force, of the
// parameters that have alternatives.
function parametrisation(e) {
  const alt = e.controls.filter((c) => c.alternatives.length);
  if (!alt.length) return null;
  const groups = [], seen = new Set();
  for (const c of alt) {
    if (seen.has(c.name)) continue;
    const members = [c, ...alt.filter((x) => c.partners.includes(x.name))];
    members.forEach((m) => seen.add(m.name));
    groups.push({ text: members.map((m) => m.name).join(" + "),
                  active: members.some((m) => m.active) });
  }
  const used = groups.filter((g) => g.active).map((g) => g.text);
  const other = groups.filter((g) => !g.active).map((g) => g.text);
  const text = used.length ? `in use: ${used.join(", ")}` : "none of them in use with these settings";
  return el("div", { class: "param" }, `${text}${other.length ? ` (or ${other.join(", or ")}: ` +
    "setting one switches)" : ""}`);
}

// -- export and check --------------------------------------------------------------------

function copyButton(textarea) {
  const b = el("button", { textContent: "Copy" });
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
    out.replaceChildren();
    for (const [title, text] of [["Mitsuba XML", x.xml], ["load_dict", x.python]]) {
      const t = el("textarea", { value: text, readOnly: true, aria: { label: title } });
      out.append(el("div", { class: "row" }, title, copyButton(t)), t);
    }
  } catch (err) { entryError(e.id, err.message); }
}

// The check buttons follow the check running: its own offers to cancel it, the others
// wait (one check at a time).
function checkButtons() {
  for (const b of document.querySelectorAll("button.check")) {
    const id = +b.dataset.id, running = state.check;
    b.textContent = running && running.id === id ? "Cancel check" : "Check";
    b.disabled = !!running && running.id !== id;
    b.title = running && running.id !== id
      ? `one check at a time: ${running.label}'s is running`
      : running ? "stop the check (after the test under way)"
                : "run the check suite (quick settings) on this BSDF";
  }
}

function checkTable(r) {
  const rows = r.checks.map((c) => el("tr", {}, el("td", { class: c.status }, c.status),
                                      el("td", {}, c.name), el("td", {}, c.message)));
  const verdict = r.passed ? "PASS" : "FAIL";
  return [el("b", { class: verdict }, verdict), " (check, quick settings)",
          el("table", {}, el("tbody", {}, ...rows))];
}

async function check(e, out) {
  if (state.check) {  // the button of the check running cancels it
    await api("DELETE", "/api/check").catch((err) => entryError(e.id, err.message));
    if (state.check.mine) out.textContent = "cancelling: the test under way ends first\u2026";
    else { state.check = null; checkButtons(); }  // (another page's check)
    return;
  }
  state.check = { id: e.id, label: e.label, mine: true };
  checkButtons();
  out.textContent = "running the check suite (quick settings)\u2026 One check runs at a " +
                    "time; \u201cCancel check\u201d stops it.";
  try {
    const r = await api("POST", `/api/check/${e.id}`, {});
    out.replaceChildren(...(r.cancelled ? ["check cancelled"] : checkTable(r)));
  } catch (err) {
    out.textContent = "";
    entryError(e.id, err.message);
  }
  state.check = null;
  checkButtons();
}

// -- the panel ---------------------------------------------------------------------------

export function renderEntry(e, error) {
  let sec = $(`entry-${e.id}`);
  if (!sec) {
    sec = el("section", { id: `entry-${e.id}`, class: "entry", aria: { label: e.label } });
    $("entries").append(sec);
  }
  sec.style.borderLeftColor = e.colour;
  const colour = el("input", { type: "color", value: e.colour, title: "colour in the plots",
                               aria: { label: `colour of ${e.label}` } });
  colour.addEventListener("input", async () => {
    e.colour = colour.value;
    sec.style.borderLeftColor = e.colour;
    draw(ALL);
    refineSpheres();
    await api("PATCH", `/api/entries/${e.id}`, { colour: e.colour })
      .catch((err) => entryError(e.id, err.message));
  });
  const shown = el("input", { type: "checkbox", checked: e.visible, title: "draw it",
                              aria: { label: `draw ${e.label}` } });
  shown.addEventListener("change", async () => {
    e.visible = shown.checked;
    await api("PATCH", `/api/entries/${e.id}`, { visible: e.visible })
      .catch((err) => entryError(e.id, err.message));
    redraw();
  });
  const remove = el("button", { textContent: "\u00d7", title: "remove this BSDF",
                                aria: { label: `remove ${e.label}` } });
  remove.addEventListener("click", async () => {
    await spheresStopped();
    try {
      await api("DELETE", `/api/entries/${e.id}`);
    } catch (err) { entryError(e.id, err.message); return; }
    state.entries = state.entries.filter((x) => x.id !== e.id);
    state.data.delete(e.id);
    sec.remove();
    draw(ALL);
    refineSpheres();
  });
  const head = el("div", { class: "head" }, colour, shown,
                  el("span", { class: "label", title: e.plugin }, e.label), remove);
  const controls = el("div", { class: "controls" }, ...e.controls.map((c) => control(e, c)));
  // the export and the check each have their own area: both stay shown
  const exported = el("div", { class: "output export" });
  const checked = el("div", { class: "output check" });
  const exp = el("button", { textContent: "Export", disabled: !e.exportable,
                             title: "as Mitsuba XML and as a load_dict call" });
  exp.addEventListener("click", () => showExport(e, exported));
  const chk = el("button", { class: "check" });
  chk.dataset.id = e.id;
  chk.addEventListener("click", () => check(e, checked));
  const param = parametrisation(e);
  const extra = e.measured ? measuredPanel(e, added) : e.fit ? [fitInfo(e)] : [];
  sec.replaceChildren(head, el("div", { class: "error" }, error || ""),
                      ...(param ? [param] : []), ...extra,
                      ...(e.controls.length ? [controls] : []),
                      el("div", { class: "actions" }, exp, chk), exported, checked);
  checkButtons();
  fitButtons();
}

// A BSDF the server added (a fitted model): its panel and its plots.
function added(e) {
  state.entries.push(e);
  renderEntry(e);
  redraw(ALL, [e.id]);
}
