/* Teach Studio page: exporting a recording, a demonstration or a policy's rollout as a robot's
 * trajectory. One control for the three lists: what to export, a format, an Export button.
 *
 * The Export button exports what the person means: a recording at its capture times where they
 * keep the robot's limits, else at the person's pace, slowed only where the robot needs it
 * (`fit`); the page then says so in words, with the physics report the file states. A refusal
 * by the safety checks (the robot truly cannot make the motion) is said in words right above
 * "Export anyway, findings written in the file", its findings listed below the buttons, so the
 * sentence and the buttons that act on it stay in view together.
 *
 * Recordings and demonstrations export for the robot chosen above (GET
 * /api/robot/export/{recording|demonstration}/{name}: retargeted, timed, checked and replayed in
 * physics as `studio export --robot` does, the report in the file; its X-Studio-Export header
 * says what it did), and "Check in physics" shows, before exporting, the report the file
 * will state (GET /api/robot/simulate/{recording|demonstration}/{name}); a rollout, the one last
 * watched of the policy chosen under Watch, for the robot it was learnt on (CSV as ever from
 * /api/watch/trajectory.csv, MCAP from /api/robot/export/rollout.mcap).
 */

import { api, download, guarded } from "./api.js";
import { $, el, enc, fillSelect, setProp, showError } from "./dom.js";
import { watchTarget } from "./policies.js";
import { S, listen } from "./state.js";

const ALL_FORMATS = [["csv", "CSV"], ["mcap", "MCAP (ROS 2)"], ["lerobot", "LeRobot dataset (zip)"]];
const ENDINGS = { csv: "csv", mcap: "mcap", lerobot: "lerobot.zip" };
const ANYWAY = "Export anyway, findings written in the file";
const MARGIN = "how far (rad) the robot keeps every joint from its hard limit: the retargeting, the timing and the safety checks all keep it (empty: the default)";
const PHYSICS = "replay the motion the export would write in physics (MuJoCo: the robot's motors and their force limits, gravity, the table) and say whether it completes, how closely the robot follows it, where a motor saturates and what touches";
const HOW = "retargeted onto the robot chosen under Source, at your pace, slowed only where the robot needs it, checked for safety and replayed in physics";

const KINDS = {
  recording: {
    noun: "recording", formats: ALL_FORMATS,
    title: "the recording as the robot's joint trajectory, retargeted onto the robot chosen under Source: at its capture times where they keep the robot's limits, else at your pace, slowed only where the robot needs it; checked for safety and replayed in physics",
    items: () => S.recordings.filter((r) => !r.error && !r.capturing).map((r) => [r.name, r.name]),
  },
  demonstration: {
    noun: "demonstration", formats: ALL_FORMATS, title: `the demonstration as the robot's joint trajectory, ${HOW}`,
    items: () => S.demos.filter((d) => !d.error).map((d) => [d.name, d.name]),
  },
  rollout: {
    noun: "rollout", formats: ALL_FORMATS.slice(0, 2), testid: "download-rollout",
    title: "the rollout last watched of the policy chosen above, for the robot it was learnt on: CSV time,q1..q6, or MCAP (ROS 2 JointTrajectory) checked for safety and replayed in physics",
  },
};

