/* Teach Studio page: scrubbing a watched rollout, the scene's camera presets, and posing the robot by hand.
 *
 * The scene keeps the scrub position, the speed and the pause (POST /api/scene/playback); this
 * module only shows them and sends the user's changes. Between answers the time shown runs on the
 * page's own clock at the playback's speed, and only while the rollout plays: a paused or finished
 * rollout writes nothing to the page. It follows the policy watched (`watchedRun`, set by
 * policies.js).
 *
 * Posing by hand: a slider per robot joint between its limits (shown at both ends), which moves the
 * robot in the scene (POST /api/scene/jog, latest wins), and "use this pose as the goal", which
 * fills the train form's goal with joints 1-3 (degrees, as the form takes it).
 */

import { api, guarded, inTurn } from "./api.js";
import { $, el, fmt, setProp, setText, showError } from "./dom.js";
import { S, listen } from "./state.js";
import { checkTrainForm } from "./training.js";

const TICK_MS = 100; // the time shown moves this often while a rollout plays
const VIEWS = [["front", "Front view", "Front"], ["top", "Top view", "Top"], ["side", "Side view", "Side"]];
const GOAL_JOINTS = 3; // the train form's goal: joints 1-3
const BIG_STEP = 10; // samples a Shift+arrow steps
/** The rollout's keyboard shortcuts, as the page's tooltips and help list them. */
export const ROLLOUT_KEYS = "space play/pause · ←/→ one sample · Shift+←/→ ten samples · Home/End start/end";

// The rollout as the scene last answered, and when (performance.now()).
S.rollout = null;
let answeredAt = 0;
let ticker = null;

function build() {
  const speeds = [0.25, 0.5, 1, 2, 4];
  const box = $("watch-controls");
  box.replaceChildren(
    el("div", { class: "row wrap playback", id: "rollout", testid: "rollout", hidden: true },
      el("button", { id: "rollout-back", testid: "rollout-back", "aria-label": "Step back", "aria-keyshortcuts": "ArrowLeft Shift+ArrowLeft", title: "one sample back (←; Shift+← ten)", text: "|◀" }),
      el("button", { id: "rollout-play", testid: "rollout-play", "aria-label": "Pause", "aria-keyshortcuts": "Space", title: "play / pause (space)", text: "❚❚" }),
      el("button", { id: "rollout-forward", testid: "rollout-forward", "aria-label": "Step forward", "aria-keyshortcuts": "ArrowRight Shift+ArrowRight", title: "one sample forward (→; Shift+→ ten)", text: "▶|" }),
      el("input", { id: "rollout-time", testid: "rollout-time", type: "range", min: "0", max: "1", step: "any", value: "0", class: "grow", "aria-label": "Rollout time", "aria-keyshortcuts": "Home End", title: `drag to scrub; keys: ${ROLLOUT_KEYS}` }),
      el("span", { class: "mono", id: "rollout-clock", testid: "rollout-clock", text: "0.00 / 0.00 s" }),
      el("select", { id: "rollout-speed", testid: "rollout-speed", "aria-label": "Rollout speed", title: "playback speed" },
        ...speeds.map((s) => el("option", { value: String(s), text: `${s}×`, selected: s === 1 }))),
      el("span", { class: "muted keys", testid: "rollout-keys", title: "keyboard shortcuts while a rollout is shown (not while typing in a field)", text: `⌨ ${ROLLOUT_KEYS}` }),
    ),
    el("div", { class: "row", role: "group", "aria-label": "Camera" },
      el("span", { class: "muted", text: "camera:" }),
      ...VIEWS.map(([view, name, text]) => el("button", { testid: `view-${view}`, "aria-label": name, title: `${text} view of the scene`, text, onclick: () => showView(view) })),
      el("label", { title: "keep the robot's tool in the middle of the scene" },
        el("input", { type: "checkbox", id: "view-follow", testid: "view-follow", "aria-label": "Follow the tool", onchange: (e) => follow(e.target.checked) }), " follow the tool"),
    ),
    el("details", { id: "jog", testid: "jog", ontoggle: (e) => { if (e.target.open) loadJog(); } },
      el("summary", { text: "Pose by hand" }),
      el("p", { class: "muted small", id: "jog-robot", testid: "jog-robot" }),
      el("div", { id: "jog-joints", testid: "jog-joints" }),
      el("div", { class: "row" },
        el("button", { id: "jog-goal", testid: "jog-goal", text: "Use this pose as the goal", title: "fill Train → goal with joints 1–3 of this pose", onclick: useAsGoal }),
      ),
    ),
    el("div", { class: "err", id: "rollout-error", testid: "rollout-error", hidden: true }),
  );
  $("rollout-back").addEventListener("click", () => act({ step: -1 }));
  $("rollout-forward").addEventListener("click", () => act({ step: 1 }));
  $("rollout-play").addEventListener("click", () => act({ paused: !(S.rollout && S.rollout.paused) && !finished() }));
  $("rollout-speed").addEventListener("change", () => act({ speed: Number($("rollout-speed").value) }));
  const slider = $("rollout-time");
  slider.addEventListener("input", () => { slider.dataset.dragging = "1"; scrubTo(Number(slider.value)); });
  slider.addEventListener("change", () => { delete slider.dataset.dragging; scrubTo(Number(slider.value)); });
  document.addEventListener("keydown", onKey);
}

