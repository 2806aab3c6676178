/* Teach Studio page: the live source: its status line, the source form, playback, the simulator's reach, the robot taught. */

import { api, guarded, inTurn } from "./api.js";
import { $, fmt, setProp, setText, showError } from "./dom.js";
import { S, listen, set } from "./state.js";

export function renderSource() {
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
  // The joints of the robot drawn (the live chain drives another robot once it is drawn): never
  // angles of another width than the drawn robot's.
  const drawn = (S.robots || []).find((r) => r.name === s.robot_drawn);
  const q = s.q_robot || [];
  const fits = !drawn || drawn.joints.length === q.length;
  setText("src-q", fits ? q.map((v) => ((v * 180) / Math.PI).toFixed(0).padStart(4)).join(" ") + " °" : "–");
  // The source's own trouble (no device, a dropped bridge) stays apart from a refused action.
  showError("source-status-error", s.error ? `Source: ${s.error}` : null);
  const rejected = s.rejected ? `${s.rejected} datagram${s.rejected === 1 ? "" : "s"} rejected` : "";
  const warning = [s.warning, rejected].filter(Boolean).join(" · ");
  setProp("source-warning", "hidden", !warning);
  setText("source-warning", warning);
  if (document.activeElement !== $("retarget-mode") && s.retarget) setProp("retarget-mode", "value", s.retarget.mode);
  renderRobot(s);
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
}
// The status line follows every status; the capture and mark buttons (main.js) and camera.js after it.
listen("source", renderSource);

export function syncKindOptions() {
  const kind = $("source-kind").value;
  for (const e of document.querySelectorAll(".kind-opt")) e.hidden = !e.dataset.kind.split(" ").includes(kind);
}

export async function applySource() {
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
    set("source", await api("PUT", "/api/source", body));
    return true;
  }, $("source-apply"));
  // A refused switch changed nothing on the server: the selector goes back to the source that
  // still runs, so the page never names one source while another one feeds it.
  if (!switched && S.source && S.source.kind) {
    setProp("source-kind", "value", S.source.kind);
    syncKindOptions();
  }
}

export async function simulatorReach(action) {
  const body = { action };
  if (action === "reach") {
    const f = $("train-form").elements;
    body.goal_deg = [Number(f.goal0.value), Number(f.goal1.value), Number(f.goal2.value)];
  }
  await guarded("source-error", async () => {
    set("source", await api("POST", "/api/source/reach", body));
  }, $(action === "reach" ? "source-reach" : "source-wander"));
}

const playbackInTurn = inTurn(); // a seek, then play: in that order

export function playback(action, extra = {}) {
  return playbackInTurn(() => guarded("source-error", async () => {
    set("source", await api("POST", "/api/source/playback", { action, ...extra }));
  }));
}

export async function setRetarget() {
  await guarded("source-error", async () => {
    set("source", await api("PUT", "/api/source/retarget", {
      mode: $("retarget-mode").value,
      mirror: $("retarget-mirror").checked,
    }));
  });
}

// ------------------------------------------------------------------ the robot taught

function renderRobot(s) {
  const select = $("robot-name");
  if (s.robot && !select.dataset.pending && document.activeElement !== select && select.querySelector(`option[value="${s.robot}"]`)) {
    setProp(select, "value", s.robot);
    announceRobot(s.robot);
  }
  showTrainedRobot();
  // Joint mode maps the arm's joints onto a robot that offers it (GET /api/robots' joint_mode:
  // the Puma560); any other robot follows the hand.
  const joint = $("retarget-mode").querySelector('option[value="joint"]');
  const taught = (S.robots || []).find((r) => r.name === s.robot);
  if (joint) setProp(joint, "disabled", !!taught && !taught.joint_mode);
  setProp("robot-warning", "hidden", !s.robot_warning);
  setText("robot-warning", s.robot_warning || "");
  renderRobotNotes(s.robot_notes || []);
  steadyNotices(s);
}

// The notices under the source come and go with the frames (a hand that moves between two
// warnings changes them every second): the room they took stays theirs while the same source
// feeds the same robot, so the sections below never jump. Another source or robot starts afresh.
let notices = { key: null, height: 0 };

function steadyNotices(s) {
  const box = $("source-notices");
  const key = `${s.kind} ${s.recording || ""} ${s.robot || ""}`;
  if (key !== notices.key) {
    notices = { key, height: 0 };
    setProp(box.style, "minHeight", "");
  }
  const height = box.offsetHeight; // never below the room already kept
  if (height > notices.height) {
    notices.height = height;
    setProp(box.style, "minHeight", `${height}px`);
  }
}

/** One line per sentence the studio gives about the robot drawn (its meshes loading, a motion
 * being retargeted onto it, what cannot be shown on it and why); while a switch is on its way,
 * the page's own "loading" line. */
function renderRobotNotes(notes) {
  const select = $("robot-name");
  const pending = select.dataset.pending ? [`Loading the ${robotTitle(select.value)}'s meshes…`] : [];
  const lines = [...pending, ...notes];
  const box = $("robot-notes");
  if (box.dataset.text !== lines.join("\n")) {
    box.dataset.text = lines.join("\n");
    box.replaceChildren(...lines.map((line) => { const p = document.createElement("p"); p.textContent = line; return p; }));
  }
  setProp(box, "hidden", !lines.length);
}

function robotTitle(name) {
  const option = $("robot-name").querySelector(`option[value="${name}"]`);
  return option ? option.textContent.split(" (")[0] : name;
}

export async function loadRobots() {
  await guarded("source-error", async () => {
    const body = await api("GET", "/api/robots");
    const select = $("robot-name");
    select.replaceChildren(...body.robots.map((r) => {
      const o = document.createElement("option");
      o.value = r.name;
      o.textContent = r.title;
      o.title = `${r.joints.length} joints: ${r.joints.join(", ")}`;
      return o;
    }));
    select.value = body.robot;
    S.robots = body.robots;
    S.limitMargin = body.limit_margin_rad;
    showTrainedRobot();
    announceRobot(body.robot);
  });
}

/** Tell the page's other parts (the train form's goal, the timeline, the jog sliders) that the
 * robot taught is now ``name``: `set("robot")`, once per change. */
function announceRobot(name) {
  if (!S.robots || S.robot === name) return;
  set("robot", name);
}

/** The train form says which robot a run trains: the one chosen here. */
function showTrainedRobot() {
  const option = $("robot-name").selectedOptions[0];
  if (option) setText("train-robot", option.textContent);
}

export async function setRobot() {
  const select = $("robot-name");
  select.dataset.pending = "1";
  renderRobotNotes((S.source && S.source.robot_notes) || []);
  try {
    const chosen = await guarded("source-error", async () => {
      const body = await api("PUT", "/api/robot", { name: select.value });
      select.value = body.robot;
      showTrainedRobot();
      announceRobot(body.robot);
      return true;
    }, select);
    if (!chosen && S.source && S.source.robot) select.value = S.source.robot;
  } finally {
    delete select.dataset.pending;
    renderRobotNotes((S.source && S.source.robot_notes) || []);
  }
}
