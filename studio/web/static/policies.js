/* Teach Studio page: policies: the list, watching one in the scene, uploads, and the export buttons. */

import { api, download, guarded, uploadChosen } from "./api.js";
import { runLabel } from "./chart.js";
import { $, confirmDialog, el, emptyRow, enc, fillSelect, flashRow, fmt, setText, showError } from "./dom.js";
import { S, set } from "./state.js";

export async function loadPolicies() {
  await guarded("policies-error", async () => {
    S.policies = await api("GET", "/api/policies");
    renderPolicies();
    renderWatchChoices();
  });
}

// One name per policy: a run's policy goes by its run's label (as in the runs list), an
// uploaded one by its file name.
function policyLabel(p) {
  const run = p.source === "run" && p.run ? S.runs.find((r) => r.id === p.run) : null;
  return run ? runLabel(run) : p.name;
}

function policyKey(p) {
  return p.source === "run" && p.run ? `run:${p.run}` : `policy:${p.name}`;
}

// What a policy acts on, from its listing's task: the paper's grid or the continuous joints.
function policyTask(p) {
  const t = p.task || {};
  if (t.kind === "arm-grid") return `grid ${t.joints}×${t.bins}`;
  if (t.kind === "arm-reach") return `continuous ${t.joints} joints`;
  if (t.kind === "dmp") return `movement primitive, ${p.joints} joints`;
  return t.kind || "";
}

export function renderPolicies() {
  const body = $("policies-body");
  if (!S.policies.length) {
    body.replaceChildren(emptyRow(4, "No policies: finish a run, or upload a .policy.npz."));
    return;
  }
  body.replaceChildren(...S.policies.map((p) => {
    const label = policyLabel(p);
    const what = p.error
      ? el("span", { class: "badge failed", text: "unreadable", title: p.error, testid: "policy-damaged" })
      : el("span", { title: policyTask(p), text: `${p.planning} · ${policyTask(p)}` });
    return el("tr", { "data-name": p.name, "data-key": policyKey(p), testid: "policy-row", title: p.error || "" },
      el("td", { class: "name", title: [label, p.run && `run ${p.run}`, p.notes].filter(Boolean).join("\n"), text: label }),
      el("td", { testid: "policy-task" }, what),
      el("td", { class: "muted", title: p.run || "", text: p.source === "run" ? "run" : "upload" }),
      el("td", { class: "actions" },
        p.error ? null : el("button", { class: "icon", title: "watch", testid: "policy-watch", onclick: () => { selectWatch(p); watch(); } }, "▶"),
        p.source === "upload" ? el("button", { class: "icon", title: "delete", testid: "policy-delete", onclick: () => deletePolicy(p.name) }, "✕") : null,
      ),
    );
  }));
}

function selectWatch(p) {
  $("watch-policy").value = policyKey(p);
}

export function renderWatchChoices() {
  const items = [];
  const seenRuns = new Set();
  for (const r of S.runs) {
    if (r.has_policy) { items.push([`run:${r.id}`, `run ${runLabel(r)}`]); seenRuns.add(r.id); }
  }
  for (const p of S.policies) {
    if ((p.source === "run" && p.run && seenRuns.has(p.run)) || p.error) continue;
    items.push([policyKey(p), `${p.source === "upload" ? "file" : "run"} ${policyLabel(p)}`]);
  }
  if (!items.length) items.push(["", "(no policy yet)"]);
  fillSelect($("watch-policy"), items);
}

export function watchTarget() {
  const v = $("watch-policy").value;
  if (!v) return null;
  const i = v.indexOf(":");
  return { type: v.slice(0, i), id: v.slice(i + 1) };
}

export async function watch() {
  const t = watchTarget();
  if (!t) { showError("watch-error", "There is no policy to watch yet: train a run to the end, or upload a policy file."); return; }
  const body = { start: $("watch-start").value };
  if (t.type === "run") body.run = t.id; else body.policy = t.id;
  if ($("watch-seed").value !== "") body.seed = Number($("watch-seed").value);
  if ($("watch-demo").value) body.demonstration = $("watch-demo").value;
  setText("watch-result", "");
  await guarded("watch-error", async () => {
    const w = await api("POST", "/api/watch", body);
    const secs = w.times && w.times.length ? w.times[w.times.length - 1] : 0;
    // a movement primitive has no random start: it starts where its demonstration did
    const from = w.seed != null ? `from a random start (seed ${w.seed})` : body.start === "current" ? "from the current pose" : "from its demonstration's start";
    setText("watch-result", `${w.steps} steps, ${secs.toFixed(1)} s ${from} — ${w.reached_goal ? "reaches the goal" : "does not reach the goal"}`);
    renderLikeness(w.likeness, w.likeness_note);
    set("watchedRun", t); // watch.js: the scrubber
  }, $("watch-go"));
}

