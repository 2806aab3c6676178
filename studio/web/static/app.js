/* Teach Studio page: talks to the API in docs/api.md, renders lists, live status and curves.
 *
 * Plain JS, no build step. Live data arrives over one EventSource('/api/events'); the curve chart
 * (uPlot) gets new data at most CURVE_FPS times a second, whatever the event rate.
 */
"use strict";

// Live updates (the chart and the run list's progress) are drawn together, at most this often:
// without a GPU every repaint of the page is composited by the CPU that trains, so two timers
// drawing apart would cost two frames where one does.
const CURVE_FPS = 6;
// Without a GPU the scene is drawn at this device-pixel ratio (a quarter of the pixels at 0.5):
// a still scene then costs about 0.09 instead of 0.15 cores, a moving one far less, and that
// CPU goes to training instead. A browser with a GPU draws at its own ratio.
const SOFTWARE_SCENE_DPR = 0.5;
const SOFTWARE_RENDERERS = /swiftshader|llvmpipe|softpipe|software/i;
const PALETTE = ["#2a62b8", "#d9822b", "#23874b", "#b83280", "#6b4fbb", "#0f8b8d", "#a0522d", "#7a7a7a"];
const $ = (id) => document.getElementById(id);

/* ------------------------------------------------------------------ state */
const S = {
  config: null,
  source: null,
  capture: null,
  recordings: [],
  demos: [],
  runs: [],
  sweeps: [], // `studio sweep` summaries (GET /api/sweeps); their trials are runs of a group
  openSweeps: new Set(), // sweep ids unfolded in the run list (table, figure, runs)
  policies: [],
  curves: new Map(), // run id -> {episodes, mean, std, min, max, count}
  shown: new Set(), // run ids plotted
  shownTouched: false, // the user changed which runs are plotted
  marking: false,
  watchedRun: null,
  curveDirty: true,
  softwareScene: false, // WebGL is drawn in software here: the scene gets a lower resolution
};
window.studio = S; // for the browser tests and for poking around in the console

/* ------------------------------------------------------------------ API helpers */
class ApiError extends Error {}

async function api(method, path, body) {
  const opts = { method, headers: {} };
  if (body instanceof FormData) {
    opts.body = body;
  } else if (body !== undefined) {
    opts.headers["Content-Type"] = "application/json";
    opts.body = JSON.stringify(body);
  }
  let resp;
  try {
    resp = await fetch(path, opts);
  } catch (e) {
    throw new ApiError("The studio server is not reachable; check that `studio serve` is still running.");
  }
  if (resp.status === 204) return null;
  const text = await resp.text();
  let data = null;
  try { data = text ? JSON.parse(text) : null; } catch (e) { data = null; }
  if (!resp.ok) {
    const err = new ApiError(detailOf(data, resp, text));
    err.data = data; // e.g. a refused form: {detail, problems, by_field}
    throw err;
  }
  return data;
}

function detailOf(data, resp, text) {
  if (data && data.detail !== undefined) {
    const d = data.detail;
    if (typeof d === "string") return d;
    if (Array.isArray(d)) return d.map((x) => (x && x.msg) || JSON.stringify(x)).join("; ");
    return JSON.stringify(d);
  }
  if (resp.status === 413) return "The file is larger than the upload limit.";
  if (resp.status === 404) return `Not found (${resp.url.replace(location.origin, "")}): this server does not offer that yet.`;
  return `The server answered ${resp.status} ${resp.statusText}${text ? ": " + text.slice(0, 200) : ""}.`;
}

function showError(id, err) {
  const el = $(id);
  if (!el) return;
  if (!err) { setProp(el, "hidden", true); setText(el, ""); return; }
  setText(el, err instanceof Error ? err.message : String(err));
  setProp(el, "hidden", false);
}

/** Write a text or a property only when it changes: an unchanged value then costs no style,
 * layout or paint. The live stream re-sends the same status several times a second, and with
 * software rendering every repaint of the page costs the training run CPU. */
function setText(idOrEl, text) {
  const e = typeof idOrEl === "string" ? $(idOrEl) : idOrEl;
  text = String(text);
  if (e && e.textContent !== text) e.textContent = text;
}
function setProp(idOrEl, prop, value) { // also a dataset: setProp(e.dataset, "x", "1")
  const e = typeof idOrEl === "string" ? $(idOrEl) : idOrEl;
  if (e && e[prop] !== value) e[prop] = value;
}

/** Run an action, showing its error (or clearing the old one) next to the control. */
async function guarded(errId, fn, button) {
  showError(errId, null);
  if (button) button.disabled = true;
  try {
    return await fn();
  } catch (e) {
    showError(errId, e);
    if (!(e instanceof ApiError)) console.error(e);
    return undefined;
  } finally {
    if (button) button.disabled = false;
  }
}

/** Fetch a file and save it, so that a refusal (409, 404) shows up as a message, not a page. */
async function download(url, fallbackName, errId) {
  showError(errId, null);
  let resp;
  try {
    resp = await fetch(url);
  } catch (e) {
    showError(errId, "The studio server is not reachable.");
    return;
  }
  if (!resp.ok) {
    const text = await resp.text();
    let data = null;
    try { data = JSON.parse(text); } catch (e) { data = null; }
    showError(errId, detailOf(data, resp, text));
    return;
  }
  const blob = await resp.blob();
  const cd = resp.headers.get("Content-Disposition") || "";
  const m = /filename\*?=(?:UTF-8'')?"?([^";]+)"?/i.exec(cd);
  const name = m ? decodeURIComponent(m[1]) : fallbackName;
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.appendChild(a);
  a.click();
  setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
}

function confirmDialog(text, okLabel = "Delete") {
  const dlg = $("confirm-dialog");
  setText("confirm-text", text);
  dlg.querySelector('[data-testid="confirm-ok"]').textContent = okLabel;
  dlg.returnValue = "";
  dlg.showModal();
  return new Promise((resolve) => {
    dlg.addEventListener("close", () => resolve(dlg.returnValue === "ok"), { once: true });
  });
}