// ------------------------------------------------------------------ the rollout

function finished() {
  const r = S.rollout;
  return !!r && !r.paused && timeNow() >= r.duration;
}

function timeNow() {
  const r = S.rollout;
  if (!r) return 0;
  if (r.paused) return r.t;
  return Math.min(r.t + ((performance.now() - answeredAt) / 1000) * r.speed, r.duration);
}

/** Take the scene's answer and show it; the clock runs only while the rollout plays. */
function showRollout(r) {
  S.rollout = r && r.active ? r : null;
  answeredAt = performance.now();
  setProp("rollout", "hidden", !S.rollout);
  if (!S.rollout) { stopTicker(); return; }
  $("rollout-time").max = String(r.duration);
  setProp($("rollout-speed"), "value", String(r.speed));
  render();
  if (r.paused || r.finished) stopTicker();
  else if (!ticker) ticker = setInterval(render, TICK_MS);
}

function stopTicker() {
  if (ticker) clearInterval(ticker);
  ticker = null;
}

function render() {
  const r = S.rollout;
  if (!r) return;
  const t = timeNow();
  const slider = $("rollout-time");
  if (!slider.dataset.dragging) setProp(slider, "value", String(t));
  setText("rollout-clock", `${fmt(t, 2)} / ${fmt(r.duration, 2)} s`);
  const playing = !r.paused && t < r.duration;
  // A step has nowhere to go at an end: its button says so, rather than leave the clock still.
  setProp("rollout-forward", "disabled", t >= r.duration);
  setProp("rollout-back", "disabled", t <= 0);
  setText("rollout-play", playing ? "❚❚" : "▶");
  $("rollout-play").setAttribute("aria-label", playing ? "Pause" : "Play");
  if (!playing) stopTicker();
}

// The scene's changes go one at a time, in the order the user made them: a play sent while a scrub
// is still on its way would otherwise race it, and the scrub (which pauses) could land second.
const changeInTurn = inTurn();

function change(body) {
  return changeInTurn(() => guarded("rollout-error", async () => showRollout(await api("POST", "/api/scene/playback", body))));
}

// Scrubbing sends the newest position only, one request at a time, and pauses the rollout there.
let scrubBusy = false;
let scrubNext = null;

/** A step, play or pause, or speed: it comes after any scrub still waiting to be sent (the slider's
 * ``change`` that follows its last ``input``), which is dropped so it cannot undo this. */
async function act(body) {
  scrubNext = null;
  await change(body);
}
async function scrubTo(t) {
  scrubNext = t;
  if (scrubBusy) return;
  scrubBusy = true;
  try {
    while (scrubNext !== null) {
      const at = Math.min(Math.max(scrubNext, 0), S.rollout ? S.rollout.duration : 0);
      scrubNext = null;
      await change({ t: at, paused: true });
    }
  } finally {
    scrubBusy = false;
  }
}

export async function loadRollout() {
  try { showRollout(await api("GET", "/api/scene/playback")); } catch (e) { /* a studio without a scene */ }
}

/** Whether a key press belongs to where it happened: typing in a field, a focused button's own
 * space or Enter, the timeline's own keys, or a take under way (its ← and → keep and redo). */
function keyTakenElsewhere(ev) {
  const target = ev.target;
  if (!target || !target.closest) return false;
  if (target.isContentEditable || ["INPUT", "TEXTAREA", "SELECT"].includes(target.tagName)) return true;
  if ((ev.key === " " || ev.key === "Enter") && target.closest("button, summary, a, [role='button']")) return true;
  if (target.closest("[data-keys='own'], dialog[open]")) return true;
  const take = S.takePhase;
  return take !== "idle" && take !== "kept";
}

