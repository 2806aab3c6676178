/* Teach Studio page: the train form: the learning package's defaults, its problems by field, starting a run. */

import { ApiError, api } from "./api.js";
import { emptyCurve } from "./curves.js";
import { $, el, showError } from "./dom.js";
import { openCompare } from "./compare.js";
import { renderRuns, upsertRun } from "./runs.js";
import { S, listen, markCurvesDirty } from "./state.js";
import { placedObstacles, refreshObstacles } from "./obstacles.js";

/** Form inputs of a field the API names (the goal is three inputs). */
const TRAIN_INPUTS = { goal_deg: ["goal0", "goal1", "goal2"] };

/** Fill the train form with the learning package's defaults (served by /api/config). */
export function resetTrainForm() {
  showTrainErrors(null);
  const defaults = S.config && S.config.training;
  if (!defaults) return;
  const f = $("train-form");
  const planners = S.config.planners || [defaults.planning];
  f.elements.planning.replaceChildren(...planners.map((p) => el("option", { value: p, text: p })));
  for (const [k, v] of Object.entries(defaults)) {
    if (k === "goal_deg") fillGoal(robotGoal() || v);
    else if (f.elements[k] && !(f.elements[k] instanceof RadioNodeList)) f.elements[k].value = v == null ? "" : String(v);
  }
}

/** The default goal of the robot chosen under Source (joints 1-3, degrees, as GET /api/robots
 * serves it from the learning package): the goal `studio train --robot NAME` trains towards. */
function robotGoal() {
  const robot = (S.robots || []).find((r) => r.name === S.robot);
  return robot && robot.goal_deg && robot.goal_deg.length ? robot.goal_deg : null;
}

function fillGoal(goal) {
  const f = $("train-form");
  goal.forEach((g, i) => { f.elements[`goal${i}`].value = String(g); });
}

// Another robot chosen: the form's goal becomes that robot's default (the Puma560's would be
// another arm's pose, often beyond its limits), and the picked demonstrations are checked again.
// A goal taken from a pose by hand (watch.js) is checked at once, as Start would check it: a
// joint within the robot's limits may still fall in a grid bin whose centre lies beyond them.
listen("robot", () => {
  const goal = robotGoal();
  if (!goal) return;
  fillGoal(goal);
  checkTrainForm();
});

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
export function syncTaskFields() {
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
    obstacles: placedObstacles(),
  };
  if (empty.length) {
    const problems = empty.map((k) => `${k.replace("_", " ")} is empty; enter a number.`);
    const err = new ApiError(problems.join(" "));
    err.data = { problems, by_field: Object.fromEntries(empty.map((k, i) => [k, problems[i]])) };
    throw err;
  }
  if (body.task === "arm-reach") {
    // an empty tiles field leaves the robot's default (the API's null)
    for (const k of REACH_FIELDS) if (k !== "tiles" || f[k].value.trim() !== "") body[k] = num(k);
    body.actions = f.actions.value;
    if (f.learner.value) body.learner = f.learner.value; // a baseline; none: Dyna-Q
  }
  const robot = $("robot-name").value; // the robot chosen under Source, shown in the form
  if (robot) body.robot = robot;
  if (f.name.value.trim()) body.name = f.name.value.trim();
  return body;
}

/** Fields the form checks as they are filled in: the demonstrations picked against the goal. */
const LIVE_CHECKED = ["demonstrations", "goal_deg"];
let checkSeq = 0;
let checkShown = false; // whether the sentences beside the form are the live check's

/** Clear what the live check showed (never a refused Start's sentences). */
function clearCheck() {
  if (checkShown) showTrainErrors(null);
  checkShown = false;
}

/** Check the picked demonstrations against the form's goal and task now, before Start, with the
 * learning package's own resolver (/api/demonstrations/check); show its sentences by field.
 * ``always``: check the goal even with no demonstration picked (a goal taken from a pose). */
export async function checkTrainForm(always = false) {
  const seq = ++checkSeq;
  let body;
  try { body = readTrainForm(); } catch { return; } // an empty number: Start will say which
  if (!body.demonstrations.length && always !== true) { clearCheck(); return; }
  let data = {};
  try {
    await api("POST", "/api/demonstrations/check", body); // 204: it would start
  } catch (e) {
    if (!(e instanceof ApiError) || !e.data) return; // offline: Start will say
    data = e.data;
  }
  if (seq !== checkSeq) return; // a newer check is on its way
  const byField = Object.fromEntries(Object.entries(data.by_field || {}).filter(([k]) => LIVE_CHECKED.includes(k)));
  const problems = Object.values(byField);
  if (!problems.length) { clearCheck(); return; }
  const err = new ApiError(problems.join(" "));
  err.data = { problems, by_field: byField };
  showTrainErrors(err);
  checkShown = true;
}

export async function startRun(ev) {
  ev.preventDefault();
  checkSeq++; // a check still on its way must not redraw the form's sentences
  checkShown = false;
  showTrainErrors(null);
  const button = $("train-start");
  button.disabled = true;
  try {
    await refreshObstacles(); // where the boxes were dragged in the scene
    const body = readTrainForm();
    const pair = $("train-form").elements.baseline.checked;
    // with "also train without demonstrations": the run and its twin, plotted alone and compared
    const runs = pair ? await api("POST", "/api/runs/pair", body) : [await api("POST", "/api/runs", body)];
    // the user's choice of plotted runs: a runs list reloaded meanwhile keeps it (not the newest four)
    if (pair) { S.shown = new Set(); S.shownTouched = true; }
    for (const run of runs) {
      // the run's events may have come first (a short run can even be done): keep what they brought
      if (!S.runs.some((r) => r.id === run.id)) upsertRun(run);
      S.shown.add(run.id);
      if (!S.curves.has(run.id)) S.curves.set(run.id, emptyCurve());
    }
    renderRuns();
    markCurvesDirty();
    if (pair) openCompare();
  } catch (e) {
    showTrainErrors(e);
    if (!(e instanceof ApiError)) console.error(e);
  } finally {
    button.disabled = false;
  }
}
