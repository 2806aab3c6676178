/* Teach Studio page: talks to the API in docs/api.md, renders lists, live status and curves.
 *
 * ES modules, no build step: this one wires the page and starts it. Read the others by what they
 * show: sources, recordings (and capture), demos, training (the form), runs, chart (curves.js holds
 * the averaging rule the server shares), policies, scene; events is the live stream that feeds
 * them; api and dom are the helpers; state the one state and its announcements. Live data arrives over
 * one EventSource('/api/events'); the curve chart (uPlot) gets new data at most CURVE_FPS times a
 * second, whatever the event rate.
 */

import { api, guarded } from "./api.js";
import { fitChart } from "./chart.js";
import { cutDemo, loadDemos, setDemoRange, syncDemoRange, toggleMark, updateMarkButton } from "./demos.js";
import { $, showError } from "./dom.js";
import { CURVE_FPS, connectEvents, renderLive } from "./events.js";
import { exportFile, loadPolicies, uploadPolicy, watch } from "./policies.js";
import { dismissCaptureFailure, loadRecordings, renderCaptureButton, saveRecordingEdit, toggleCapture, uploadRecording } from "./recordings.js";
import { loadRuns } from "./runs.js";
import { wireCompare } from "./compare.js";
import { loadConfig, softwareWebGL } from "./scene.js";
import { buildExportControl } from "./exports.js";
import { applySource, loadRobots, playback, setRetarget, setRobot, simulatorReach, syncKindOptions } from "./sources.js";
import { S, listen, markCurvesDirty, set } from "./state.js";
import { checkTrainForm, resetTrainForm, startRun, syncTaskFields } from "./training.js";
import { addObstacle, refreshObstacles } from "./obstacles.js";

function wire() {
  // The buttons that follow the live source, after its status line; camera.js listens after them.
  listen("source", () => { renderCaptureButton(); updateMarkButton(); });
  $("source-kind").addEventListener("change", syncKindOptions);
  $("source-apply").addEventListener("click", applySource);
  $("playback-toggle").addEventListener("click", () => playback($("playback-toggle").dataset.playing === "1" ? "pause" : "play"));
  const seek = $("playback-seek");
  seek.addEventListener("input", () => { seek.dataset.dragging = "1"; });
  seek.addEventListener("change", () => { delete seek.dataset.dragging; playback("seek", { t: Number(seek.value) }); });
  $("playback-speed").addEventListener("change", () => {
    if (S.source && S.source.kind === "recording") playback(S.source.playback && S.source.playback.playing ? "play" : "pause", { speed: Number($("playback-speed").value) });
  });
  $("playback-loop").addEventListener("change", async () => {
    if (!(S.source && S.source.kind === "recording")) return;
    // Live updates must not flip the box back while the change is on its way; the server
    // changes the loop of the recording playing in place (no restart).
    const box = $("playback-loop");
    box.dataset.pending = "1";
    try { await applySource(); } finally { delete box.dataset.pending; }
  });
  $("source-reach").addEventListener("click", () => simulatorReach("reach"));
  $("source-wander").addEventListener("click", () => simulatorReach("wander"));
  $("retarget-mode").addEventListener("change", setRetarget);
  $("retarget-mirror").addEventListener("change", setRetarget);
  $("robot-name").addEventListener("change", setRobot);
  for (const kind of ["recording", "demonstration", "rollout"]) buildExportControl(kind);

  $("capture-toggle").addEventListener("click", toggleCapture);
  $("capture-failure-dismiss").addEventListener("click", dismissCaptureFailure);
  $("recording-upload").addEventListener("change", (e) => uploadRecording(e.target));
  $("edit-form").addEventListener("submit", saveRecordingEdit);

  $("demo-recording").addEventListener("change", () => { setDemoRange(0, 0); syncDemoRange(); });
  $("demo-t0-range").addEventListener("input", () => {
    const t0 = Math.min(Number($("demo-t0-range").value), Number($("demo-t1-range").value));
    setDemoRange(t0, Number($("demo-t1-range").value));
  });
  $("demo-t1-range").addEventListener("input", () => {
    const t1 = Math.max(Number($("demo-t1-range").value), Number($("demo-t0-range").value));
    setDemoRange(Number($("demo-t0-range").value), t1);
  });
  for (const id of ["demo-t0", "demo-t1"]) {
    $(id).addEventListener("change", () => setDemoRange(Number($("demo-t0").value) || 0, Number($("demo-t1").value) || 0));
  }
  $("demo-cut").addEventListener("click", cutDemo);
  $("demo-mark").addEventListener("click", toggleMark);

  $("train-form").addEventListener("submit", startRun);
  $("train-form").elements.task.addEventListener("change", syncTaskFields);
  $("train-form").addEventListener("change", (ev) => { if (ev.target.closest("#train-demos, .goal3") || ["task", "bins"].includes(ev.target.name)) checkTrainForm(); });
  $("train-defaults").addEventListener("click", resetTrainForm);
  $("train-add-obstacle").addEventListener("click", addObstacle);
  refreshObstacles(); // boxes placed before a reload stay listed
  $("train-defaults").addEventListener("click", syncTaskFields); // after the reset above
  $("curve-log").addEventListener("change", markCurvesDirty);
  $("curve-band").addEventListener("change", markCurvesDirty);
  $("curve-x").addEventListener("change", markCurvesDirty);
  wireCompare(); // the run table, smoothing and the CSV of plotted runs

  $("watch-go").addEventListener("click", watch);
  $("watch-stop").addEventListener("click", () => guarded("watch-error", () => api("POST", "/api/watch/stop")));
  $("policy-upload").addEventListener("change", (e) => uploadPolicy(e.target));
  for (const b of document.querySelectorAll("[data-dl]")) b.addEventListener("click", () => exportFile(b.dataset.dl));
}

async function main() {
  wire();
  syncKindOptions();
  updateMarkButton();
  renderCaptureButton();
  setInterval(renderLive, 1000 / CURVE_FPS);
  new ResizeObserver(fitChart).observe($("curve-plot"));
  connectEvents();
  S.softwareScene = softwareWebGL();
  await loadConfig();
  const initial = api("GET", "/api/source").then((s) => {
    if (s.kind) $("source-kind").value = s.kind;
    syncKindOptions();
    set("source", s);
  }).catch((e) => showError("source-error", e));
  const cap = api("GET", "/api/capture").then((c) => { S.capture = c; renderCaptureButton(); updateMarkButton(); }).catch(() => {});
  const mark = api("GET", "/api/demonstrations/mark").then((m) => {
    S.marking = !!(m && m.marking);
    S.markT0 = m && m.t0;
    updateMarkButton();
  }).catch(() => {});
  await Promise.all([initial, cap, mark, loadRobots(), loadRecordings(), loadDemos(), loadRuns(), loadPolicies()]);
  if (S.source && S.source.recording) $("source-recording").value = S.source.recording;
  document.body.dataset.ready = "1";
}

main();
