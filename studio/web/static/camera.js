/* Teach Studio page: the camera teacher (docs/api.md, "Teachers without hardware").
 *
 * An ES module that index.html loads after main.js. It follows the live source (`listen("source")`
 * in state.js, on every status), keeps its loop in `S.camera`, and announces each frame it sent
 * and the studio's answer as `S.landmarks` (the browser tests collect them).
 *
 * When the live source is `camera`, the page asks for the camera, runs BlazePose (MediaPipe Tasks'
 * PoseLandmarker from the vendored `@mediapipe/tasks-vision`, loaded only then, on the CPU) on each
 * new video frame, draws the picture small with the skeleton over it, and sends each frame's 33
 * world and image landmarks to POST /api/source/landmarks. No picture leaves the page. Frames are
 * taken one at a time, with a yield to the page between them: the model runs on the page's thread.
 * A person the model takes for one seen from behind has their left and right put back (see
 * facesAway).
 */

import { api } from "./api.js";
import { $, setProp, setText } from "./dom.js";
import { S, listen, set } from "./state.js";

const VENDOR = "/static/vendor/mediapipe-tasks-vision";
const MODELS = { lite: "/static/vendor/pose-landmarker/pose_landmarker_lite.task", full: "/static/vendor/pose-landmarker/pose_landmarker_full.task" };
// On the CPU (XNNPACK in WebAssembly), not WebGL: without a GPU, browsers draw WebGL in software
// (SwiftShader), where the same model took about 20 times the CPU per frame (vendor/README.md);
// lite takes about two thirds of full's.
const DEFAULT_MODEL = "lite";
const CAMERA_SIZE = { width: 640, height: 480 }; // asked of the camera; BlazePose works on 256 px
const ARM_LANDMARKS = { right: [12, 14, 16], left: [11, 13, 15] }; // shoulder, elbow, wrist
const VISIBLE = 0.5; // a bone with a less visible end is not drawn
// BlazePose's left/right landmark pairs (nose excepted: eyes, ears, mouth, shoulders, arms, hands, legs).
const LEFT_RIGHT = [[1, 4], [2, 5], [3, 6], [7, 8], [9, 10], [11, 12], [13, 14], [15, 16], [17, 18], [19, 20], [21, 22], [23, 24], [25, 26], [27, 28], [29, 30], [31, 32]];
// The right shoulder this far (a fraction of the shoulders-to-hips height) right of the left one in
// the picture reads as a person seen from behind; nearer, the person may simply stand sideways.
const TURNED_MARGIN = 0.25;
// Human-arm joints in HumanArm's order (studio.kinematics ARM_JOINTS), as the page names them.
const JOINT_LABELS = ["shoulder Z", "shoulder X", "shoulder Y", "elbow Z", "elbow Y", "wrist Z", "wrist X"];
// The achieved frame rate is counted over the last FPS_FRAMES results within FPS_WINDOW_S: a few
// seconds at camera rate, and still a figure on a busy machine without a GPU (a frame in seconds).
const FPS_FRAMES = 10;
const FPS_WINDOW_S = 20;
const CAPTURE_AGE_MS = 5000; // a frame's captureTime older than this is taken as another clock's
const FRAME_WAIT_MS = 100; // wait at most this long for the next video frame (hidden tabs, old browsers)
const PREFS_KEY = "studio.camera";
// This page's id in every landmark frame: the studio tells a second tab by it. Frames' times are
// the camera's capture times, so a frame estimated slowly on a busy machine would seem, by its
// time alone, to come from another clock. (Not crypto.randomUUID: a plain-HTTP page on the LAN
// is no secure context.)
const SENDER = `${Date.now().toString(36)}-${Math.random().toString(36).slice(2, 12)}`;

const C = {
  running: false, // the camera loop is on
  starting: null, // the promise of a start under way
  session: 0, // bumped by stop(): a start still under way then gives up quietly
  stream: null,
  pose: null, // the PoseLandmarker
  poseModel: null, // the model it runs
  poseTime: 0, // the last timestamp (ms) given to the model: each must be later than the one before
  fps: null,
  frames: 0, // results drawn
  sent: 0, // landmark frames the studio accepted
  times: [], // the last result times (s), for the frame rate
  inflight: false, // one landmark POST at a time; the newest frame waits, older ones are dropped
  pending: null,
  status: null, // {text, level}: one sentence about what the camera sees or why it cannot
  answer: null, // the studio's last answer: {person_detected, observable, warning, ...}
  studioSide: null, // the teaching arm the studio last reported
  probe: null, // tests and benchmarks: a function(canvas) of the frame; its value travels with it
  swapped: 0, // results whose left and right labels the page swapped back (see facesAway)
  grabbed: null, // the canvas each frame is copied into
  current: null, // the frame the model works on: {t, tag, width, height}
};
S.camera = C;

