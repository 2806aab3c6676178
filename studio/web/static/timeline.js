/* Teach Studio page: a recording's timeline, to cut demonstrations seeing the signal.
 *
 * Choosing a recording to cut from (or its row's timeline button) plots the joints of the robot
 * chosen under Source (solid, by its own joint names, retargeted by the server as an export is) and
 * the human arm's (dashed) over the whole recording, served downsampled by
 * GET /api/recordings/{name}/timeline (uPlot, as the curve chart); choosing another robot plots
 * its joints instead. "Timeline shows" plots the
 * recording's own values instead, as the server serves them (``signals``): a tape's bend or twist
 * per region, a camera's landmark visibility, a hand guide's hand position. The robot in the scene follows
 * the playhead: hovering the plot moves it, as do the arrow keys. Dragging selects the segment to
 * cut (its robot path is drawn and played in the scene); `[` and `]` set its ends at the playhead;
 * space plays and pauses. The segment is the Demonstrations section's t0 and t1, so Cut cuts it.
 */

import { api, guarded } from "./api.js";
import { setDemoRange } from "./demos.js";
import { $, el, enc, fmt, setProp, setText } from "./dom.js";
import { S, listen } from "./state.js";

const ROBOT = ["#1f4e9c", "#2a7bd8", "#0f8b8d", "#23874b", "#6b4fbb", "#b83280", "#5c6b7a"];
const HUMAN = ["#d9822b", "#b8661f", "#a0522d", "#c9a227", "#e05a47", "#8c6d46", "#7a7a7a"];
const STEP_S = 0.1;

const UNITS = { deg: (x) => `${x}°`, cm: (x) => `${x} cm` };

const T = { asked: 0, drawn: 0, name: null, show: "joints", data: null, chart: null, playhead: 0, playing: false, last: 0, want: null, sending: false };
S.timeline = T;

function duration() { return T.data ? T.data.duration : 0; }
function clamp(t) { return Math.max(0, Math.min(duration(), t)); }
function ends() { return [Number($("demo-t0").value) || 0, Number($("demo-t1").value) || 0]; }

/** Plot recording ``name``'s joints (hidden with no name). */
export async function showTimeline(name) {
  pause();
  T.name = name || null;
  setProp("timeline", "hidden", !name);
  setProp("timeline-bar", "hidden", !name);
  if (!name) return;
  const box = $("timeline-plot");
  const points = Math.max(100, Math.min(600, box.clientWidth || 400));
  setText("timeline-time", "fitting the arm to the recording…");
  const asked = ++T.asked;
  await guarded("timeline-error", async () => {
    const data = await api("GET", `/api/recordings/${enc(name)}/timeline?points=${points}`);
    if (asked !== T.asked || T.name !== name) return; // another recording or robot was chosen meanwhile
    T.data = data;
    T.playhead = 0;
    showChoices();
    draw();
    T.drawn = asked; // the answer to the latest request is on screen (the browser tests wait for it)
  });
}

/** "Timeline shows": the joints, then what this recording itself holds; the choice stays when
 * the next recording has it too. */
function showChoices() {
  const names = ["joints", ...(T.data.signals || []).map((g) => g.name)];
  if (!names.includes(T.show)) T.show = "joints";
  const select = $("timeline-show");
  select.replaceChildren(...names.map((n) => el("option", { value: n, text: n === "joints" ? "joints (robot and human arm)" : n, selected: n === T.show })));
}

/** Say whose joints the solid lines are: the robot's name, then each joint's own, in its colour. */
function showLegend() {
  const d = T.data;
  const box = $("timeline-robot");
  const joints = T.show === "joints" && d ? d.robot_joints || [] : [];
  setProp(box, "hidden", !joints.length);
  if (!joints.length) { box.replaceChildren(); return; }
  box.replaceChildren(
    el("span", { text: `solid: joints of the ${d.robot_title}: ` }),
    ...joints.map((name, j) => el("span", { class: "mono", style: `color: ${ROBOT[j % ROBOT.length]}`, text: `${name} ` })),
    el("span", { text: "· dashed: the human arm's" }),
    ...(d.robot_notes || []).map((note) => el("span", { class: "warn", text: ` · ${note}` })),
  );
}

