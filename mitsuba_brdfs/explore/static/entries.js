// The explorer page, part 2 of 4: the entries' panels (one per BSDF: its controls,
// XML, errors) on the left.
"use strict";

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