/** Build the export control of ``kind`` (recording, demonstration, rollout) into its box. */
export function buildExportControl(kind) {
  const k = KINDS[kind];
  const noun = k.noun[0].toUpperCase() + k.noun.slice(1);
  const parts = [];
  if (k.items) {
    parts.push(el("select", { id: `${kind}-export-item`, testid: `${kind}-export-item`, class: "grow", "aria-label": `${noun} to export` }));
  }
  parts.push(el("select", { id: `${kind}-export-format`, testid: `${kind}-export-format`, class: "export-format", "aria-label": `${noun} export format` },
    ...k.formats.map(([value, label]) => el("option", { value, text: label }))));
  parts.push(el("button", { id: `${kind}-export-go`, testid: k.testid || `${kind}-export-go`, class: "primary", title: k.title, onclick: () => exportNow(kind, { unchecked: false }) }, `Export ${k.noun}`));
  if (k.items) {
    parts.push(el("input", { id: `${kind}-export-margin`, testid: `${kind}-export-margin`, type: "number", min: "0", step: "0.01", class: "export-margin", "aria-label": "Margin from each joint's limit (rad)", placeholder: marginHint(), title: MARGIN }));
    parts.push(el("button", { id: `${kind}-physics-go`, testid: `${kind}-physics-go`, title: PHYSICS, onclick: () => checkPhysics(kind) }, "Check in physics"));
    parts.push(el("button", { id: `${kind}-physics-play`, testid: `${kind}-physics-play`, title: "play in the scene the motion the robot makes in physics (MuJoCo) for what Export writes: its motors, their force limits and gravity, not the plan", onclick: () => playSimulated(kind) }, "Play simulated"));
  }
  const anyway = el("button", { id: `${kind}-export-anyway`, testid: `${kind}-export-anyway`, hidden: true, title: "write the file even though the safety checks refuse it; every finding is stated in it", onclick: () => exportNow(kind, { unchecked: true }) }, ANYWAY);
  // the sentence, then the buttons that act on it, then the details: both stay in view
  $(`${kind}-export`).replaceChildren(
    el("div", { class: "row wrap" }, ...parts),
    el("div", { class: "err", id: `${kind}-export-error`, testid: `${kind}-export-error`, role: "alert", hidden: true }),
    el("div", { class: "hint", id: `${kind}-export-done`, testid: `${kind}-export-done`, role: "status", hidden: true }),
    el("div", { class: "row", id: `${kind}-export-fixes` }, anyway),
    el("ul", { class: "findings", id: `${kind}-export-findings`, testid: `${kind}-export-findings`, hidden: true }),
    el("div", { class: "hint", id: `${kind}-physics`, testid: `${kind}-physics`, role: "status", hidden: true }),
  );
  fillExportItems(kind);
}

/** Offer the list's current items (kept chosen across refreshes). */
export function fillExportItems(kind) {
  const k = KINDS[kind];
  const select = $(`${kind}-export-item`);
  if (!k.items || !select) return;
  const items = k.items();
  fillSelect(select, items.length ? items : [["", `(no ${k.noun} yet)`]]);
}

/** The margin field's hint: the default margin, once GET /api/robots said it. */
function marginHint() {
  return S.limitMargin == null ? "margin, rad" : `margin ${S.limitMargin} rad`;
}

listen("robot", () => {
  for (const kind of ["recording", "demonstration"]) {
    const field = $(`${kind}-export-margin`);
    if (field) field.placeholder = marginHint();
  }
});

/** The export's limit margin, when the field gives one (the default otherwise). */
function margin(kind, query) {
  const field = $(`${kind}-export-margin`);
  if (field && field.value !== "") query.set("limit_margin", field.value);
}

function target(kind, { unchecked }) {
  const k = KINDS[kind];
  const format = $(`${kind}-export-format`).value;
  const query = new URLSearchParams();
  if (kind === "rollout") {
    const t = watchTarget();
    if (!t) return { error: "Choose a run or a policy under Watch first, watch it, then export its rollout." };
    query.set(t.type === "run" ? "run" : "policy", t.id);
    if (format === "csv") return { url: `/api/watch/trajectory.csv?${query}`, name: `${t.id}.rollout.csv` };
    if (unchecked) query.set("unchecked", "true");
    query.set("fit", "true");
    return { url: `/api/robot/export/rollout.mcap?${query}`, name: `${t.id}.rollout.mcap` };
  }
  const name = $(`${kind}-export-item`).value;
  if (!name) return { error: `Choose a ${k.noun} to export first.` };
  query.set("format", format);
  if (unchecked) query.set("unchecked", "true");
  query.set("fit", "true"); // at the person's pace where its own times break the limits
  margin(kind, query);
  const robot = (S.source && S.source.robot) || "robot";
  return { url: `/api/robot/export/${kind}/${enc(name)}?${query}`, name: `${name}.${robot}.${ENDINGS[format]}` };
}

