/* Teach Studio page: the live stream: one EventSource('/api/events') feeds every list, the status and the chart. */

import { renderCurves } from "./chart.js";
import { loadDemos, updateMarkButton } from "./demos.js";
import { $, setProp, setText } from "./dom.js";
import { loadPolicies, renderWatchChoices } from "./policies.js";
import { loadRecordings, renderCaptureButton } from "./recordings.js";
import { loadCurve, loadRuns, mergeCurve, renderRuns, upsertRun } from "./runs.js";
import { S, set } from "./state.js";

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
  events.addEventListener("source", (e) => set("source", JSON.parse(e.data)));
  events.addEventListener("capture", (e) => { S.capture = JSON.parse(e.data); renderCaptureButton(); updateMarkButton(); });
  events.addEventListener("run", (e) => {
    const d = JSON.parse(e.data);
    if (!d.run) return;
    const before = S.runs.find((r) => r.id === d.run.id);
    upsertRun(d.run);
    if (!before && !S.shownTouched) S.shown.add(d.run.id);
    if (d.curve) mergeCurve(d.run.id, d.curve, d.from);
    for (const p of d.pieces || []) mergeCurve(d.run.id, p.curve, p.from, p.to);
    scheduleRunsRender(!before || before.status !== d.run.status);
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

// A running run's row (its progress bar and CPU time) is redrawn every RUNS_EVERY_FRAMES live
// frames, not with every frame of the chart: rebuilding and laying out the list was most of the
// page's own work while a run trained, for a bar that moves a pixel. A live frame is one with news
// to draw (the timer's ticks without any are not counted: when a busy machine sends news less
// often than the timer ticks, counting ticks redrew the row with every frame of the chart). A run
// that appears or changes status is drawn with the next frame.
export const RUNS_EVERY_FRAMES = 3;
let runsRenderPending = false;
let runsRenderUrgent = false;
let framesSinceRuns = 0;
function scheduleRunsRender(urgent) { // drawn by a coming renderLive, in the same frame as the chart
  runsRenderPending = true;
  runsRenderUrgent ||= urgent;
}
export function renderLive() {
  if (!S.curveDirty && !runsRenderPending) return; // nothing new since the last frame
  framesSinceRuns++;
  if (runsRenderPending && (runsRenderUrgent || framesSinceRuns >= RUNS_EVERY_FRAMES)) {
    runsRenderPending = false;
    runsRenderUrgent = false;
    framesSinceRuns = 0;
    renderRuns();
  }
  renderCurves();
}
