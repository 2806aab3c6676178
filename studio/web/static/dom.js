/* Teach Studio page: the page's DOM helpers: look-ups, writes that skip unchanged values, rows, formats. */

export const $ = (id) => document.getElementById(id);

export function showError(id, err) {
  const el = $(id);
  if (!el) return;
  if (!err) { setProp(el, "hidden", true); setText(el, ""); return; }
  setText(el, err instanceof Error ? err.message : String(err));
  setProp(el, "hidden", false);
}

/** Write a text or a property only when it changes: an unchanged value then costs no style,
 * layout or paint. The live stream re-sends the same status several times a second, and with
 * software rendering every repaint of the page costs the training run CPU. */
export function setText(idOrEl, text) {
  const e = typeof idOrEl === "string" ? $(idOrEl) : idOrEl;
  text = String(text);
  if (e && e.textContent !== text) e.textContent = text;
}
export function setProp(idOrEl, prop, value) { // also a dataset: setProp(e.dataset, "x", "1")
  const e = typeof idOrEl === "string" ? $(idOrEl) : idOrEl;
  if (e && e[prop] !== value) e[prop] = value;
}

export function confirmDialog(text, okLabel = "Delete") {
  const dlg = $("confirm-dialog");
  setText("confirm-text", text);
  dlg.querySelector('[data-testid="confirm-ok"]').textContent = okLabel;
  dlg.returnValue = "";
  dlg.showModal();
  return new Promise((resolve) => {
    dlg.addEventListener("close", () => resolve(dlg.returnValue === "ok"), { once: true });
  });
}

export const enc = encodeURIComponent;
export const fmt = (x, d = 1) => (x === null || x === undefined || Number.isNaN(x) ? "–" : Number(x).toFixed(d));
export function fmtDuration(s) {
  if (s === null || s === undefined) return "–";
  if (s < 60) return `${s.toFixed(1)} s`;
  const m = Math.floor(s / 60);
  return `${m}:${String(Math.floor(s - 60 * m)).padStart(2, "0")}`;
}
export function fmtCpu(s) {
  if (!s) return "0 s";
  return s < 100 ? `${s.toFixed(1)} s` : `${(s / 60).toFixed(1)} min`;
}
export function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null || v === false) continue;
    if (k === "class") e.className = v;
    else if (k === "text") e.textContent = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else if (k === "testid") e.dataset.testid = v;
    else e.setAttribute(k, v === true ? "" : v);
  }
  for (const c of children) if (c !== null && c !== undefined) e.append(c);
  return e;
}
export function emptyRow(cols, text) {
  return el("tr", { class: "empty" }, el("td", { colspan: cols, text }));
}
export function fillSelect(sel, items, keep = true) {
  const old = sel.value;
  sel.replaceChildren(...items.map(([value, label]) => el("option", { value, text: label })));
  if (keep && items.some(([v]) => v === old)) sel.value = old;
}

export function flashRow(bodyId, name) {
  if (!name) return;
  const row = $(bodyId).querySelector(`tr[data-name="${CSS.escape(name)}"]`);
  if (row) { row.classList.add("selected"); setTimeout(() => row.classList.remove("selected"), 2500); }
}

/** A list's group heading row (the shipped samples under the user's own files). */
export function groupRow(cols, text, testid) {
  return el("tr", { class: "group", testid }, el("td", { colspan: cols, text }));
}
