/* Teach Studio page: compare runs as in TensorBoard or Weights & Biases.
 *
 * "Compare runs" opens the run table: each run's settings (those that differ between the plotted
 * runs highlighted), its tags and notes (saved to <run>/notes.json, see docs/api.md), a filter by
 * name, tag and task that the run list follows, and a tick to plot it. The chart's smoothing
 * slider and "Export CSV" (every plotted run in one file, the server's curves.csv layout) are
 * wired here too.
 */

import { api, download } from "./api.js";
import { runColor, runLabel, runTask } from "./chart.js";
import { $, el, enc, fmtCpu, setProp, setText, showError } from "./dom.js";
import { reconcileRows, renderRuns, toggleShown } from "./runs.js";
import { runMatches } from "./runfilter.js";
import { S, listen, markCurvesDirty } from "./state.js";

/** Settings that say nothing about how a run learns (shown elsewhere, or its name). */
const NOT_SETTINGS = new Set(["name", "task"]); // the task has its own column (runTask)

/** A setting's value as the table shows it (lists joined, nothing as a dash). */
function shown(v) {
  if (v === undefined || v === null || (Array.isArray(v) && !v.length)) return "–";
  if (Array.isArray(v)) return v.join(", ");
  if (typeof v === "object") return JSON.stringify(v);
  return String(v);
}

/** A setting's name with a line-break opportunity after each underscore (planning_steps). */
function wrapAtUnderscores(key) {
  return key.split("_").flatMap((part, i, all) => (i < all.length - 1 ? [`${part}_`, el("wbr")] : [part]));
}

/** The settings columns: every config field any listed run has, with whether the plotted runs
 * differ in it (a field only some of them have differs too). */
function settingColumns(runs) {
  const keys = [];
  for (const r of runs) for (const k of Object.keys(r.config || {})) if (!NOT_SETTINGS.has(k) && !keys.includes(k)) keys.push(k);
  const plotted = runs.filter((r) => S.shown.has(r.id));
  return keys.map((key) => ({ key, differs: new Set(plotted.map((r) => shown((r.config || {})[key]))).size > 1 }));
}

async function saveNotes(r, row) {
  const tags = row.querySelector("[data-testid='compare-tags']").value.split(",").map((t) => t.trim()).filter(Boolean);
  const notes = row.querySelector("[data-testid='compare-notes']").value;
  showError("compare-error", null);
  try {
    const saved = await api("PUT", `/api/runs/${enc(r.id)}/notes`, { tags, notes });
    S.notes.set(r.id, saved);
    renderRuns();
  } catch (e) {
    showError("compare-error", `${runLabel(r)}: ${e.message}`);
  }
}

function compareRow(r, columns) {
  const label = runLabel(r);
  const plotted = S.shown.has(r.id);
  const row = el("tr", { "data-id": r.id, testid: "compare-row", class: plotted ? "" : "unplotted" });
  const save = () => saveNotes(r, row);
  row.append(
    el("td", {}, el("input", { type: "checkbox", "aria-label": `Plot ${label}`, checked: plotted,
      onchange: (e) => { toggleShown(r.id, e.target.checked); renderRuns(); } })),
    el("td", { class: "name", title: label }, el("span", { class: "swatch", style: `background:${runColor(r.id)}` }), label),
    el("td", { text: r.status }),
    el("td", { text: runTask(r) }),
    ...columns.map((c) => el("td", { class: c.differs && plotted ? "differs" : null, "data-key": c.key, text: shown((r.config || {})[c.key]) })),
    el("td", { class: "num", text: fmtCpu(r.cpu_seconds) }),
    el("td", {}, el("input", { type: "text", testid: "compare-tags", "aria-label": `Tags of ${label}`,
      placeholder: "tags: a, b", title: "Tags, comma separated", onchange: save })),
    el("td", {}, el("textarea", { rows: 1, testid: "compare-notes", "aria-label": `Notes of ${label}`, placeholder: "notes", onchange: save })),
  );
  row.drawn = row.outerHTML; // the browser may touch its fields' attributes (autofill's style)
  return row;
}

/** Show each run's stored tags and notes in its fields, except in the field being edited. The
 * values are not in the rows' HTML, so a save (here or in another page) never redraws a row
 * under the cursor. */
function syncNoteFields() {
  for (const row of $("compare-body").children) {
    const n = S.notes.get(row.dataset.id) || { tags: [], notes: "" };
    for (const [testid, value] of [["compare-tags", n.tags.join(", ")], ["compare-notes", n.notes]]) {
      const field = row.querySelector(`[data-testid='${testid}']`);
      if (field && field !== document.activeElement && field.value !== value) field.value = value;
    }
  }
}

/** Draw the run table (only while it is open: nothing is written to a closed dialog). */
export function renderCompare() {
  const dlg = $("compare-dialog");
  if (!dlg || !dlg.open) return;
  const all = S.runs.filter((r) => !r.damaged);
  const runs = all.filter((r) => runMatches(r));
  let columns = settingColumns(runs);
  if ($("compare-differing").checked) columns = columns.filter((c) => c.differs);
  const head = el("tr", {}, el("th", {}), el("th", { text: "run" }), el("th", { text: "status" }), el("th", { text: "task" }),
    ...columns.map((c) => el("th", { class: c.differs ? "differs" : null, "data-key": c.key, title: c.differs ? "the plotted runs differ here" : "" }, ...wrapAtUnderscores(c.key))),
    el("th", { class: "num", text: "CPU" }), el("th", { text: "tags" }), el("th", { text: "notes" }));
  reconcileRows($("compare-head"), [head]);
  reconcileRows($("compare-body"), runs.map((r) => compareRow(r, columns)));
  syncNoteFields();
  const differ = columns.filter((c) => c.differs).length;
  setText("compare-summary", `${runs.length} of ${all.length} runs · ${S.shown.size} plotted · ${differ} setting${differ === 1 ? "" : "s"} differ`);
}

function exportCsv() {
  const ids = [...S.runs].reverse().filter((r) => S.shown.has(r.id) && !r.damaged).map((r) => r.id);
  if (!ids.length) { showError("curve-error", "No run is plotted; tick the runs to export."); return; }
  download(`/api/run-curves.csv?${ids.map((id) => `run=${enc(id)}`).join("&")}`, "curves.csv", "curve-error");
}

/** Open the run table (on the plotted runs: tick the ones to compare first). */
export function openCompare() {
  const dlg = $("compare-dialog");
  if (!dlg.open) dlg.show();
  setProp($("compare-open"), "ariaExpanded", "true");
  renderCompare();
  $("compare-filter").focus();
}

export function wireCompare() {
  listen("drawnRuns", renderCompare);
  $("curve-smooth").addEventListener("input", () => {
    setText("curve-smooth-value", Number($("curve-smooth").value).toFixed(2));
    markCurvesDirty();
  });
  $("curve-csv").addEventListener("click", exportCsv);
  $("compare-open").addEventListener("click", () => {
    if ($("compare-dialog").open) { $("compare-dialog").close(); return; }
    openCompare();
  });
  $("compare-dialog").addEventListener("keydown", (e) => { if (e.key === "Escape") $("compare-dialog").close(); });
  $("compare-dialog").addEventListener("close", () => setProp($("compare-open"), "ariaExpanded", "false"));
  $("compare-filter").addEventListener("input", (e) => { S.runFilter = e.target.value; renderRuns(); });
  $("compare-differing").addEventListener("change", renderCompare);
}
