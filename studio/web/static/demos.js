/* Teach Studio page: demonstrations: cut one from a recording or mark one while recording; the list. */

import { api, guarded } from "./api.js";
import { $, confirmDialog, el, emptyRow, enc, flashRow, fmt, groupRow, setProp, setText, showError } from "./dom.js";
import { fillExportItems } from "./exports.js";
import { renderWatchDemos, showNewPolicy } from "./policies.js";
import { S } from "./state.js";

function currentDemoRecording() {
  return S.recordings.find((r) => r.name === $("demo-recording").value);
}

export function syncDemoRange() {
  const r = currentDemoRecording();
  const dur = r ? r.duration : 1;
  for (const id of ["demo-t0-range", "demo-t1-range"]) $(id).max = String(dur);
  for (const id of ["demo-t0", "demo-t1"]) $(id).max = String(dur);
  const t0 = Math.min(Number($("demo-t0").value) || 0, dur);
  let t1 = Number($("demo-t1").value) || 0;
  if (t1 <= 0 || t1 > dur) t1 = dur;
  setDemoRange(t0, t1);
}

export function setDemoRange(t0, t1) {
  $("demo-t0").value = t0.toFixed(2);
  $("demo-t1").value = t1.toFixed(2);
  $("demo-t0-range").value = String(t0);
  $("demo-t1-range").value = String(t1);
}

export async function cutDemo() {
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

export async function toggleMark() {
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

export function updateMarkButton() {
  const b = $("demo-mark");
  const capturing = !!(S.capture && S.capture.active) || !!(S.source && S.source.recording_active);
  setText(b, S.marking ? "Mark stop" : "Mark start");
  b.classList.toggle("active", S.marking);
  setProp(b, "disabled", !capturing && !S.marking);
  setProp(b, "title", capturing ? "mark a demonstration in the recording being captured" : "start a recording first (Record)");
  setText("demo-mark-state", S.marking ? `marking from ${fmt(S.markT0, 1)} s` : "");
}

export async function loadDemos() {
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
  if (!d.error) actions.push(el("button", { class: "icon", title: "preview on the robot", "aria-label": `Preview ${d.name} on the robot`, testid: "demo-preview", onclick: () => previewDemo(d.name) }, "▶"));
  if (!d.error) actions.push(el("button", { class: "icon", title: "fit a movement primitive (DMP) to it on the robot chosen under Source: a policy to watch, score and export", "aria-label": `Fit a movement primitive to ${d.name}`, testid: "demo-dmp", onclick: (e) => fitPrimitive(d.name, e.currentTarget) }, "≈"));
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
  renderWatchDemos();
  fillExportItems("demonstration");
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

/** Fit the movement-primitive baseline to a demonstration on the robot taught; it joins the
 * policies, chosen to watch. */
async function fitPrimitive(name, button) {
  await guarded("demo-error", async () => {
    const policy = await api("POST", `/api/demonstrations/${enc(name)}/dmp`);
    await showNewPolicy(policy);
  }, button);
}

async function deleteDemo(name) {
  if (!(await confirmDialog(`Delete the demonstration ${name}? The recording it came from is kept.`))) return;
  await guarded("demo-error", async () => {
    await api("DELETE", `/api/demonstrations/${enc(name)}`);
    await loadDemos();
  });
}
