/* Teach Studio page: capture (the Record button) and the recordings list: play, rename, copy, upload, delete. */

import { api, download, guarded, uploadChosen } from "./api.js";
import { syncDemoRange } from "./demos.js";
import { fillExportItems } from "./exports.js";
import { $, confirmDialog, el, emptyRow, enc, fillSelect, flashRow, fmt, fmtDuration, groupRow, setProp, setText, showError } from "./dom.js";
import { applySource, syncKindOptions } from "./sources.js";
import { S } from "./state.js";
import { recordCountdown } from "./countdown.js";

export function renderCaptureButton() {
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

export async function dismissCaptureFailure() {
  await guarded("capture-error", async () => {
    await api("DELETE", "/api/capture/error");
    if (S.capture) S.capture.error = null;
    renderCaptureButton();
  }, $("capture-failure-dismiss"));
}

export async function toggleCapture() {
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
    if (!(await recordCountdown())) return; // cancelled
    const body = {};
    if ($("capture-name").value.trim()) body.name = $("capture-name").value.trim();
    if ($("capture-operator").value.trim()) body.operator = $("capture-operator").value.trim();
    await guarded("capture-error", async () => {
      S.capture = await api("POST", "/api/capture/start", body);
      renderCaptureButton();
    }, b);
  }
}

export async function loadRecordings() {
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
  if (!r.error && !r.capturing) actions.push(el("button", { class: "icon", title: "timeline: see the joints over time and cut a demonstration", "aria-label": `Timeline of ${r.name}`, testid: "recording-timeline", onclick: () => openTimeline(r.name) }, "∿"));
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
  fillExportItems("recording");
}

async function copyRecording(name) {
  await guarded("recordings-error", async () => {
    const rec = await api("POST", `/api/recordings/${enc(name)}/copy`);
    await loadRecordings();
    flashRow("recordings-body", rec && rec.name);
  });
}

/** Plot the recording on the Demonstrations section's timeline (timeline.js follows the select). */
function openTimeline(name) {
  const select = $("demo-recording");
  select.value = name;
  select.dispatchEvent(new Event("change"));
  $("sec-demos").open = true;
  $("timeline").scrollIntoView({ block: "nearest" });
  $("timeline").focus({ preventScroll: true });
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

export async function saveRecordingEdit(ev) {
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

export async function uploadRecording(input) {
  await uploadChosen(input, "/api/recordings", "recordings-error", async (rec) => {
    await loadRecordings();
    flashRow("recordings-body", rec && rec.name);
  });
}
