/* Teach Studio page: the page's one state, and the one way its parts announce a change.
 *
 * Every field the page's modules share is declared here, with what it holds and who writes it.
 * `S` is sealed: a module that writes a field not declared here throws (modules run in strict
 * mode), and tests/web/test_page_modules.py refuses one before it runs. A module's own details
 * stay in its own `let`s; only what another module (or a browser test) reads is a field.
 *
 * A change others follow is written with `set(field, value)`, which announces it to every
 * `listen(field, fn)`: the source's status, the robot taught, the policy watched, the camera's
 * last frame, the drawn run list. Nothing is put on `window`: a browser test reaches the state with
 * `import("/static/state.js")` (tests/page_hooks.py), the same module instance the page runs.
 */

export const S = Object.seal({
  config: null, // GET /api/config: the learning defaults, planners, scene address (scene.js)
  source: null, // the live source's status, as the studio last sent it (set: sources.js, events.js)
  capture: null, // the recording under way, or why the last one stopped (recordings.js, events.js)
  recordings: [], // GET /api/recordings (recordings.js)
  demos: [], // GET /api/demonstrations (demos.js)
  marking: false, // a demonstration is being marked while recording (demos.js)
  markT0: null, // where the marked demonstration starts (s of the recording; demos.js)
  runs: [], // GET /api/runs, newest first, updated by the live stream (runs.js)
  sweeps: [], // `studio sweep` summaries (GET /api/sweeps); their trials are runs of a group
  openSweeps: new Set(), // sweep ids unfolded in the run list (table, figure, runs)
  policies: [], // GET /api/policies (policies.js)
  robots: null, // the offered robots with their joints and default goals (GET /api/robots)
  robot: null, // the robot taught, as the page last announced it (set: sources.js)
  limitMargin: null, // rad plans keep from each joint's hard limit by default (GET /api/robots)
  curves: new Map(), // run id -> {episodes, mean, std, min, max, count}
  shown: new Set(), // run ids plotted
  shownTouched: false, // the user changed which runs are plotted
  notes: new Map(), // run id -> {tags, notes} (GET /api/run-notes; compare.js)
  runFilter: "", // the run table's filter: words of a name, tag:…, task:… (runfilter.js)
  drawnRuns: 0, // run-list redraws; announced after each one (set: runs.js; compare.js follows)
  curveDirty: true, // the chart redraws with the next live frame (chart.js)
  curveRenders: 0, // chart redraws with new data (chart.js; the benchmarks count them)
  watchedRun: null, // the run or policy last watched, {type, id} (set: policies.js; watch.js follows)
  rollout: null, // the watched rollout's playback as the scene last answered (watch.js)
  takes: { started: null, finished: null, takes: [] }, // GET /api/takes: the take session (takes.js)
  takePhase: "idle", // where the take flow is: idle, countdown, recording, review, kept (takes.js)
  timeline: null, // the recording timeline: its data, chart and playhead (timeline.js)
  timelineShown: [], // the timeline's series labels as drawn (timeline.js)
  camera: null, // the camera loop: running, frame rate, the studio's last answer (camera.js)
  landmarks: null, // the camera's last frame sent and the studio's answer (set: camera.js)
  softwareScene: false, // WebGL is drawn in software here: the scene gets a lower resolution
});

const listeners = new Map(); // field -> [fn(value)]

/** Write a declared field and announce it to the field's listeners, in the order they listened. */
export function set(field, value) {
  if (!Object.hasOwn(S, field)) throw new Error(`state.js declares no field "${field}"`);
  S[field] = value;
  for (const fn of listeners.get(field) || []) fn(value);
}

/** Call ``fn(value)`` after every `set` of a declared field. */
export function listen(field, fn) {
  if (!Object.hasOwn(S, field)) throw new Error(`state.js declares no field "${field}"`);
  if (!listeners.has(field)) listeners.set(field, []);
  listeners.get(field).push(fn);
}

/** The chart redraws with the next live frame (events.js, renderLive). */
export function markCurvesDirty() { S.curveDirty = true; }