/** Show what a finished export did, or the findings of a refusal, beside the buttons. */
function showVerdict(kind, { said, findings, more }) {
  const done = $(`${kind}-export-done`);
  const list = $(`${kind}-export-findings`);
  if (said) done.replaceChildren(...said.map((line, i) => el("div", { text: line, class: i ? "muted" : undefined })));
  setProp(done, "hidden", !said);
  list.replaceChildren(...(findings || []).map((f) => el("li", { text: f.sentence })));
  if (more) list.append(el("li", { class: "muted", text: more }));
  setProp(list, "hidden", !(findings && findings.length));
}

/** The export's account of itself (its X-Studio-Export header), or null. */
function aboutOf(resp) {
  try { return JSON.parse(resp.headers.get("X-Studio-Export") || "null"); } catch (e) { return null; }
}

async function exportNow(kind, how) {
  const errId = `${kind}-export-error`;
  const anyway = $(`${kind}-export-anyway`);
  setProp(anyway, "hidden", true);
  showVerdict(kind, {});
  const t = target(kind, how);
  if (t.error) { showError(errId, t.error); return; }
  const button = $(`${kind}-export-go`);
  button.disabled = true;
  anyway.disabled = true;
  try {
    let about = null;
    const answer = await download(t.url, t.name, errId, (resp) => { about = aboutOf(resp); });
    if (about) {
      showVerdict(kind, {
        said: [about.said, ...about.slowdowns, ...about.physics],
        findings: about.findings,
      });
      $(`${kind}-export-done`).scrollIntoView({ block: "nearest" });
    }
    // refused by the safety checks, the robot truly cannot make it: the findings, and the
    // offer to write it with the findings in it, right under the sentence
    if (answer && answer.reason === "safety") {
      setProp(anyway, "hidden", false);
      showVerdict(kind, { findings: answer.findings || [] });
      $(`${kind}-export-fixes`).scrollIntoView({ block: "nearest" });
    }
  } finally {
    button.disabled = false;
    anyway.disabled = false;
  }
}

/** Replay the chosen item as its export would write it, in physics, and show the report. */
async function checkPhysics(kind) {
  const errId = `${kind}-export-error`;
  const box = $(`${kind}-physics`);
  const name = $(`${kind}-export-item`).value;
  setProp(box, "hidden", true);
  if (!name) { showError(errId, `Choose a ${KINDS[kind].noun} to check first.`); return; }
  const query = new URLSearchParams({ fit: "true" }); // the samples the Export button writes
  margin(kind, query);
  const report = await guarded(errId, () => api("GET", `/api/robot/simulate/${kind}/${enc(name)}?${query}`), $(`${kind}-physics-go`));
  if (!report) return;
  box.replaceChildren(...report.sentences.map((line) => el("div", { text: line })));
  setProp(box, "hidden", false);
}

/** Play in the scene the motion the robot makes in physics for what Export writes. */
async function playSimulated(kind) {
  const errId = `${kind}-export-error`;
  const box = $(`${kind}-physics`);
  const name = $(`${kind}-export-item`).value;
  if (!name) { showError(errId, `Choose a ${KINDS[kind].noun} to play first.`); return; }
  const query = new URLSearchParams();
  margin(kind, query);
  const done = await guarded(errId, async () => {
    await api("POST", `/api/robot/simulate/${kind}/${enc(name)}/play?${query}`);
    return true;
  }, $(`${kind}-physics-play`));
  if (!done) return;
  box.replaceChildren(el("div", { text: `The robot in the scene plays the motion it makes in physics for ${name}, once simulated (the notes under Robot say meanwhile).` }));
  setProp(box, "hidden", false);
}