const enc = encodeURIComponent;
const fmt = (x, d = 1) => (x === null || x === undefined || Number.isNaN(x) ? "–" : Number(x).toFixed(d));
function fmtDuration(s) {
  if (s === null || s === undefined) return "–";
  if (s < 60) return `${s.toFixed(1)} s`;
  const m = Math.floor(s / 60);
  return `${m}:${String(Math.floor(s - 60 * m)).padStart(2, "0")}`;
}
function fmtCpu(s) {
  if (!s) return "0 s";
  return s < 100 ? `${s.toFixed(1)} s` : `${(s / 60).toFixed(1)} min`;
}
function el(tag, attrs = {}, ...children) {
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
function emptyRow(cols, text) {
  return el("tr", { class: "empty" }, el("td", { colspan: cols, text }));
}
function fillSelect(sel, items, keep = true) {
  const old = sel.value;
  sel.replaceChildren(...items.map(([value, label]) => el("option", { value, text: label })));
  if (keep && items.some(([v]) => v === old)) sel.value = old;
}

/* ------------------------------------------------------------------ source */
function renderSource() {
  const s = S.source;
  if (!s) return;
  setText("top-source-kind", s.kind ? (s.kind === "recording" ? `recording ${s.recording || ""}` : s.kind) : "none");
  setText("top-rate", fmt(s.rate_hz, 0));
  setText("top-dropped", s.dropped ?? "–");
  setText("src-running", s.running ? "yes" : "no");
  setText("src-rate", fmt(s.rate_hz, 1));
  setText("src-frames", s.frames ?? "–");
  setText("src-dropped", s.dropped ?? "–");
  setText("src-residual", fmt(s.fit_residual_mm, 1));
  setText("src-q", (s.q_robot || []).map((v) => ((v * 180) / Math.PI).toFixed(0).padStart(4)).join(" ") + " °");
  // The source's own trouble (no device, a dropped bridge) stays apart from a refused action.
  showError("source-status-error", s.error ? `Source: ${s.error}` : null);
  const rejected = s.rejected ? `${s.rejected} datagram${s.rejected === 1 ? "" : "s"} rejected` : "";
  const warning = [s.warning, rejected].filter(Boolean).join(" · ");
  setProp("source-warning", "hidden", !warning);
  setText("source-warning", warning);
  if (document.activeElement !== $("retarget-mode") && s.retarget) setProp("retarget-mode", "value", s.retarget.mode);
  if (s.retarget) setProp("retarget-mirror", "checked", !!s.retarget.mirror);
  const pb = s.playback;
  setProp("playback", "hidden", !(s.kind === "recording" && pb));
  if (pb) {
    setText("playback-toggle", pb.playing ? "❚❚" : "▶");
    setProp($("playback-toggle").dataset, "playing", pb.playing ? "1" : "0");
    const seek = $("playback-seek");
    setProp(seek, "max", String(Math.max(pb.duration, 0.01)));
    if (!seek.dataset.dragging) setProp(seek, "value", String(pb.t));
    setText("playback-time", `${pb.t.toFixed(1)} / ${pb.duration.toFixed(1)} s`);
    if (document.activeElement !== $("playback-speed")) {
      const sp = String(pb.speed);
      if ([...$("playback-speed").options].some((o) => o.value === sp)) setProp("playback-speed", "value", sp);
    }
    if (!$("playback-loop").dataset.pending) setProp("playback-loop", "checked", !!pb.loop);
  }
  renderCaptureButton();
  updateMarkButton();
  document.dispatchEvent(new CustomEvent("studio:source", { detail: s })); // camera.js follows it
}

function syncKindOptions() {
  const kind = $("source-kind").value;
  for (const e of document.querySelectorAll(".kind-opt")) e.hidden = !e.dataset.kind.split(" ").includes(kind);
}

async function applySource() {
  const kind = $("source-kind").value;
  const body = { kind };
  if (kind === "recording") {
    body.recording = $("source-recording").value;
    if (!body.recording) { showError("source-error", "Choose a recording first (or upload one under Record)."); return; }
    body.speed = Number($("playback-speed").value);
    body.loop = $("playback-loop").checked;
  } else if (kind === "network") {
    if ($("source-port").value !== "") body.port = Number($("source-port").value);
  } else if (kind === "serial") {
    body.device = $("source-device").value.trim();
    if ($("source-calibration").value.trim()) body.calibration = $("source-calibration").value.trim();
  } else if (kind === "camera" || kind === "hand") {
    body.side = $("source-side").value;
  } else if ($("source-seed").value !== "") {
    body.seed = Number($("source-seed").value);
  }
  const switched = await guarded("source-error", async () => {
    S.source = await api("PUT", "/api/source", body);
    renderSource();
    return true;
  }, $("source-apply"));
  // A refused switch changed nothing on the server: the selector goes back to the source that
  // still runs, so the page never names one source while another one feeds it.
  if (!switched && S.source && S.source.kind) {
    setProp("source-kind", "value", S.source.kind);
    syncKindOptions();
  }
}

async function simulatorReach(action) {
  const body = { action };
  if (action === "reach") {
    const f = $("train-form").elements;
    body.goal_deg = [Number(f.goal0.value), Number(f.goal1.value), Number(f.goal2.value)];
  }
  await guarded("source-error", async () => {
    S.source = await api("POST", "/api/source/reach", body);
    renderSource();
  }, $(action === "reach" ? "source-reach" : "source-wander"));
}

async function playback(action, extra = {}) {
  await guarded("source-error", async () => {
    S.source = await api("POST", "/api/source/playback", { action, ...extra });
    renderSource();
  });
}

async function setRetarget() {
  await guarded("source-error", async () => {
    S.source = await api("PUT", "/api/source/retarget", {
      mode: $("retarget-mode").value,
      mirror: $("retarget-mirror").checked,
    });
    renderSource();
  });
}

/* ------------------------------------------------------------------ capture & recordings */
function renderCaptureButton() {
  const active = !!(S.capture && S.capture.active) || !!(S.source && S.source.recording_active);
  const b = $("capture-toggle");
  b.classList.toggle("active", active);
  setText(b, active ? "■ Stop" : "● Record");
  setProp(b.dataset, "active", active ? "1" : "0");
  const secs = S.capture && S.capture.active ? S.capture.seconds : 0;
  setText("capture-elapsed", `${fmt(secs, 1)} s`);
  setProp("top-rec", "hidden", !active);
  setText("top-rec-time", fmt(secs, 1));
  const failure = (S.capture && S.capture.error) || ""; // e.g. a full disk: shown until dismissed
  setProp("capture-failure", "hidden", !failure);
  setText("capture-failure-text", failure);
}

async function dismissCaptureFailure() {
  await guarded("capture-error", async () => {
    await api("DELETE", "/api/capture/error");
    if (S.capture) S.capture.error = null;
    renderCaptureButton();
  }, $("capture-failure-dismiss"));
}

async function toggleCapture() {
  const b = $("capture-toggle");
  if (b.dataset.active === "1") {
    await guarded("capture-error", async () => {
      const rec = await api("POST", "/api/capture/stop");
      S.capture = await api("GET", "/api/capture"); // inactive, with the reason if the disk failed
      renderCaptureButton();
      await loadRecordings();
      flashRow("recordings-body", rec && rec.name);
    }, b);
  } else {
    if (window.recordCountdown && !(await window.recordCountdown())) return; // camera.js: cancelled
    const body = {};
    if ($("capture-name").value.trim()) body.name = $("capture-name").value.trim();
    if ($("capture-operator").value.trim()) body.operator = $("capture-operator").value.trim();
    await guarded("capture-error", async () => {
      S.capture = await api("POST", "/api/capture/start", body);
      renderCaptureButton();
    }, b);
  }
}

function flashRow(bodyId, name) {
  if (!name) return;
  const row = $(bodyId).querySelector(`tr[data-name="${CSS.escape(name)}"]`);
  if (row) { row.classList.add("selected"); setTimeout(() => row.classList.remove("selected"), 2500); }
}

async function loadRecordings() {
  await guarded("recordings-error", async () => {
    S.recordings = await api("GET", "/api/recordings");
    renderRecordings();
  });
}

function recordingRow(r) {
  const flags = [];
  if (r.sample) flags.push(el("span", { class: "badge", text: "sample", title: "shipped with the studio: read-only" }));
  if (r.kind === "pose" || r.kind === "hand") flags.push(el("span", { class: "badge", testid: "recording-kind", text: r.kind === "pose" ? "camera" : "hand guide", title: r.kind === "pose" ? "body landmarks from the camera, per frame (no image)" : "hand poses from the hand guide, per frame" }));
  if (r.recovered) flags.push(el("span", { class: "badge warn", text: "recovered", title: "the capture did not close cleanly; every frame written is kept" }));
  if (r.error) flags.push(el("span", { class: "badge failed", text: "unreadable", title: r.error, testid: "recording-damaged" }));
  if (r.capturing) flags.push(el("span", { class: "badge warn", text: "being captured", title: "another studio on this data folder is recording it; it can be changed once that capture stops", testid: "recording-capturing" }));
  if (r.warnings && r.warnings.length) flags.push(el("span", { class: "badge warn", text: "odd times", title: r.warnings.join("\n"), testid: "recording-warning" }));
  const title = [r.error, r.notes, r.operator && `operator: ${r.operator}`, r.created].filter(Boolean).join("\n");
  const actions = [];
  if (!r.error) actions.push(el("button", { class: "icon", title: "play as the live source", testid: "recording-play", onclick: () => useRecording(r.name) }, "▶"));
  if (r.sample) {
    actions.push(el("button", { class: "icon", title: "copy to my recordings", testid: "recording-copy", onclick: () => copyRecording(r.name) }, "copy"));
  } else if (!r.capturing) {
    actions.push(el("button", { class: "icon", title: "rename / notes", testid: "recording-edit", onclick: () => editRecording(r) }, "✎"));
  }
  actions.push(el("button", { class: "icon", title: "download", testid: "recording-download", onclick: () => download(`/api/recordings/${enc(r.name)}/file`, `${r.name}.${r.kind || "tape"}.csv`, "recordings-error") }, "⤓"));
  if (!r.sample && !r.capturing) actions.push(el("button", { class: "icon", title: "delete", testid: "recording-delete", onclick: () => deleteRecording(r.name) }, "✕"));
  return el("tr", { "data-name": r.name, testid: "recording-row", title },
    el("td", { class: "name", title: [r.name, title].filter(Boolean).join("\n") }, el("span", { text: r.name, testid: "recording-name" }), " ", ...flags),
    el("td", { class: "num", testid: "recording-duration", text: fmtDuration(r.duration) }),
    el("td", { class: "num", text: String(r.frames) }),
    el("td", { class: "actions" }, ...actions),
  );
}

/** A list's group heading row (the shipped samples under the user's own files). */
function groupRow(cols, text, testid) {
  return el("tr", { class: "group", testid }, el("td", { colspan: cols, text }));
}

function renderRecordings() {
  const body = $("recordings-body");
  const mine = S.recordings.filter((r) => !r.sample);
  const samples = S.recordings.filter((r) => r.sample);
  setText("rec-count", mine.length ? `(${mine.length})` : "");
  const rows = mine.length ? mine.map(recordingRow)
    : [emptyRow(4, samples.length ? "No recordings of your own yet: press Record, upload a .tape.csv, or copy a sample." : "No recordings yet: press Record, or upload a .tape.csv.")];
  if (samples.length) {
    rows.push(groupRow(4, "Samples (read-only): play, cut, or copy one to make it yours", "recordings-samples"));
    rows.push(...samples.map(recordingRow));
  }
  body.replaceChildren(...rows);
  const items = S.recordings.filter((r) => !r.error).map((r) => [r.name, `${r.name} (${fmtDuration(r.duration)})`]);
  fillSelect($("source-recording"), items);
  fillSelect($("demo-recording"), items);
  syncDemoRange();
}

async function copyRecording(name) {
  await guarded("recordings-error", async () => {
    const rec = await api("POST", `/api/recordings/${enc(name)}/copy`);
    await loadRecordings();
    flashRow("recordings-body", rec && rec.name);
  });
}

async function useRecording(name) {
  $("source-kind").value = "recording";
  syncKindOptions();
  $("source-recording").value = name;
  $("sec-source").open = true;
  await applySource();
}

function editRecording(r) {
  const dlg = $("edit-dialog");
  setText("edit-title", r.name);
  $("edit-name").value = r.name;
  $("edit-operator").value = r.operator || "";
  $("edit-notes").value = r.notes || "";
  showError("edit-error", null);
  dlg.dataset.name = r.name;
  dlg.showModal();
}

async function saveRecordingEdit(ev) {
  const dlg = $("edit-dialog");
  if (ev.submitter && ev.submitter.value !== "save") return;
  ev.preventDefault();
  const old = dlg.dataset.name;
  const patch = {};
  const name = $("edit-name").value.trim();
  if (name && name !== old) patch.name = name;
  patch.notes = $("edit-notes").value;
  patch.operator = $("edit-operator").value;
  const ok = await guarded("edit-error", async () => {
    await api("PATCH", `/api/recordings/${enc(old)}`, patch);
    return true;
  }, $("edit-save"));
  if (ok) {
    dlg.close("save");
    await loadRecordings();
  }
}

async function deleteRecording(name) {
  if (!(await confirmDialog(`Delete the recording ${name}? Its file is removed from the data directory.`))) return;
  await guarded("recordings-error", async () => {
    await api("DELETE", `/api/recordings/${enc(name)}`);
    await loadRecordings();
  });
}

async function uploadRecording(input) {
  const f = input.files[0];
  if (!f) return;
  await guarded("recordings-error", async () => {
    checkUploadSize(f);
    const fd = new FormData();
    fd.append("file", f, f.name);
    const rec = await api("POST", "/api/recordings", fd);
    await loadRecordings();
    flashRow("recordings-body", rec && rec.name);
  });
  input.value = "";
}

function checkUploadSize(f) {
  const limit = S.config && S.config.upload_limit_bytes;
  if (limit && f.size > limit) {
    throw new ApiError(`${f.name} is ${(f.size / 1e6).toFixed(1)} MB, over the ${(limit / 1e6).toFixed(0)} MB upload limit.`);
  }
}

/* ------------------------------------------------------------------ demonstrations */
function currentDemoRecording() {
  return S.recordings.find((r) => r.name === $("demo-recording").value);
}

function syncDemoRange() {
  const r = currentDemoRecording();
  const dur = r ? r.duration : 1;
  for (const id of ["demo-t0-range", "demo-t1-range"]) $(id).max = String(dur);
  for (const id of ["demo-t0", "demo-t1"]) $(id).max = String(dur);
  const t0 = Math.min(Number($("demo-t0").value) || 0, dur);
  let t1 = Number($("demo-t1").value) || 0;
  if (t1 <= 0 || t1 > dur) t1 = dur;
  setDemoRange(t0, t1);
}

function setDemoRange(t0, t1) {
  $("demo-t0").value = t0.toFixed(2);
  $("demo-t1").value = t1.toFixed(2);
  $("demo-t0-range").value = String(t0);
  $("demo-t1-range").value = String(t1);
}

async function cutDemo() {
  const body = {
    recording: $("demo-recording").value,
    t0: Number($("demo-t0").value),
    t1: Number($("demo-t1").value),
    goal_from_end: $("demo-goal-from-end").checked,
  };
  if ($("demo-name").value.trim()) body.name = $("demo-name").value.trim();
  $("demo-ok").hidden = true;
  if (!body.recording) { showError("demo-error", "Choose a recording to cut from (record or upload one first)."); return; }
  await guarded("demo-error", async () => {
    const d = await api("POST", "/api/demonstrations", body);
    demoAccepted(d);
  }, $("demo-cut"));
}

function demoAccepted(d) {
  if (!d) return;
  const el2 = $("demo-ok");
  el2.textContent = `Kept ${d.name}: ${d.steps} grid steps${d.reaches_goal ? ", reaches the goal" : ""}; its robot path is drawn in the scene.`;
  el2.hidden = false;
  loadDemos().then(() => flashRow("demos-body", d.name));
}

async function toggleMark() {
  const action = S.marking ? "stop" : "start";
  $("demo-ok").hidden = true;
  await guarded("demo-error", async () => {
    const body = { action };
    if (action === "stop") {
      if ($("demo-name").value.trim()) body.name = $("demo-name").value.trim();
      body.goal_from_end = $("demo-goal-from-end").checked;
    }
    let res;
    try {
      res = await api("POST", "/api/demonstrations/mark", body);
    } finally {
      if (action === "stop") S.marking = false;
    }
    if (action === "start") {
      S.marking = true;
      S.markT0 = res && res.t0;
    } else {
      const d = res && res.demonstration ? res.demonstration : res;
      if (d && d.name) demoAccepted(d);
    }
  }, $("demo-mark"));
  updateMarkButton();
}

function updateMarkButton() {
  const b = $("demo-mark");
  const capturing = !!(S.capture && S.capture.active) || !!(S.source && S.source.recording_active);
  setText(b, S.marking ? "Mark stop" : "Mark start");
  b.classList.toggle("active", S.marking);
  setProp(b, "disabled", !capturing && !S.marking);
  setProp(b, "title", capturing ? "mark a demonstration in the recording being captured" : "start a recording first (Record)");
  setText("demo-mark-state", S.marking ? `marking from ${fmt(S.markT0, 1)} s` : "");
}

async function loadDemos() {
  await guarded("demo-error", async () => {
    S.demos = await api("GET", "/api/demonstrations");
    renderDemos();
  });
}

function demoRow(d) {
  const goal = d.error
    ? el("span", { class: "badge failed", text: "unreadable", title: d.error, testid: "demo-damaged" })
    : el("span", { class: d.reaches_goal ? "badge done" : "badge warn", text: d.reaches_goal ? "reached" : "not reached", title: `goal ${(d.goal || []).map((g) => fmt(g, 0)).join(", ")}°` });
  const actions = [];
  if (!d.error) actions.push(el("button", { class: "icon", title: "preview on the robot", testid: "demo-preview", onclick: () => previewDemo(d.name) }, "▶"));
  if (!d.sample) actions.push(el("button", { class: "icon", title: "delete", testid: "demo-delete", onclick: () => deleteDemo(d.name) }, "✕"));
  return el("tr", { "data-name": d.name, testid: "demo-row", title: d.error || "" },
    el("td", { class: "name", title: d.name }, d.name, d.sample ? " " : null, d.sample ? el("span", { class: "badge", text: "sample", title: "shipped with the studio: read-only" }) : null),
    el("td", { class: "mono small", title: d.error ? "" : `from ${d.recording}`, text: d.error ? "" : `${fmt(d.t0, 1)}–${fmt(d.t1, 1)} s` }),
    el("td", { class: "num", text: d.error ? "" : String(d.steps) }),
    el("td", {}, goal),
    el("td", { class: "actions" }, ...actions),
  );
}

function renderDemos() {
  const body = $("demos-body");
  const mine = S.demos.filter((d) => !d.sample);
  const samples = S.demos.filter((d) => d.sample);
  const rows = mine.length ? mine.map(demoRow)
    : [emptyRow(5, "No demonstrations of your own: mark one while recording, or cut one from a recording.")];
  if (samples.length) {
    rows.push(groupRow(5, "Samples (read-only): preview, or tick them to train", "demos-samples"));
    rows.push(...samples.map(demoRow));
  }
  body.replaceChildren(...rows);
  // The training form's demonstration checkboxes keep their ticks across refreshes.
  const box = $("train-demos");
  const ticked = new Set([...box.querySelectorAll("input:checked")].map((i) => i.value));
  const usable = [...mine, ...samples].filter((d) => !d.error);
  if (!usable.length) {
    box.replaceChildren(el("span", { class: "muted", text: "none yet" }));
  } else {
    box.replaceChildren(...usable.map((d) => el("label", { title: `${d.steps} steps from ${d.recording}${d.sample ? " (sample)" : ""}` },
      el("input", { type: "checkbox", value: d.name, testid: "train-demo", checked: ticked.has(d.name) }), d.name)));
  }
}

async function previewDemo(name) {
  await guarded("demo-error", () => api("POST", `/api/demonstrations/${enc(name)}/preview`));
}

async function deleteDemo(name) {
  if (!(await confirmDialog(`Delete the demonstration ${name}? The recording it came from is kept.`))) return;
  await guarded("demo-error", async () => {
    await api("DELETE", `/api/demonstrations/${enc(name)}`);
    await loadDemos();
  });
}

/* ------------------------------------------------------------------ training */
/** Form inputs of a field the API names (the goal is three inputs). */
const TRAIN_INPUTS = { goal_deg: ["goal0", "goal1", "goal2"] };

/** Fill the train form with the learning package's defaults (served by /api/config). */
function resetTrainForm() {
  showTrainErrors(null);
  const defaults = S.config && S.config.training;
  if (!defaults) return;
  const f = $("train-form");
  const planners = S.config.planners || [defaults.planning];
  f.elements.planning.replaceChildren(...planners.map((p) => el("option", { value: p, text: p })));
  for (const [k, v] of Object.entries(defaults)) {
    if (k === "goal_deg") v.forEach((g, i) => { f.elements[`goal${i}`].value = String(g); });
    else if (f.elements[k] && !(f.elements[k] instanceof RadioNodeList)) f.elements[k].value = v == null ? "" : String(v);
  }
}

/** Show every problem of a refused run beside the form, and mark each bad field (null clears). */
function showTrainErrors(err) {
  const f = $("train-form");
  for (const input of f.querySelectorAll(".bad")) {
    input.classList.remove("bad");
    input.removeAttribute("aria-invalid");
    input.removeAttribute("title");
  }
  const box = $("train-error");
  if (!err) { showError("train-error", null); return; }
  const data = err.data || {};
  const problems = data.problems && data.problems.length ? data.problems : [err.message || String(err)];
  box.replaceChildren(...problems.map((p) => el("div", { testid: "train-problem", text: p })));
  box.hidden = false;
  for (const [field, text] of Object.entries(data.by_field || {})) {
    for (const name of TRAIN_INPUTS[field] || [field]) {
      const input = f.elements[name];
      if (!input || !input.classList) continue;
      input.classList.add("bad");
      input.setAttribute("aria-invalid", "true");
      input.setAttribute("title", text);
    }
  }
}

/** Continuous-task fields of the train form (shown only for that task). */
const REACH_FIELDS = ["joints", "step_deg", "tilings", "tiles"];

/** Show the fields of the chosen task; empty continuous-task fields take /api/config's defaults. */
function syncTaskFields() {
  const f = $("train-form");
  const reach = f.elements.task.value === "arm-reach";
  for (const label of f.querySelectorAll(".reach-only")) label.hidden = !reach;
  f.elements.bins.closest("label").hidden = reach;
  const defaults = (S.config && S.config.training) || {};
  for (const k of REACH_FIELDS) {
    if (f.elements[k].value === "" && defaults[k] != null) f.elements[k].value = String(defaults[k]);
  }
}

function readTrainForm() {
  const f = $("train-form").elements;
  const empty = [];
  const num = (k) => {
    const raw = f[k].value.trim();
    if (raw === "") empty.push(k);
    return Number(raw);
  };
  const body = {
    planning: f.planning.value,
    planning_steps: num("planning_steps"),
    epsilon: num("epsilon"),
    alpha: num("alpha"),
    gamma: num("gamma"),
    episodes: num("episodes"),
    experiments: num("experiments"),
    bins: num("bins"),
    task: f.task.value,
    seed: num("seed"),
    goal_deg: [num("goal0"), num("goal1"), num("goal2")],
    demonstrations: [...$("train-demos").querySelectorAll("input:checked")].map((i) => i.value),
  };
  if (empty.length) {
    const problems = empty.map((k) => `${k.replace("_", " ")} is empty; enter a number.`);
    const err = new ApiError(problems.join(" "));
    err.data = { problems, by_field: Object.fromEntries(empty.map((k, i) => [k, problems[i]])) };
    throw err;
  }
  if (body.task === "arm-reach") for (const k of REACH_FIELDS) body[k] = num(k);
  if (f.name.value.trim()) body.name = f.name.value.trim();
  return body;
}

async function startRun(ev) {
  ev.preventDefault();
  showTrainErrors(null);
  const button = $("train-start");
  button.disabled = true;
  try {
    const run = await api("POST", "/api/runs", readTrainForm());
    upsertRun(run);
    if (!S.shown.has(run.id)) S.shown.add(run.id);
    S.curves.set(run.id, emptyCurve());
    renderRuns();
    markCurvesDirty();
  } catch (e) {
    showTrainErrors(e);
    if (!(e instanceof ApiError)) console.error(e);
  } finally {
    button.disabled = false;
  }
}

const CURVE_KEYS = ["episodes", "mean", "std", "min", "max", "count"];

function emptyCurve() {
  return Object.fromEntries(CURVE_KEYS.map((k) => [k, []]));
}

function upsertRun(run) {
  const i = S.runs.findIndex((r) => r.id === run.id);
  if (i >= 0) S.runs[i] = run;
  else S.runs.unshift(run);
}

async function loadRuns() {
  await guarded("runs-error", async () => {
    S.runs = await api("GET", "/api/runs");
    S.sweeps = S.runs.some(sweepOf) ? await api("GET", "/api/sweeps") : [];
    if (!S.shownTouched) {
      // By default plot the newest few runs, so a fresh page shows the latest comparison.
      S.shown = new Set(S.runs.filter((r) => !r.damaged).slice(0, 4).map((r) => r.id));
    }
    renderRuns();
    await Promise.all([...S.shown].filter((id) => !S.curves.has(id)).map(loadCurve));
    renderWatchChoices();
    renderPolicies(); // a run's policy is listed under the run's name
  });
}

async function loadCurve(id) {
  try {
    const c = await api("GET", `/api/runs/${enc(id)}/curve`);
    S.curves.set(id, Object.fromEntries(CURVE_KEYS.map((k) => [k, c[k] || []])));
    markCurvesDirty();
  } catch (e) {
    showError("runs-error", e);
  }
}

function runColor(id) {
  const i = S.runs.length - 1 - S.runs.findIndex((r) => r.id === id);
  return PALETTE[((i % PALETTE.length) + PALETTE.length) % PALETTE.length];
}

/** What a run learns, in words: the paper's grid (tabular) or continuous joints (tile coding).
 * A run made before the continuous task existed has no task in its config: it is a grid run. */
function runTask(r) {
  const c = r.config || {};
  return c.task === "arm-reach" ? `continuous, ${c.joints} joints` : "grid";
}

function runLabel(r) {
  const c = r.config || {};
  const name = r.name || r.id;
  const demos = (c.demonstrations || []).length;
  const planning = c.planning && !name.includes(c.planning) ? ` · ${c.planning}` : "";
  return `${name} · ${runTask(r)}${planning}${demos && !/demo/.test(name) ? ` +${demos} demo` : ""}`;
}

function renderRuns() {
  const body = $("runs-body");
  if (!S.runs.length) {
    body.replaceChildren(emptyRow(6, "No runs yet: fill in the form and press Start."));
    return;
  }
  const rows = [];
  const grouped = new Set();
  for (const r of S.runs) { // a sweep's trials show as one group row, at its newest trial's place
    const sweep = sweepOf(r);
    if (!sweep) rows.push(runRow(r));
    else if (!grouped.has(sweep)) { grouped.add(sweep); rows.push(...sweepRows(sweep)); }
  }
  reconcileRows(body, rows);
  const failed = S.runs.find((r) => r.status === "failed" && r.error && !r._errorShown);
  if (failed) { failed._errorShown = true; showError("runs-error", `${failed.name || failed.id}: ${failed.error}`); }
}

/** Put ``rows`` into ``body``, keeping every row that is drawn the same already: a running run
 * refreshes its row a few times a second, and rebuilding the whole list each time would lay out
 * and repaint all of it. Rows are equal when their HTML is (their handlers depend on the id alone). */
function reconcileRows(body, rows) {
  const old = [...body.children];
  rows.forEach((row, i) => {
    if (i >= old.length) body.append(row);
    else if (old[i].outerHTML !== row.outerHTML) old[i].replaceWith(row);
  });
  for (const extra of old.slice(rows.length)) extra.remove();
}

/** A run folder the studio cannot read: the reason, and a way to delete it. */
function damagedRunRow(r) {
  return el("tr", { "data-id": r.id, testid: "run-row", "data-status": "damaged", title: r.error || "" },
    el("td", {}),
    el("td", { class: "name" }, r.id, " ", el("span", { class: "muted", testid: "run-damage", text: r.error || "" })),
    el("td", {}, el("span", { class: "badge failed", testid: "run-status", text: "damaged" })),
    el("td", {}),
    el("td", {}),
    el("td", { class: "actions" },
      el("button", { class: "icon", title: "delete this damaged run folder", testid: "run-delete", onclick: () => deleteRun(r.id) }, "✕")),
  );
}

function runRow(r) {
  if (r.damaged) return damagedRunRow(r);
  const total = r.episodes_total || (r.config && r.config.episodes) || 1;
  const pct = Math.min(100, (100 * (r.episodes_done || 0)) / total);
  const live = r.status === "running" || r.status === "queued";
  const c = r.config || {};
  const title = `planning ${c.planning} n=${c.planning_steps} ε=${c.epsilon} α=${c.alpha} γ=${c.gamma}\n` +
    `${c.episodes} episodes × ${c.experiments} experiments, ${c.bins} bins, goal ${(c.goal_deg || []).join(", ")}°, seed ${c.seed}` +
    `${(c.demonstrations || []).length ? `\ndemonstrations: ${c.demonstrations.join(", ")}` : ""}` +
    `${r.error ? `\n${r.error}` : ""}`;
  return el("tr", { "data-id": r.id, testid: "run-row", "data-status": r.status, title },
    el("td", {}, el("input", {
      type: "checkbox", testid: "run-show", checked: S.shown.has(r.id),
      onchange: (e) => toggleShown(r.id, e.target.checked),
    })),
    el("td", { class: "name", title: runLabel(r) }, el("span", { class: "swatch", style: `background:${runColor(r.id)}` }), runLabel(r)),
    el("td", {}, el("span", { class: `badge ${r.status}`, testid: "run-status", text: r.note ? "preparing" : r.status })),
    r.note // before its first episode: what the run does (compiling the learner, the first time)
      ? el("td", { class: "run-note", testid: "run-note", text: r.note })
      : el("td", { title: `${r.episodes_done} / ${total} episodes` },
        el("span", { class: "progress", testid: "run-progress", "data-done": r.episodes_done },
          el("span", { style: `width:${pct.toFixed(1)}%` }))),
    el("td", { class: "num", testid: "run-cpu", text: fmtCpu(r.cpu_seconds) }),
    el("td", { class: "actions" },
      live && !r.elsewhere ? el("button", { class: "icon", title: "stop", testid: "run-stop", onclick: () => stopRun(r.id) }, "■") : null,
      live && r.elsewhere ? el("button", { class: "icon", title: "another process trains it: stop it there; mark it stopped only if that process is gone", testid: "run-mark-stopped", onclick: () => markRunStopped(r.id) }, "⊘") : null,
      !live ? el("button", { class: "icon", title: "delete", testid: "run-delete", onclick: () => deleteRun(r.id) }, "✕") : null,
    ),
  );
}

/* ------------------------------------------------------------------ sweeps (`studio sweep`) */
// A sweep's trials are ordinary runs (origin "sweep", group = the sweep's id): the list shows them
// as one group row. Ticking it plots all of them; ▸ unfolds the summary figure, its table (the
// columns that matter; sweep.csv has them all), downloads, and the trials' own rows.
const SWEEP_TABLE_COLUMNS = ["trial", "seed", "status", "episodes_done", "cpu_seconds", "wall_seconds"];

function sweepOf(r) {
  return r.origin === "sweep" && r.group ? r.group : null;
}

function toggleSweep(id, on) {
  for (const r of S.runs) if (sweepOf(r) === id) toggleShown(r.id, on);
  renderRuns();
}

function foldSweep(id) {
  if (S.openSweeps.has(id)) S.openSweeps.delete(id);
  else S.openSweeps.add(id);
  renderRuns();
}

function sweepRows(id) {
  const runs = S.runs.filter((r) => sweepOf(r) === id);
  const info = S.sweeps.find((s) => s.id === id);
  const open = S.openSweeps.has(id);
  const trials = info ? info.trials : runs.length;
  const finished = info ? info.finished : runs.filter((r) => r.status === "done").length;
  const status = info ? info.status : runs.some((r) => r.status === "running") ? "running" : "done";
  const cpu = runs.reduce((sum, r) => sum + (r.cpu_seconds || 0), 0);
  const about = info ? ` · ${info.swept.join(" × ")} · ${info.metric}` : "";
  const head = el("tr", { class: "sweep", "data-id": id, testid: "sweep-row", "data-status": status,
    title: `sweep ${id}: ${finished} of ${trials} trials finished; tick to plot every trial` },
    el("td", {}, el("input", {
      type: "checkbox", testid: "sweep-show", checked: runs.length > 0 && runs.every((r) => S.shown.has(r.id)),
      onchange: (e) => toggleSweep(id, e.target.checked),
    })),
    el("td", { class: "name", title: `sweep ${id}${about} (${runs.length} runs)` },
      el("button", { class: "icon", testid: "sweep-open", title: open ? "fold" : "unfold: summary, figure and trials",
        onclick: () => foldSweep(id) }, open ? "▾" : "▸"),
      `sweep ${id}${about} (${runs.length} runs)`),
    el("td", {}, el("span", { class: `badge ${status === "interrupted" ? "stopped" : status}`, testid: "sweep-status", text: status })),
    el("td", { title: `${finished} / ${trials} trials` },
      el("span", { class: "progress", testid: "sweep-progress", "data-done": finished },
        el("span", { style: `width:${(100 * finished / Math.max(trials, 1)).toFixed(1)}%` }))),
    el("td", { class: "num", text: fmtCpu(cpu) }),
    el("td", {}),
  );
  return open ? [head, sweepDetail(id, info), ...runs.map(runRow)] : [head];
}

function sweepDetail(id, info) {
  const base = `/api/sweeps/${enc(id)}`;
  const get = (path, name) => download(`${base}/${path}`, `${id}-${name}`, "runs-error");
  let table = el("div", { class: "muted", text: "No summary yet." });
  if (info && info.rows.length) {
    const cols = info.columns.filter((c) => SWEEP_TABLE_COLUMNS.includes(c) || info.swept.includes(c) || c === info.metric);
    table = el("table", { class: "list", testid: "sweep-table" },
      el("thead", {}, el("tr", {}, ...cols.map((c) => el("th", { text: c })))),
      el("tbody", {}, ...info.rows.map((row) => el("tr", {}, ...cols.map((c) => el("td", { text: row[c] }))))));
  }
  const version = info ? `${info.status}-${info.finished}` : "0";
  return el("tr", { class: "sweep-detail", "data-id": id, testid: "sweep-detail" }, el("td", { colspan: 6 },
    el("img", { src: `${base}/figure.png?v=${enc(version)}`, testid: "sweep-figure", style: "max-width:100%",
      alt: info ? `${info.metric} against ${info.swept[0]}, mean and standard error over seeds` : "sweep figure" }),
    el("div", { class: "row" },
      el("button", { type: "button", testid: "sweep-csv", onclick: () => get("sweep.csv", "sweep.csv") }, "sweep.csv"),
      el("button", { type: "button", testid: "sweep-png", onclick: () => get("figure.png", "sweep.png") }, "Figure PNG"),
      el("button", { type: "button", testid: "sweep-svg", onclick: () => get("figure.svg", "sweep.svg") }, "Figure SVG")),
    el("div", { style: "overflow-x:auto" }, table)));
}

function toggleShown(id, on) {
  S.shownTouched = true;
  if (on) {
    S.shown.add(id);
    if (!S.curves.has(id)) loadCurve(id);
  } else {
    S.shown.delete(id);
  }
  markCurvesDirty();
}

async function stopRun(id) {
  await guarded("runs-error", async () => {
    upsertRun(await api("POST", `/api/runs/${enc(id)}/stop`));
    renderRuns();
  });
}

async function markRunStopped(id) {
  const r = S.runs.find((x) => x.id === id);
  if (!(await confirmDialog(`Mark the run ${(r && r.name) || id} stopped? Do so only if no process trains it any more (a crash, a reboot, another machine); its curve so far is kept.`, "Mark stopped"))) return;
  await guarded("runs-error", async () => {
    upsertRun(await api("POST", `/api/runs/${enc(id)}/mark-stopped`));
    renderRuns();
  });
}

async function deleteRun(id) {
  const r = S.runs.find((x) => x.id === id);
  const what = r && r.damaged ? `the damaged run folder ${id}` : `the run ${(r && r.name) || id} with its curves and policy`;
  if (!(await confirmDialog(`Delete ${what}?`))) return;
  await guarded("runs-error", async () => {
    await api("DELETE", `/api/runs/${enc(id)}`);
    S.shown.delete(id);
    S.curves.delete(id);
    await loadRuns();
    markCurvesDirty();
  });
}

/** Merge an SSE curve piece into the run's curve: replace everything from its first episode on. */
function mergeCurve(id, piece, from, to) {
  if (!piece || !piece.episodes) return;
  let c = S.curves.get(id);
  if (!c) { c = emptyCurve(); S.curves.set(id, c); }
  if (to !== undefined && to !== null) { // episodes [from, to) changed: replace just those
    for (let e = c.episodes.length; e < from; e++) { // episodes nobody finished yet: empty
      for (const k of CURVE_KEYS) c[k].push(k === "episodes" ? e + 1 : 0);
    }
    for (const k of CURVE_KEYS) c[k].splice(from, to - from, ...(piece[k] || []));
    markCurvesDirty();
    return;
  }
  // `from` is the 0-based index of the piece's first episode (episode numbers are 1-based).
  const first = from !== undefined && from !== null ? from + 1 : piece.episodes[0];
  // Episodes are numbered; drop what we already hold from `first` on, then append.
  let cut = c.episodes.length;
  if (first !== undefined) {
    cut = c.episodes.findIndex((e) => e >= first);
    if (cut < 0) cut = c.episodes.length;
  }
  for (const k of CURVE_KEYS) {
    c[k] = (c[k] || []).slice(0, cut).concat(piece[k] || []);
  }
  markCurvesDirty();
}

/* ------------------------------------------------------------------ the chart */
// uPlot (vendored from npm, see static/vendor/README.md) draws on a canvas: a redraw with new data
// takes about a millisecond, so live curves at CURVE_FPS never compete with training for the CPU.
function markCurvesDirty() { S.curveDirty = true; }

/**
 * At most MAX_PLOT_POINTS points per run: longer curves are averaged in equal buckets of episodes,
 * the same buckets for every run (band: the buckets' lowest low and highest high), so a 100 000-
 * episode run draws as fast as a short one and the chart never slows the page down.
 */
const MAX_PLOT_POINTS = 600;

/** The runs to plot, oldest first (so colours and legend order stay put as runs are added). */
function plottedRuns() {
  return [...S.runs].reverse().filter((r) => {
    const c = S.curves.get(r.id);
    return S.shown.has(r.id) && c && c.episodes.length > 0;
  });
}

/** Episodes per experiment of a run (its fraction-of-run axis divides by this). */
function runLength(r) {
  const c = S.curves.get(r.id);
  const planned = r.config && r.config.episodes;
  return Math.max(1, planned || (c.episodes.length ? c.episodes[c.episodes.length - 1] : 1));
}

/**
 * Bucket edges of the x axis: ``x[b]`` is bucket b's x value and ``bucketOf(run, episode)`` its
 * bucket. "episode": equal buckets of episodes; "log": log-spaced buckets, so a 100-episode run
 * keeps its shape beside a 50 000-episode one; "fraction": each run over [0, 1] of its own length.
 */
function chartAxis(runs, xMode) {
  if (xMode === "fraction") {
    const longest = Math.max(...runs.map(runLength));
    const n = Math.min(MAX_PLOT_POINTS, longest);
    const x = Array.from({ length: n }, (_, b) => (b + 1) / n);
    return { x, bucketOf: (r, e) => Math.min(n - 1, Math.floor(((e - 1) / runLength(r)) * n)) };
  }
  let last = 0;
  for (const r of runs) {
    const e = S.curves.get(r.id).episodes;
    last = Math.max(last, e[e.length - 1]);
  }
  if (xMode === "log" && last > MAX_PLOT_POINTS) {
    // upper edges geometric from 1 to last (duplicates merged), so early episodes stay single
    const edges = [];
    for (let b = 1; b <= MAX_PLOT_POINTS; b++) {
      const edge = Math.ceil(Math.exp((Math.log(last) * b) / MAX_PLOT_POINTS));
      if (!edges.length || edge > edges[edges.length - 1]) edges.push(edge);
    }
    edges[edges.length - 1] = last;
    const bucketOf = (r, e) => {
      let lo = 0; let hi = edges.length - 1;
      while (lo < hi) { const mid = (lo + hi) >> 1; if (edges[mid] >= e) hi = mid; else lo = mid + 1; }
      return lo;
    };
    return { x: edges, bucketOf };
  }
  const k = Math.max(1, Math.ceil(last / MAX_PLOT_POINTS));
  const n = Math.ceil(last / k);
  return { x: Array.from({ length: n }, (_, b) => Math.min(last, (b + 1) * k)), bucketOf: (r, e) => Math.floor((e - 1) / k) };
}

/**
 * The chart's columns: the x axis, then per run its mean and, with a band, its low and high
 * edges. Missing episodes are null (a gap); on a log axis nothing below one step is drawn. Also
 * per run the fewest experiments any point of a bucket averages (``counts``) and the run's most
 * (``full``), so the legend and a marker say where the band stops averaging every experiment.
 */
function chartData(runs, band, log, xMode = "episode") {
  const { x, bucketOf } = chartAxis(runs, xMode);
  const n = x.length;
  const cols = [x];
  const counts = [];
  const full = [];
  const floor = (v) => (log && v < 1 ? null : v);
  for (const r of runs) {
    const c = S.curves.get(r.id);
    const sum = new Float64Array(n); const sd = new Float64Array(n); const cnt = new Uint32Array(n);
    const lo = new Float64Array(n).fill(Infinity); const hi = new Float64Array(n).fill(-Infinity);
    const fewest = new Array(n).fill(null);
    let most = 0;
    for (let i = 0; i < c.episodes.length; i++) {
      const b = bucketOf(r, c.episodes[i]);
      sum[b] += c.mean[i]; sd[b] += c.std[i] || 0; cnt[b] += 1;
      lo[b] = Math.min(lo[b], c.min[i]); hi[b] = Math.max(hi[b], c.max[i]);
      const k = c.count && c.count[i] !== undefined ? c.count[i] : null;
      if (k !== null) { fewest[b] = fewest[b] === null ? k : Math.min(fewest[b], k); most = Math.max(most, k); }
    }
    const mean = new Array(n).fill(null); const low = new Array(n).fill(null); const high = new Array(n).fill(null);
    for (let b = 0; b < n; b++) {
      if (!cnt[b]) continue;
      const m = sum[b] / cnt[b];
      mean[b] = floor(m);
      if (band === "minmax") {
        low[b] = floor(lo[b]); high[b] = floor(hi[b]);
      } else {
        const s = sd[b] / cnt[b];
        low[b] = floor(Math.max(m - s, log ? Math.max(lo[b], 1) : 0)); high[b] = floor(m + s);
      }
    }
    cols.push(mean);
    if (band !== "none") cols.push(low, high);
    counts.push(fewest);
    full.push(most || (r.config && r.config.experiments) || 0);
  }
  cols.counts = counts;
  cols.full = full;
  return cols;
}

/** Where each run's points stop averaging all its experiments: the first such x, or null. */
function fewerFrom(data, i) {
  const counts = data.counts[i];
  for (let b = 0; b < counts.length; b++) {
    if (counts[b] !== null && counts[b] < data.full[i]) return data[0][b];
  }
  return null;
}

function hexAlpha(hex, a) {
  const n = parseInt(hex.slice(1), 16);
  return `rgba(${(n >> 16) & 255},${(n >> 8) & 255},${n & 255},${a})`;
}

/** uPlot options for these runs: a mean line per run and, with a band, two unlabelled edges filled;
 * a dashed marker where a run's points start averaging fewer experiments than it has. */
function chartOptions(runs, band, log, width, height, xMode = "episode") {
  const xLabel = xMode === "fraction" ? "fraction of run" : "episode";
  const series = [{ label: xLabel, value: (u, v) => (v == null ? "–" : xMode === "fraction" ? v.toFixed(3) : String(v)) }];
  const bands = [];
  runs.forEach((r, i) => {
    const color = runColor(r.id);
    const meanIdx = series.length;
    series.push({
      label: runLabel(r), stroke: color, width: 1.8, spanGaps: false,
      value: (u, v, si, di) => {
        if (v == null) return "–";
        const n = di == null || !u.data.counts ? null : u.data.counts[i][di];
        const of = u.data.full ? u.data.full[i] : null;
        return `${v.toFixed(1)} steps${n != null && of ? ` · ${n} of ${of} exp.` : ""}`;
      },
    });
    if (band !== "none") {
      for (const edge of ["low", "high"]) {
        series.push({ label: `${runLabel(r)} ${edge}`, class: "band-edge", stroke: "transparent", width: 0, points: { show: false } });
      }
      bands.push({ series: [meanIdx + 2, meanIdx + 1], fill: hexAlpha(color, 0.16) });
    }
  });
  const axis = { stroke: "#555", grid: { stroke: "#eceef1", width: 1 }, ticks: { stroke: "#d6d9de", width: 1 }, font: "11px system-ui, sans-serif", labelFont: "11px system-ui, sans-serif" };
  return {
    width, height, series, bands,
    scales: {
      x: xMode === "log" ? { time: false, distr: 3, log: 10 } : { time: false },
      y: log ? { distr: 3, log: 10 } : { range: (u, min, max) => [0, max > 0 ? max * 1.05 : 1] },
    },
    axes: [
      { ...axis, label: xLabel, labelSize: 16, size: 30 },
      { ...axis, label: "steps", labelSize: 16, size: 48 },
    ],
    legend: { live: true },
    cursor: { drag: { x: true, y: false } },
    hooks: {
      init: [(u) => {
        // Drag to zoom into episodes (the zoom then survives live updates); double-click resets.
        u.over.addEventListener("dblclick", () => { S.chartZoomed = false; });
      }],
      setSelect: [(u) => { if (u.select.width > 0) S.chartZoomed = true; }],
      draw: [(u) => {
        // Mark where each run's band stops averaging all of its experiments (runs of different
        // lengths, or a stopped run): the band goes on, over fewer experiments, as the legend says.
        const ctx = u.ctx;
        runs.forEach((r, i) => {
          const at = u.data.counts ? fewerFrom(u.data, i) : null;
          if (at === null) return;
          const px = Math.round(u.valToPos(at, "x", true));
          ctx.save();
          ctx.strokeStyle = runColor(r.id);
          ctx.setLineDash([4, 4]);
          ctx.lineWidth = 1;
          ctx.beginPath();
          ctx.moveTo(px, u.bbox.top);
          ctx.lineTo(px, u.bbox.top + u.bbox.height);
          ctx.stroke();
          ctx.restore();
        });
      }],
    },
  };
}

/** The chart's key: what the line, the band and the dashed marker mean (each run's name and
 * colour are in uPlot's own legend under the chart). Written only when it changes. */
function renderCurveKey(runs, data, band) {
  setProp("curve-key", "hidden", runs.length === 0);
  setProp("curve-key-band", "hidden", band === "none");
  setText("curve-key-band-text", band === "minmax" ? "min–max" : "± 1 std");
  setProp("curve-key-fewer", "hidden", !runs.some((r, i) => fewerFrom(data, i) !== null));
}

let chart = null;
let chartKey = "";
let chartRuns = []; // run ids of the chart's mean columns, in order
let chartStride = 1; // columns per run: mean, or mean, low and high

/** Size the chart to its pane, leaving room for the legend under it. */
function fitChart() {
  if (!chart) return;
  const box = $("curve-plot");
  const legend = chart.root.querySelector(".u-legend");
  const height = Math.max(80, box.clientHeight - (legend ? legend.offsetHeight : 0) - 2);
  chart.setSize({ width: box.clientWidth, height });
}

function renderCurves() {
  if (!S.curveDirty || typeof uPlot === "undefined") return;
  S.curveDirty = false;
  const band = $("curve-band").value;
  const log = $("curve-log").checked;
  const xMode = $("curve-x").value;
  const runs = plottedRuns();
  setProp("curve-empty", "hidden", runs.length > 0);
  if (!runs.length) {
    if (chart) { chart.destroy(); chart = null; chartKey = ""; chartRuns = []; }
    setProp("curve-key", "hidden", true);
    return;
  }
  const key = JSON.stringify([runs.map((r) => [r.id, runLabel(r), runColor(r.id)]), band, log, xMode]);
  const data = chartData(runs, band, log, xMode);
  renderCurveKey(runs, data, band);
  if (chart && key === chartKey) {
    chart.setData(data, !S.chartZoomed);
  } else {
    if (chart) chart.destroy();
    const box = $("curve-plot");
    chart = new uPlot(chartOptions(runs, band, log, box.clientWidth, box.clientHeight, xMode), data, box);
    chartKey = key;
    chartRuns = runs.map((r) => r.id);
    chartStride = band === "none" ? 1 : 3;
    S.chartZoomed = false;
    fitChart();
  }
  S.curveRenders = (S.curveRenders || 0) + 1; // chart redraws with new data (benchmarks read it)
}

/** Ids of the runs in the chart, in legend order (used by the browser tests). */
S.plottedRuns = () => (chart ? [...chartRuns] : []);

/** The x where a plotted run starts averaging fewer experiments than it has, or null (tests). */
S.chartFewerFrom = (id) => (chart && chartRuns.includes(id) ? fewerFrom(chart.data, chartRuns.indexOf(id)) : null);

/** Number of plotted mean-curve points of a run, or of all runs (used by the browser tests). */
S.curvePoints = (id) => {
  if (!chart) return 0;
  let n = 0;
  chartRuns.forEach((run, i) => {
    if (id === undefined || run === id) n += chart.data[1 + i * chartStride].filter((v) => v !== null).length;
  });
  return n;
};

/* ------------------------------------------------------------------ policies, watch, export */
async function loadPolicies() {
  await guarded("policies-error", async () => {
    S.policies = await api("GET", "/api/policies");
    renderPolicies();
    renderWatchChoices();
  });
}

// One name per policy: a run's policy goes by its run's label (as in the runs list), an
// uploaded one by its file name.
function policyLabel(p) {
  const run = p.source === "run" && p.run ? S.runs.find((r) => r.id === p.run) : null;
  return run ? runLabel(run) : p.name;
}

function policyKey(p) {
  return p.source === "run" && p.run ? `run:${p.run}` : `policy:${p.name}`;
}

// What a policy acts on, from its listing's task: the paper's grid or the continuous joints.
function policyTask(p) {
  const t = p.task || {};
  if (t.kind === "arm-grid") return `grid ${t.joints}×${t.bins}`;
  if (t.kind === "arm-reach") return `continuous ${t.joints} joints`;
  return t.kind || "";
}

function renderPolicies() {
  const body = $("policies-body");
  if (!S.policies.length) {
    body.replaceChildren(emptyRow(4, "No policies: finish a run, or upload a .policy.npz."));
    return;
  }
  body.replaceChildren(...S.policies.map((p) => {
    const label = policyLabel(p);
    const what = p.error
      ? el("span", { class: "badge failed", text: "unreadable", title: p.error, testid: "policy-damaged" })
      : el("span", { title: policyTask(p), text: `${p.planning} · ${policyTask(p)}` });
    return el("tr", { "data-name": p.name, "data-key": policyKey(p), testid: "policy-row", title: p.error || "" },
      el("td", { class: "name", title: [label, p.run && `run ${p.run}`, p.notes].filter(Boolean).join("\n"), text: label }),
      el("td", { testid: "policy-task" }, what),
      el("td", { class: "muted", title: p.run || "", text: p.source === "run" ? "run" : "upload" }),
      el("td", { class: "actions" },
        p.error ? null : el("button", { class: "icon", title: "watch", testid: "policy-watch", onclick: () => { selectWatch(p); watch(); } }, "▶"),
        p.source === "upload" ? el("button", { class: "icon", title: "delete", testid: "policy-delete", onclick: () => deletePolicy(p.name) }, "✕") : null,
      ),
    );
  }));
}

function selectWatch(p) {
  $("watch-policy").value = policyKey(p);
}

function renderWatchChoices() {
  const items = [];
  const seenRuns = new Set();
  for (const r of S.runs) {
    if (r.has_policy) { items.push([`run:${r.id}`, `run ${runLabel(r)}`]); seenRuns.add(r.id); }
  }
  for (const p of S.policies) {
    if ((p.source === "run" && p.run && seenRuns.has(p.run)) || p.error) continue;
    items.push([policyKey(p), `${p.source === "upload" ? "file" : "run"} ${policyLabel(p)}`]);
  }
  if (!items.length) items.push(["", "(no policy yet)"]);
  fillSelect($("watch-policy"), items);
}

function watchTarget() {
  const v = $("watch-policy").value;
  if (!v) return null;
  const i = v.indexOf(":");
  return { type: v.slice(0, i), id: v.slice(i + 1) };
}

async function watch() {
  const t = watchTarget();
  if (!t) { showError("watch-error", "There is no policy to watch yet: train a run to the end, or upload a policy file."); return; }
  const body = { start: $("watch-start").value };
  if (t.type === "run") body.run = t.id; else body.policy = t.id;
  if ($("watch-seed").value !== "") body.seed = Number($("watch-seed").value);
  setText("watch-result", "");
  await guarded("watch-error", async () => {
    const w = await api("POST", "/api/watch", body);
    const secs = w.times && w.times.length ? w.times[w.times.length - 1] : 0;
    const from = w.seed == null ? "from the current pose" : `from a random start (seed ${w.seed})`;
    setText("watch-result", `${w.steps} steps, ${secs.toFixed(1)} s ${from} — ${w.reached_goal ? "reaches the goal" : "does not reach the goal"}`);
    S.watchedRun = t;
  }, $("watch-go"));
}

async function deletePolicy(name) {
  if (!(await confirmDialog(`Delete the uploaded policy ${name}?`))) return;
  await guarded("policies-error", async () => {
    await api("DELETE", `/api/policies/${enc(name)}`);
    await loadPolicies();
  });
}

async function uploadPolicy(input) {
  const f = input.files[0];
  if (!f) return;
  await guarded("policies-error", async () => {
    checkUploadSize(f);
    const fd = new FormData();
    fd.append("file", f, f.name);
    const p = await api("POST", "/api/policies", fd);
    await loadPolicies();
    if (p) { selectWatch(p); flashRow("policies-body", p.name); }
  });
  input.value = "";
}

function exportFile(kind) {
  const t = watchTarget();
  if (!t) { showError("export-error", "Choose a run or a policy first."); return; }
  if (kind === "rollout") { // the selected policy's rollout as last watched, named after it
    return download(`/api/watch/trajectory.csv?${t.type === "run" ? "run" : "policy"}=${enc(t.id)}`, `${t.id}.rollout.csv`, "export-error");
  }
  if (kind === "policy") {
    if (t.type === "run") return download(`/api/runs/${enc(t.id)}/policy`, `${t.id}.policy.npz`, "export-error");
    return download(`/api/policies/${enc(t.id)}/file`, `${t.id}.policy.npz`, "export-error");
  }
  if (t.type !== "run") { showError("export-error", "Curves and plots belong to a training run; choose a run, not an uploaded file."); return; }
  const path = { curve: "curve.csv", png: "plot.png", svg: "plot.svg" }[kind];
  const query = kind === "curve" ? "" : `?log=${$("curve-log").checked}`;
  return download(`/api/runs/${enc(t.id)}/${path}${query}`, `${t.id}-${path}`, "export-error");
}

/* ------------------------------------------------------------------ live events */
let events = null;
function connectEvents() {
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
function renderLive() {
  if (runsRenderPending) {
    runsRenderPending = false;
    renderRuns();
  }
  renderCurves();
}

/* ------------------------------------------------------------------ start-up */
async function loadConfig() {
  try {
    S.config = await api("GET", "/api/config");
    resetTrainForm(); // the learning package's defaults, the one definition
  } catch (e) {
    showError("scene-msg", `The 3D scene is unavailable: ${e.message}`);
    return;
  }
  setText("version", `v${S.config.version}`);
  const url = S.config.viser_url;
  if (!url) {
    showError("scene-msg", "This studio runs without a 3D scene (no viser URL configured).");
    return;
  }
  const src = sceneUrl(url);
  if (S.config.scene_instance && !(await sceneIsOurs(src, S.config.scene_instance))) {
    showError("scene-msg", `The 3D scene at ${new URL(src).host} does not belong to this studio (another studio or program answers there); restart this studio so that it starts its own scene.`);
    return;
  }
  $("scene").src = S.softwareScene ? withSceneDpr(src, SOFTWARE_SCENE_DPR) : src;
  setProp("scene-note", "hidden", !S.softwareScene);
  showSceneLegend(S.config.scene_colors || {});
}

/** The scene's legend, in the scene's own colours (served by /api/config, defined once). */
function showSceneLegend(colors) {
  for (const sw of $("scene-legend").querySelectorAll("[data-color]")) {
    const rgb = colors[sw.dataset.color];
    if (rgb) sw.style.color = `rgb(${rgb.join(",")})`;
  }
  setProp("scene-legend", "hidden", false);
}

/**
 * Whether this browser draws WebGL in software (no GPU: SwiftShader, llvmpipe). There every
 * frame of the scene is drawn by the CPU that trains, about 0.1 s of it per full-size frame.
 */
function softwareWebGL() {
  try {
    const canvas = document.createElement("canvas");
    const gl = canvas.getContext("webgl2") || canvas.getContext("webgl");
    if (!gl) return false;
    const info = gl.getExtension("WEBGL_debug_renderer_info");
    const renderer = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
    const lose = gl.getExtension("WEBGL_lose_context");
    if (lose) lose.loseContext();
    return SOFTWARE_RENDERERS.test(renderer);
  } catch (e) {
    return false;
  }
}

/** The scene URL asking viser's client to draw at a fixed device-pixel ratio. */
function withSceneDpr(src, dpr) {
  const u = new URL(src);
  u.searchParams.set("fixedDpr", String(dpr));
  return u.toString();
}

/** Whether the scene server at `src` is this studio's: it answers our instance id. */
async function sceneIsOurs(src, instance) {
  const u = new URL(src);
  u.pathname = "/studio-instance";
  u.hash = "";
  try {
    const r = await fetch(u.toString(), { cache: "no-store" });
    if (!r.ok) return false;
    const body = await r.json();
    return body.instance === instance;
  } catch (e) {
    return false;
  }
}

/**
 * The scene's URL, moved to another site when both servers are on this machine's loopback.
 *
 * Pages on one site share a renderer process and its main thread in Chromium, so a busy 3D scene
 * (software WebGL, a fast live stream) would delay the page's own work: curves, buttons, lists.
 * 127.0.0.1 and localhost are different sites, so swapping one for the other gives the scene its
 * own process. A loopback scene seen from a page on another machine (a studio serving 0.0.0.0)
 * is reached at the page's host. Any other host is left alone.
 */
function sceneUrl(url) {
  const u = new URL(url, location.href);
  const loopback = ["127.0.0.1", "localhost"];
  if (loopback.includes(u.hostname) && u.hostname === location.hostname) {
    u.hostname = u.hostname === "localhost" ? "127.0.0.1" : "localhost";
  } else if (loopback.includes(u.hostname) && !loopback.includes(location.hostname)) {
    u.hostname = location.hostname; // a studio on 0.0.0.0 opened from another machine
  }
  return u.toString();
}

function wire() {
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
  $("train-defaults").addEventListener("click", resetTrainForm);
  $("train-defaults").addEventListener("click", syncTaskFields); // after the reset above
  $("curve-log").addEventListener("change", markCurvesDirty);
  $("curve-band").addEventListener("change", markCurvesDirty);
  $("curve-x").addEventListener("change", markCurvesDirty);

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
    S.source = s;
    if (s.kind) $("source-kind").value = s.kind;
    syncKindOptions();
    renderSource();
  }).catch((e) => showError("source-error", e));
  const cap = api("GET", "/api/capture").then((c) => { S.capture = c; renderCaptureButton(); updateMarkButton(); }).catch(() => {});
  const mark = api("GET", "/api/demonstrations/mark").then((m) => {
    S.marking = !!(m && m.marking);
    S.markT0 = m && m.t0;
    updateMarkButton();
  }).catch(() => {});
  await Promise.all([initial, cap, mark, loadRecordings(), loadDemos(), loadRuns(), loadPolicies()]);
  if (S.source && S.source.recording) $("source-recording").value = S.source.recording;
  document.body.dataset.ready = "1";
}

main();