/* ------------------------------------------------------------------ preferences */
function loadPrefs() {
  try { return JSON.parse(localStorage.getItem(PREFS_KEY)) || {}; } catch (e) { return {}; }
}
function savePrefs() {
  try {
    localStorage.setItem(PREFS_KEY, JSON.stringify({
      model: $("camera-model").value,
      mirror: $("camera-mirror").checked,
      countdown: $("capture-countdown").value,
    }));
  } catch (e) { /* private mode: the choices last this visit only */ }
}

/* ------------------------------------------------------------------ status words */
function setStatus(text, level = "notice") {
  C.status = text ? { text, level } : null;
  renderStatus();
}

/** One sentence: the camera's own trouble first, then the studio's word on the last frame (no
 * person in view, the arm out of the picture: the studio's fit decides, the page only shows it). */
function renderStatus() {
  let status = C.status;
  if (!status && C.answer && C.answer.warning) status = { text: C.answer.warning, level: "notice" };
  const box = $("camera-status");
  setProp(box, "hidden", !status);
  setText(box, status ? status.text : "");
  setProp(box, "className", status && status.level === "error" ? "err" : "notice");
}

function cameraErrorSentence(e) {
  const name = e && e.name;
  if (name === "NotAllowedError" || name === "SecurityError") return "The browser refused the camera: allow it for this page (the camera icon in the address bar), then press Apply again.";
  if (name === "NotReadableError" || name === "AbortError") return "The camera is busy: close the other program or tab using it (a video call?), then press Apply again.";
  if (name === "NotFoundError" || name === "OverconstrainedError") return "No camera was found: connect one, then press Apply again.";
  return `The camera could not start (${(e && e.message) || e}): check it works in another program, then press Apply again.`;
}

/* ------------------------------------------------------------------ BlazePose */
let vision = null; // the @mediapipe/tasks-vision module, once loaded

async function ensurePose(model) {
  if (C.pose && C.poseModel === model) return;
  if (!vision) {
    try {
      vision = await import(`${VENDOR}/vision_bundle.mjs`);
    } catch (e) {
      throw new Error(`${VENDOR}/vision_bundle.mjs did not load; reinstall Teach Studio`);
    }
  }
  // Every file comes from the studio's own vendored copy: nothing from another host.
  const fileset = await vision.FilesetResolver.forVisionTasks(VENDOR);
  const pose = await vision.PoseLandmarker.createFromOptions(fileset, {
    baseOptions: { modelAssetPath: MODELS[model], delegate: "CPU" },
    runningMode: "VIDEO", // each frame's person found from the last one's, as a video
    numPoses: 1,
    minPoseDetectionConfidence: 0.5,
    minPosePresenceConfidence: 0.5,
    minTrackingConfidence: 0.5,
    outputSegmentationMasks: false,
  });
  // Landmarks as the camera sees them, unsmoothed (the studio filters, One Euro, and reports the
  // lag it adds); the picture is mirrored on screen only.
  if (C.pose) C.pose.close();
  C.pose = pose;
  C.poseModel = model;
}

/* ------------------------------------------------------------------ the camera loop */
async function start() {
  if (C.running || C.starting) return C.starting;
  const session = ++C.session;
  const stopped = () => session !== C.session;
  C.starting = (async () => {
    setStatus(null);
    if (!navigator.mediaDevices || !navigator.mediaDevices.getUserMedia) {
      setStatus("This browser offers no camera to this page: open the studio at http://127.0.0.1 or http://localhost (a secure context).", "error");
      return;
    }
    let stream;
    try {
      stream = await navigator.mediaDevices.getUserMedia({ video: { ...CAMERA_SIZE, facingMode: "user" }, audio: false });
    } catch (e) {
      if (!stopped()) setStatus(cameraErrorSentence(e), "error");
      return;
    }
    if (stopped()) { for (const track of stream.getTracks()) track.stop(); return; }
    C.stream = stream;
    const video = $("camera-video");
    video.srcObject = stream;
    try {
      await video.play();
    } catch (e) {
      if (stopped()) return; // switched away while starting: nothing went wrong
      stopStream();
      setStatus(cameraErrorSentence(e), "error");
      return;
    }
    setStatus("Loading the pose model (a few seconds)…", "info");
    try {
      await ensurePose($("camera-model").value);
    } catch (e) {
      if (stopped()) return;
      stopStream();
      setStatus(`The pose model could not start in this browser (${(e && e.message) || e}): try an up-to-date Chrome, Edge or Firefox.`, "error");
      return;
    }
    if (stopped()) return;
    setStatus(null);
    C.running = true;
    C.times = [];
    loop();
  })();
  try { await C.starting; } finally { C.starting = null; }
}

