/* Teach Studio page: the page's one state, `window.studio` (the browser tests and the console read it). */

export const S = {
  config: null,
  source: null,
  capture: null,
  recordings: [],
  demos: [],
  runs: [],
  sweeps: [], // `studio sweep` summaries (GET /api/sweeps); their trials are runs of a group
  openSweeps: new Set(), // sweep ids unfolded in the run list (table, figure, runs)
  policies: [],
  robots: null, // the offered robots with their joints and default goals (GET /api/robots)
  robot: null, // the robot taught, as the page last announced it (`studio:robot`, sources.js)
  curves: new Map(), // run id -> {episodes, mean, std, min, max, count}
  shown: new Set(), // run ids plotted
  shownTouched: false, // the user changed which runs are plotted
  notes: new Map(), // run id -> {tags, notes} (GET /api/run-notes; compare.js)
  runFilter: "", // the run table's filter: words of a name, tag:…, task:… (runfilter.js)
  marking: false,
  watchedRun: null,
  curveDirty: true,
  softwareScene: false, // WebGL is drawn in software here: the scene gets a lower resolution
};
window.studio = S; // for the browser tests and for poking around in the console

/** The chart redraws with the next live frame (events.js, renderLive). */
export function markCurvesDirty() { S.curveDirty = true; }
