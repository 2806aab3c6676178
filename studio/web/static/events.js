/* Teach Studio page: the live stream: one EventSource('/api/events') feeds every list, the status and the chart. */

import { renderCurves } from "./chart.js";
import { loadDemos, updateMarkButton } from "./demos.js";
import { $, setProp, setText } from "./dom.js";
import { loadPolicies, renderWatchChoices } from "./policies.js";
import { loadRecordings, renderCaptureButton } from "./recordings.js";
import { loadCurve, loadRuns, mergeCurve, renderRuns, upsertRun } from "./runs.js";
import { renderSource } from "./sources.js";
import { S } from "./state.js";

// Live updates (the chart and the run list's progress) are drawn together, at most this often:
// without a GPU every repaint of the page is composited by the CPU that trains, so two timers
// drawing apart would cost two frames where one does.
export const CURVE_FPS = 6;

export let events = null;
export function connectEvents() {
  if (events) events.close();
  events = new EventSource("/api/events");
  const conn = $("conn");
  events.onopen = () => { setText(conn, "live"); setProp(conn, "className", "chip ok"); };
  events.onerror = () => {
    conn.textContent = "reconnecting…"; conn.className = "chip bad";
  };
  events.addEventListener("source", (e) => { S.source = JSON.parse(e.data); renderSource(); });
  events.addEventListener("capture", (e) => { S.capture = JSON.parse(e.data); renderCaptureButton(); updateMarkButton(); });
  events.addEventListener("run", (e) => {
    const d = JSON.parse(e.data);
    if (!d.run) return;
    const before = S.runs.find((r) => r.id === d.run.id);
    upsertRun(d.run);
    if (!before && !S.shownTouched) S.shown.add(d.run.id);
    if (d.curve) mergeCurve(d.run.id, d.curve, d.from);
    for (const p of d.pieces || []) mergeCurve(d.run.id, p.curve, p.from, p.to);
    scheduleRunsRender();
    if (before && before.status !== d.run.status && !["running", "queued"].includes(d.run.status)) {
      loadCurve(d.run.id);
      renderWatchChoices();
      loadPolicies();
    }
  });
  events.addEventListener("lists", (e) => {
    const d = JSON.parse(e.data);
    ({ recordings: loadRecordings, demonstrations: loadDemos, runs: loadRuns, policies: loadPolicies }[d.changed] || (() => {}))();
  });
}

let runsRenderPending = false;
function scheduleRunsRender() { // drawn by the next renderLive, in the same frame as the chart
  runsRenderPending = true;
}
export function renderLive() {
  if (runsRenderPending) {
    runsRenderPending = false;
    renderRuns();
  }
  renderCurves();
}
