/* Teach Studio page: recording in takes, as LeRobot's recording loop.
 *
 * Start take counts down (the Countdown control, countdown.js), then records; Stop take
 * (Escape) plays the take on the robot with its tool path drawn, for review. Then Keep take, Keep
 * and next (→) or Redo take (←, the take's recording is deleted). Make demonstrations cuts every
 * kept take, whole, into a demonstration in one go. The session lives in the data folder
 * (recordings/takes.json, see recordings/README.md), so a reload carries on with it.
 */

import { api, guarded } from "./api.js";
import { loadDemos } from "./demos.js";
import { $, el, setProp, setText } from "./dom.js";
import { loadRecordings, renderCaptureButton } from "./recordings.js";
import { recordCountdown } from "./countdown.js";
import { S } from "./state.js";

let counting = false;

function lastTake() {
  const list = S.takes.takes;
  return list.length ? list[list.length - 1] : null;
}

/** Where the flow is: idle, countdown, recording, review or kept (the last take's state). */
function phase() {
  if (counting) return "countdown";
  const last = lastTake();
  return last ? last.state : "idle";
}

const STATE_TEXT = {
  idle: "",
  countdown: "get into place…",
  recording: "recording the take: Esc stops it",
  review: "playing the take on the robot: keep it (→ keeps and starts the next) or redo it (←)",
  kept: "kept: start the next take, or make the kept takes into demonstrations",
};

export function renderTakes() {
  const p = phase();
  S.takePhase = p;
  const start = $("take-start");
  setText(start, p === "recording" ? "■ Stop take" : p === "countdown" ? "Cancel" : "● Start take");
  start.classList.toggle("active", p === "recording");
  setProp(start.dataset, "phase", p);
  setProp($("take-keep"), "disabled", p !== "review");
  setProp($("take-next"), "disabled", p !== "review");
  setProp($("take-review"), "disabled", p !== "review");
  setProp($("take-redo"), "disabled", !(p === "review" || p === "recording"));
  const kept = S.takes.takes.filter((t) => t.state === "kept" && !t.demonstration).length;
  setProp($("takes-make"), "disabled", !(p === "kept" && kept));
  setText("takes-state", STATE_TEXT[p] || "");
  const items = S.takes.takes.map((t, i) => el("li", { testid: "take", "data-name": t.recording, "data-state": t.state, title: t.error || t.recording },
    `take ${i + 1}: `, el("span", { class: "mono small", text: t.recording }), " ",
    el("span", { class: t.state === "kept" ? "badge done" : "badge warn", text: t.state })));
  $("takes-list").replaceChildren(...items);
}

async function send(path, body) {
  const session = await api("POST", path, body);
  if (session) S.takes = session;
  return session;
}

async function refreshCapture() {
  S.capture = await api("GET", "/api/capture");
  renderCaptureButton();
}

export async function startTake() {
  const p = phase();
  if (p === "recording") return stopTake();
  if (p === "countdown") { await recordCountdown(); return; } // cancels it
  if (p === "review") { showTakesError("Keep or redo the take under review first."); return; }
  counting = true;
  setProp("takes-made", "hidden", true);
  renderTakes();
  const go = await recordCountdown(true, "Esc cancels");
  counting = false;
  if (!go) { renderTakes(); return; }
  const operator = $("capture-operator").value.trim();
  await guarded("takes-error", async () => {
    await send("/api/takes/start", operator ? { operator } : {});
    await refreshCapture();
  }, $("take-start"));
  renderTakes();
}

export async function stopTake() {
  await guarded("takes-error", async () => {
    await send("/api/takes/stop");
    await refreshCapture();
    await loadRecordings();
  }, $("take-start"));
  renderTakes();
}

export async function keepTake(next = false) {
  const ok = await guarded("takes-error", () => send("/api/takes/keep"), $("take-keep"));
  renderTakes();
  if (ok && next) await startTake();
}

export async function redoTake() {
  await guarded("takes-error", async () => {
    await send("/api/takes/redo");
    await refreshCapture();
    await loadRecordings();
  }, $("take-redo"));
  renderTakes();
}

async function reviewTake() {
  await guarded("takes-error", () => api("POST", "/api/takes/review"), $("take-review"));
}

async function makeDemonstrations() {
  const body = { goal_from_end: $("demo-goal-from-end").checked };
  const done = await guarded("takes-error", () => api("POST", "/api/takes/demonstrations", body), $("takes-make"));
  if (!done) return;
  const made = done.takes.filter((t) => t.demonstration).length;
  const failed = done.takes.filter((t) => t.error);
  setProp("takes-made", "hidden", false);
  setText("takes-made", `Made ${made} demonstration${made === 1 ? "" : "s"} from ${done.takes.length} take${done.takes.length === 1 ? "" : "s"}.`);
  if (failed.length) showTakesError(failed.map((t) => `${t.recording}: ${t.error}`).join("\n"));
  S.takes = { started: null, finished: null, takes: [] };
  renderTakes();
  await loadDemos();
}

function showTakesError(text) {
  setText("takes-error", text);
  setProp("takes-error", "hidden", !text);
}

/** LeRobot's recorder keys: → keeps the take and starts the next, ← redoes it, Escape stops it
 * (or cancels the countdown). Only while a take is under way, and never while typing. */
function onKey(ev) {
  const p = phase();
  if (p === "idle" || p === "kept" || ev.altKey || ev.ctrlKey || ev.metaKey) return;
  const target = ev.target;
  if (target && (target.isContentEditable || ["INPUT", "TEXTAREA", "SELECT"].includes(target.tagName))) return;
  if (target && target.closest && target.closest("[data-keys='own']")) return; // the timeline's keys
  if (ev.key === "Escape" && (p === "recording" || p === "countdown")) {
    ev.preventDefault();
    if (p === "recording") stopTake();
    else recordCountdown();
  } else if (ev.key === "ArrowRight" && p === "review") {
    ev.preventDefault();
    keepTake(true);
  } else if (ev.key === "ArrowLeft" && (p === "review" || p === "recording")) {
    ev.preventDefault();
    redoTake();
  }
}

async function wire() {
  $("take-start").addEventListener("click", startTake);
  $("take-keep").addEventListener("click", () => keepTake(false));
  $("take-next").addEventListener("click", () => keepTake(true));
  $("take-redo").addEventListener("click", redoTake);
  $("take-review").addEventListener("click", reviewTake);
  $("takes-make").addEventListener("click", makeDemonstrations);
  document.addEventListener("keydown", onKey);
  renderTakes();
  await guarded("takes-error", async () => {
    S.takes = await api("GET", "/api/takes");
    renderTakes();
  });
}

wire();