/** The plotted columns and their series: the joints, or one group of the recording's values. */
function plotted(d) {
  const cols = [d.times];
  const series = [{ label: "t (s)" }];
  const group = (d.signals || []).find((g) => g.name === T.show);
  if (group) {
    const n = group.labels.length;
    group.labels.forEach((label, j) => {
      cols.push(group.values.map((v) => v[j]));
      series.push({ label: `${group.name} ${label}`, stroke: `hsl(${Math.round(220 - (200 * j) / Math.max(1, n - 1))}, 65%, 42%)`, width: 1.3 });
    });
    return { cols, series, unit: UNITS[group.unit] || String };
  }
  const joints = d.robot_joints || (d.robot[0] || []).map((_, j) => `robot ${j + 1}`);
  joints.forEach((name, j) => {
    cols.push(d.robot.map((q) => q[j]));
    series.push({ label: name, stroke: ROBOT[j % ROBOT.length], width: 1.5 });
  });
  for (let j = 0; j < 7; j++) {
    cols.push(d.human.map((q) => q[j]));
    series.push({ label: `human ${j + 1}`, stroke: HUMAN[j], width: 1, dash: [4, 3] });
  }
  return { cols, series, unit: UNITS.deg };
}

function draw() {
  if (T.chart) { T.chart.destroy(); T.chart = null; }
  if (typeof uPlot === "undefined" || !T.data) return;
  const d = T.data;
  const { cols, series, unit } = plotted(d);
  S.timelineShown = series.slice(1).map((s) => s.label);
  showLegend();
  const box = $("timeline-plot");
  T.chart = new uPlot({
    width: Math.max(200, box.clientWidth),
    height: 170,
    legend: { show: false },
    scales: { x: { time: false, range: [0, Math.max(d.duration, 0.01)] } },
    axes: [{ size: 28 }, { size: 52, values: (u, v) => v.map(unit) }],
    series,
    cursor: { drag: { x: true, y: false, setScale: false }, points: { show: false } },
    hooks: {
      setSelect: [onSelect],
      setCursor: [onCursor],
      draw: [drawPlayhead],
    },
  }, cols, box);
  setProp("timeline", "ariaValueMax", fmt(d.duration, 2));
  showSelection();
  movePlayhead(T.playhead, false);
}

function drawPlayhead(u) {
  const x = Math.round(u.valToPos(T.playhead, "x", true));
  const ctx = u.ctx;
  ctx.save();
  ctx.strokeStyle = "#d33";
  ctx.lineWidth = 2;
  ctx.beginPath();
  ctx.moveTo(x, u.bbox.top);
  ctx.lineTo(x, u.bbox.top + u.bbox.height);
  ctx.stroke();
  ctx.restore();
}

/** Draw the Demonstrations section's segment as the plot's selection. */
function showSelection() {
  const u = T.chart;
  if (!u) return;
  const [t0, t1] = ends();
  if (!(t1 > t0)) { u.setSelect({ left: 0, width: 0, top: 0, height: 0 }, false); return; }
  const left = u.valToPos(clamp(t0), "x");
  u.setSelect({ left, width: u.valToPos(clamp(t1), "x") - left, top: 0, height: u.bbox.height / devicePixelRatio }, false);
}

function onSelect(u) {
  if (u.select.width < 3) { showSelection(); return; } // a click, not a drag: keep the segment
  const t0 = clamp(u.posToVal(u.select.left, "x"));
  const t1 = clamp(u.posToVal(u.select.left + u.select.width, "x"));
  setEnds(t0, t1);
}

function onCursor(u) {
  if (T.playing || u.cursor.left === undefined || u.cursor.left < 0) return;
  movePlayhead(clamp(u.posToVal(u.cursor.left, "x")));
}