/** The rollout's keyboard shortcuts (``ROLLOUT_KEYS``), while a watched rollout is shown. */
function onKey(ev) {
  if (!S.rollout || ev.altKey || ev.ctrlKey || ev.metaKey || keyTakenElsewhere(ev)) return;
  const n = ev.shiftKey ? BIG_STEP : 1;
  const action = {
    " ": () => act({ paused: !S.rollout.paused && !finished() }),
    ArrowLeft: () => act({ step: -n }),
    ArrowRight: () => act({ step: n }),
    Home: () => scrubTo(0),
    End: () => scrubTo(S.rollout.duration),
  }[ev.key];
  if (!action) return;
  ev.preventDefault();
  action();
}

// ------------------------------------------------------------------ camera

async function showView(view) {
  await guarded("rollout-error", () => api("POST", "/api/scene/view", { view }));
}

async function follow(on) {
  await guarded("rollout-error", () => api("POST", "/api/scene/follow", { on }));
}

// ------------------------------------------------------------------ posing by hand

let jogBusy = false;
let jogNext = null;

async function loadJog() {
  await guarded("rollout-error", async () => {
    const jog = await api("GET", "/api/scene/jog");
    $("jog-joints").replaceChildren(...jog.joints.map((j, i) => jointRow(j, jog.q_deg[i])));
    $("jog").dataset.robot = jog.robot;
    setText("jog-robot", `${jog.title}: ${jog.joints.length} joints, each between its own limits`);
  });
}

/** One joint's slider, from its usable lower to its upper limit. Any step: Home and End put the
 * joint at its limit exactly (a step counted from a limit such as -158.85° stops short of the
 * other end). */
function jointRow(j, value) {
  const label = j.name[0].toUpperCase() + j.name.slice(1);
  const v = Math.min(Math.max(value, j.lower_deg), j.upper_deg);
  const input = el("input", { type: "range", class: "grow", min: String(j.lower_deg), max: String(j.upper_deg), step: "any", value: String(v), "aria-label": label, title: j.joint, testid: "jog-joint" });
  const shown = el("span", { class: "mono w5", testid: "jog-value", text: `${fmt(v, 1)}°` });
  input.addEventListener("input", () => { setText(shown, `${fmt(Number(input.value), 1)}°`); jog(); });
  return el("div", { class: "row jog-row" },
    el("span", { class: "w5", text: label, title: j.joint }),
    el("span", { class: "muted small mono jog-name", testid: "jog-name", title: j.joint, text: j.joint }),
    el("span", { class: "muted small mono", testid: "jog-min", title: `${label}'s lower limit`, text: `${fmt(j.lower_deg, 0)}°` }),
    input,
    el("span", { class: "muted small mono", testid: "jog-max", title: `${label}'s upper limit`, text: `${fmt(j.upper_deg, 0)}°` }),
    shown,
  );
}

function jogValues() {
  return [...$("jog-joints").querySelectorAll("input[type=range]")].map((i) => Number(i.value));
}

/** Send the sliders' pose (latest wins, one request at a time). */
async function jog() {
  jogNext = jogValues();
  if (jogBusy) return;
  jogBusy = true;
  try {
    while (jogNext) {
      const q = jogNext;
      jogNext = null;
      await guarded("rollout-error", () => api("POST", "/api/scene/jog", { q_deg: q }));
    }
  } finally {
    jogBusy = false;
  }
  showRollout(null); // a pose by hand replaces the rollout being scrubbed
}

/** A slider's angle to a hundredth of a degree, as a person types a goal, kept within its limits
 * (a slider's values step from its lower limit, so they carry its decimals). */
function goalAngle(input) {
  const lo = Math.ceil(Number(input.min) * 100) / 100;
  const hi = Math.floor(Number(input.max) * 100) / 100;
  return Math.min(hi, Math.max(lo, Math.round(Number(input.value) * 100) / 100));
}

function useAsGoal() {
  const sliders = [...$("jog-joints").querySelectorAll("input[type=range]")];
  if (sliders.length < GOAL_JOINTS) { showError("rollout-error", "Open Pose by hand and set the joints first."); return; }
  const f = $("train-form");
  for (let i = 0; i < GOAL_JOINTS; i++) {
    const input = f.elements[`goal${i}`];
    input.value = String(goalAngle(sliders[i]));
    input.dispatchEvent(new Event("change", { bubbles: true }));
  }
  showError("rollout-error", null);
  checkTrainForm(true); // at once, as Start would check it
}

build();
listen("watchedRun", loadRollout);
// Another robot chosen under Source: the sliders become its joints, between its limits.
listen("robot", () => { if ($("jog").open) loadJog(); else $("jog-joints").replaceChildren(); });
$("watch-stop").addEventListener("click", () => showRollout(null)); // the robot goes back to live
loadRollout();