/** The demonstrations the likeness card can compare with (the policy's own by default). */
export function renderWatchDemos() {
  const usable = S.demos.filter((d) => !d.error).map((d) => [d.name, d.name]);
  fillSelect($("watch-demo"), [["", "its own demonstration"], ...usable]);
}

/** The likeness card: each figure for the policy and, beside it, for the demonstration. */
function renderLikeness(card, note) {
  const box = $("watch-likeness");
  box.hidden = false;
  if (!card) {
    box.replaceChildren(el("div", { class: "muted", testid: "likeness-note", text: note || "No likeness card." }));
    return;
  }
  const p = card.policy, d = card.demonstration;
  const pct = (x) => (x == null ? "–" : `${fmt(100 * x, 0)}`);
  const shares = (m) => m.joint_shares.map(pct).join("/");
  const rows = [
    ["DTW, joints (rad/sample)", fmt(card.dtw_rad, 4), `0 (travel ${fmt(d.joint_travel_rad, 2)} rad)`, "mean joint distance along the best time alignment"],
    ["Fréchet, tool (m)", fmt(card.frechet_m, 4), `0 (path ${fmt(d.tool_path_m, 3)} m)`, "shortest leash joining the two tool paths"],
    ["smoothness LDLJ", fmt(p.ldlj, 2), fmt(d.ldlj, 2), "log dimensionless jerk of the tool's path, low-passed first: higher is smoother"],
    ["smoothness SPARC", fmt(p.sparc, 2), fmt(d.sparc, 2), "spectral arc length of the tool's speed: nearer 0 is smoother; a constant pace with abrupt starts scores low"],
    ["joint shares (%)", shares(p), shares(d), "each joint's share of the total joint travel"],
    ["  JS divergence (bits)", fmt(card.shares_js, 3), "0", "0 = the same spread over the joints, 1 = disjoint"],
    ["joints together (%)", pct(p.together), pct(d.together), "share of the moving time with two or more joints moving"],
    ["duration (s)", fmt(p.duration_s, 2), fmt(d.duration_s, 2), "a continuous policy taught from recorded demonstrations moves at their pace: their moving time (stillness before and after left out) over the steps the task takes along them"],
  ];
  box.replaceChildren(
    el("div", { class: "muted small", text: `Likeness to ${card.name}, rolled out from its start` }),
    el("table", { class: "list" },
      el("thead", {}, el("tr", {}, el("th", { text: "" }), el("th", { class: "num", text: "policy" }), el("th", { class: "num", text: "demonstration" }))),
      el("tbody", {}, ...rows.map(([what, mine, theirs, help]) => el("tr", { testid: "likeness-row", title: help },
        el("td", { text: what }), el("td", { class: "num", testid: "likeness-policy", text: mine }), el("td", { class: "num", testid: "likeness-demo", text: theirs }))))));
}

async function deletePolicy(name) {
  if (!(await confirmDialog(`Delete the uploaded policy ${name}?`))) return;
  await guarded("policies-error", async () => {
    await api("DELETE", `/api/policies/${enc(name)}`);
    await loadPolicies();
  });
}

export async function uploadPolicy(input) {
  await uploadChosen(input, "/api/policies", "policies-error", showNewPolicy);
}

/** A policy just made (uploaded, or fitted to a demonstration): listed, chosen to watch, flashed. */
export async function showNewPolicy(p) {
  await loadPolicies();
  if (p) { selectWatch(p); flashRow("policies-body", p.name); }
}

export function exportFile(kind) {
  const t = watchTarget();
  if (!t) { showError("export-error", "Choose a run or a policy first."); return; }
  if (kind === "policy") {
    if (t.type === "run") return download(`/api/runs/${enc(t.id)}/policy`, `${t.id}.policy.npz`, "export-error");
    return download(`/api/policies/${enc(t.id)}/file`, `${t.id}.policy.npz`, "export-error");
  }
  if (t.type !== "run") { showError("export-error", "Curves and plots belong to a training run; choose a run, not an uploaded file."); return; }
  const path = { curve: "curve.csv", png: "plot.png", svg: "plot.svg" }[kind];
  const query = kind === "curve" ? "" : `?log=${$("curve-log").checked}`;
  return download(`/api/runs/${enc(t.id)}/${path}${query}`, `${t.id}-${path}`, "export-error");
}