/** Set the segment to cut: the Demonstrations section's t0 and t1, its path drawn and played. */
function setEnds(t0, t1) {
  setDemoRange(Math.min(t0, t1), Math.max(t0, t1));
  showSelection();
  const [a, b] = ends();
  if (b > a && T.name) guarded("timeline-error", () => api("POST", `/api/recordings/${enc(T.name)}/review`, { t0: a, t1: b }));
}

/** Move the playhead to ``t`` s; the robot in the scene follows (the latest pose wins). */
function movePlayhead(t, scrub = true) {
  T.playhead = t;
  const el = $("timeline");
  setProp(el, "ariaValueNow", fmt(t, 2));
  setProp(el, "ariaValueText", `${fmt(t, 2)} s`);
  const [t0, t1] = ends();
  setText("timeline-time", `${fmt(t, 2)} s of ${fmt(duration(), 2)} s · segment ${fmt(t0, 2)}–${fmt(t1, 2)} s`);
  if (T.chart) T.chart.redraw(false, false);
  if (scrub) scrubTo(t);
}

async function scrubTo(t) {
  T.want = t;
  if (T.sending || !T.name) return;
  T.sending = true;
  try {
    while (T.want !== null) {
      const want = T.want;
      T.want = null;
      await api("POST", `/api/recordings/${enc(T.name)}/review`, { t: want }).catch(() => {});
    }
  } finally {
    T.sending = false;
  }
}

function play() {
  if (!T.data) return;
  const [t0, t1] = ends();
  const stop = t1 > t0 ? t1 : duration();
  if (T.playhead >= stop - 1e-3) movePlayhead(t1 > t0 ? t0 : 0);
  T.playing = true;
  T.last = performance.now();
  setProp($("timeline").dataset, "playing", "1");
  const step = (now) => {
    if (!T.playing) return;
    const t = Math.min(stop, T.playhead + (now - T.last) / 1000);
    T.last = now;
    movePlayhead(t);
    if (t >= stop) pause();
    else requestAnimationFrame(step);
  };
  requestAnimationFrame(step);
}

function pause() {
  T.playing = false;
  setProp($("timeline").dataset, "playing", "0");
}

function onKey(ev) {
  if (!T.data || ev.altKey || ev.ctrlKey || ev.metaKey) return;
  const big = ev.shiftKey ? 10 : 1;
  const [t0, t1] = ends();
  const keys = {
    " ": () => (T.playing ? pause() : play()),
    "[": () => setEnds(T.playhead, t1 > T.playhead ? t1 : duration()),
    "]": () => setEnds(t0 < T.playhead ? t0 : 0, T.playhead),
    ArrowLeft: () => movePlayhead(clamp(T.playhead - STEP_S * big)),
    ArrowRight: () => movePlayhead(clamp(T.playhead + STEP_S * big)),
    Home: () => movePlayhead(0),
    End: () => movePlayhead(duration()),
  };
  const act = keys[ev.key];
  if (!act) return;
  ev.preventDefault();
  if (ev.key !== " ") pause();
  act();
}

function wire() {
  // another robot chosen under Source: plot its joints (the server retargets the recording onto it)
  listen("robot", () => { if (T.name) showTimeline(T.name); });
  $("timeline").addEventListener("keydown", onKey);
  $("timeline-show").addEventListener("change", (e) => { T.show = e.target.value; draw(); });
  $("demo-recording").addEventListener("change", () => showTimeline($("demo-recording").value));
  for (const id of ["demo-t0", "demo-t1"]) $(id).addEventListener("change", () => { showSelection(); movePlayhead(T.playhead, false); });
  for (const id of ["demo-t0-range", "demo-t1-range"]) $(id).addEventListener("input", showSelection);
  new ResizeObserver(() => { if (T.chart) T.chart.setSize({ width: Math.max(200, $("timeline-plot").clientWidth), height: 170 }); }).observe($("timeline-plot"));
}

wire();