function stopStream() {
  if (C.stream) for (const track of C.stream.getTracks()) track.stop();
  C.stream = null;
  $("camera-video").srcObject = null;
}

function stop() {
  C.session += 1;
  C.running = false;
  stopStream();
  C.fps = null;
  C.answer = null;
  setStatus(null);
  renderFps();
  renderObservable(null);
}

/** Resolve on the video's next frame (or after FRAME_WAIT_MS), then after a yield to the page. */
function nextFrame(video) {
  return new Promise((resolve) => {
    let done = false;
    const go = (now, meta) => {
      if (done) return;
      done = true;
      setTimeout(() => resolve(meta || null), 0);
    };
    if (video.requestVideoFrameCallback) video.requestVideoFrameCallback(go);
    setTimeout(go, FRAME_WAIT_MS);
  });
}

/** The video's current picture, copied into a canvas kept for the next frames. */
function grab(video) {
  const canvas = C.grabbed || (C.grabbed = document.createElement("canvas"));
  if (canvas.width !== video.videoWidth) canvas.width = video.videoWidth;
  if (canvas.height !== video.videoHeight) canvas.height = video.videoHeight;
  canvas.getContext("2d").drawImage(video, 0, 0);
  return canvas;
}

async function loop() {
  const video = $("camera-video");
  while (C.running) {
    const meta = await nextFrame(video);
    if (!C.running) break;
    if (video.readyState < 2 || !video.videoWidth) continue;
    // The page's clock when the camera took the picture, if the browser says so; else now.
    const now = performance.now();
    const captured = meta && meta.captureTime > now - CAPTURE_AGE_MS && meta.captureTime <= now ? meta.captureTime : now;
    // One copy of the frame for the model, the drawing and its time: the video moves on meanwhile.
    const frame = grab(video);
    C.current = { t: captured / 1000, tag: C.probe ? C.probe(frame) : null, width: frame.width, height: frame.height };
    try {
      if (C.poseModel !== $("camera-model").value) { // the user switched lite/full
        setStatus("Loading the pose model (a few seconds)…", "info");
        await ensurePose($("camera-model").value);
        setStatus(null);
      }
      C.poseTime = Math.max(C.poseTime + 1, captured);
      onResults(C.pose.detectForVideo(frame, C.poseTime));
    } catch (e) {
      setStatus(`Pose estimation stopped (${(e && e.message) || e}): press Apply to start the camera again.`, "error");
      C.running = false;
      stopStream();
    }
  }
}

/**
 * Whether BlazePose labelled the person as seen from behind: their right shoulder on the
 * picture's right (the camera's picture, not mirrored), clearly so for the body's height.
 *
 * The studio's contract is a person facing the camera, whose right is on the picture's left.
 * BlazePose decides left from right by the body it believes it sees, and on some figures (the
 * studio's own rendered mannequin, a face it cannot read) it takes the front for the back and
 * swaps every left/right pair: the taped arm's landmarks would then be the other arm's.
 */
function facesAway(image, width, height) {
  const [ls, rs, lh, rh] = [image[11], image[12], image[23], image[24]];
  const torso = Math.hypot(((ls.x + rs.x - lh.x - rh.x) / 2) * width, ((ls.y + rs.y - lh.y - rh.y) / 2) * height);
  return (rs.x - ls.x) * width > TURNED_MARGIN * torso;
}

/** The landmarks with every left/right pair exchanged. */
function swapSides(points) {
  const out = points.slice();
  for (const [a, b] of LEFT_RIGHT) [out[a], out[b]] = [points[b], points[a]];
  return out;
}

function onResults(results) {
  const frame = C.current;
  if (!frame || !C.running) return;
  const now = performance.now() / 1000;
  C.frames += 1;
  C.times.push(now);
  while (C.times.length > FPS_FRAMES || (C.times.length && C.times[0] < now - FPS_WINDOW_S)) C.times.shift();
  C.fps = C.times.length > 1 ? (C.times.length - 1) / (C.times[C.times.length - 1] - C.times[0]) : null;
  let image = results.landmarks[0] || null;
  let world = results.worldLandmarks[0] || null;
  // Seen "from behind": swap the labels back, so the taped arm is the person's taped arm.
  const swapped = !!(image && world && facesAway(image, frame.width, frame.height));
  if (swapped) {
    image = swapSides(image);
    world = swapSides(world);
    C.swapped += 1;
  }
  draw(image, $("source-side").value);
  renderFps();
  send({
    t: frame.t,
    world: world && image ? world.map((p) => [p.x, p.y, p.z, p.visibility ?? 0]) : null,
    image: world && image ? image.map((p) => [p.x, p.y, p.visibility ?? 0]) : null,
    width: frame.width,
    height: frame.height,
    fps: C.fps,
    model: C.poseModel,
    sender: SENDER,
  }, { tag: frame.tag, tResult: now, swapped });
}

/* ------------------------------------------------------------------ to the studio */
function send(body, info) {
  if (C.inflight) { C.pending = [body, info]; return; }
  C.inflight = true;
  post(body, info).finally(() => {
    C.inflight = false;
    const next = C.pending;
    C.pending = null;
    if (next && C.running) send(...next);
  });
}

async function post(body, info) {
  let answer = null;
  try {
    answer = await api("POST", "/api/source/landmarks", body);
    C.sent += 1;
    C.answer = answer;
    if (C.status && C.status.level !== "error") C.status = null;
  } catch (e) {
    // 429 (too many frames) drops this one; anything else is worth a word.
    if (!/too many|429/i.test(e.message)) setStatus(e.message, "notice");
  }
  renderStatus();
  renderObservable(answer ? answer.observable : null);
  set("landmarks", { body, answer, tag: info.tag, swapped: info.swapped, tResult: info.tResult, tAnswered: performance.now() / 1000 });
}

/* ------------------------------------------------------------------ drawing */
function draw(lm, side) {
  const picture = C.grabbed; // the frame the model saw, from the page's own copy
  const canvas = $("camera-view");
  const w = canvas.width;
  const h = Math.round((w * picture.height) / picture.width) || canvas.height;
  if (canvas.height !== h) canvas.height = h;
  const ctx = canvas.getContext("2d");
  ctx.save();
  if ($("camera-mirror").checked) { ctx.translate(w, 0); ctx.scale(-1, 1); }
  ctx.drawImage(picture, 0, 0, w, h);
  if (lm) {
    ctx.lineWidth = 2;
    ctx.strokeStyle = "rgba(255,255,255,0.85)";
    ctx.beginPath();
    for (const { start: a, end: b } of vision.PoseLandmarker.POSE_CONNECTIONS) {
      if (lm[a].visibility < VISIBLE || lm[b].visibility < VISIBLE) continue;
      ctx.moveTo(lm[a].x * w, lm[a].y * h);
      ctx.lineTo(lm[b].x * w, lm[b].y * h);
    }
    ctx.stroke();
    const arm = ARM_LANDMARKS[side];
    ctx.strokeStyle = "#fc6";
    ctx.lineWidth = 4;
    ctx.beginPath();
    arm.forEach((i, k) => (k ? ctx.lineTo(lm[i].x * w, lm[i].y * h) : ctx.moveTo(lm[i].x * w, lm[i].y * h)));
    ctx.stroke();
    ctx.fillStyle = "#fc6";
    for (const i of arm) {
      ctx.beginPath();
      ctx.arc(lm[i].x * w, lm[i].y * h, 4, 0, 2 * Math.PI);
      ctx.fill();
    }
  }
  ctx.restore();
}

function renderFps() {
  setText("camera-fps", C.fps == null ? "–" : C.fps.toFixed(1));
  setText("camera-model-running", C.running && C.poseModel ? C.poseModel : "–");
}

function renderObservable(observable) {
  const box = $("camera-observable");
  if (!box.children.length) {
    for (const label of JOINT_LABELS) box.append(Object.assign(document.createElement("span"), { className: "joint", textContent: label }));
  }
  [...box.children].forEach((chip, j) => {
    const state = observable ? (observable[j] ? "seen" : "held") : "";
    setProp(chip.dataset, "state", state);
    setProp(chip, "title", state === "seen" ? "the camera determines this joint in this frame" : state === "held" ? "not seen well from one camera: held smoothly from earlier frames" : "");
  });
  setProp(box.dataset, "observable", observable ? observable.map((o) => (o ? "1" : "0")).join("") : "");
}

/* ------------------------------------------------------------------ following the source */
function onSource(s) {
  if (!s) return;
  // Follow the studio's side when it changes there, not on every status: a choice not yet applied stays.
  if (s.side && s.side !== C.studioSide) { C.studioSide = s.side; setProp("source-side", "value", s.side); }
  if (s.kind === "camera" && !C.running && !C.starting) start();
  // Another source: the camera stops, and what it said (a failed start too) goes with it.
  else if (s.kind !== "camera" && (C.running || C.starting || C.stream || C.status)) stop();
}

function wire() {
  const prefs = loadPrefs();
  if (prefs.model in MODELS) $("camera-model").value = prefs.model;
  else $("camera-model").value = DEFAULT_MODEL;
  if (typeof prefs.mirror === "boolean") $("camera-mirror").checked = prefs.mirror;
  if (prefs.countdown !== undefined && prefs.countdown !== "") $("capture-countdown").value = prefs.countdown;
  for (const id of ["camera-model", "camera-mirror", "capture-countdown"]) $(id).addEventListener("change", savePrefs);
  listen("source", onSource);
  renderObservable(null);
  renderFps();
  onSource(S.source);
}

wire();
