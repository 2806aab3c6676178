/* Teach Studio page: the run list (with `studio sweep`'s groups), and each run's curve as the live stream grows it. */

import { api, download, guarded } from "./api.js";
import { runColor, runLabel } from "./chart.js";
import { CURVE_KEYS, TIME_KEYS, emptyCurve } from "./curves.js";

const TIME_KEY_SET = new Set(Object.values(TIME_KEYS));
import { $, confirmDialog, el, emptyRow, enc, fmtCpu, showError } from "./dom.js";
import { renderPolicies, renderWatchChoices } from "./policies.js";
import { runMatches, tagChips } from "./runfilter.js";
import { S, markCurvesDirty, set } from "./state.js";

export function upsertRun(run) {
  const i = S.runs.findIndex((r) => r.id === run.id);
  if (i >= 0) S.runs[i] = run;
  else S.runs.unshift(run);
}

export async function loadRuns() {
  await guarded("runs-error", async () => {
    const notes = api("GET", "/api/run-notes").catch(() => null); // tags and notes (compare.js)
    const was = new Map(S.runs.map((r) => [r.id, r.status]));
    S.runs = await api("GET", "/api/runs");
    // A run that finished since we last saw it: its curve as saved. A short run can go from queued
    // to done between two ticks of the event stream and send no event of its own, and a stream
    // that reconnected missed the events it would have sent.
    const stale = (r) => !["running", "queued"].includes(r.status) && (was.get(r.id) !== r.status || !S.curves.get(r.id)?.episodes.length);
    const finished = new Set(S.runs.filter((r) => S.curves.has(r.id) && stale(r)).map((r) => r.id));
    const all = await notes;
    if (all) S.notes = new Map(Object.entries(all));
    S.sweeps = S.runs.some(sweepOf) ? await api("GET", "/api/sweeps") : [];
    if (!S.shownTouched) {
      // By default plot the newest few runs, so a fresh page shows the latest comparison.
      S.shown = new Set(S.runs.filter((r) => !r.damaged).slice(0, 4).map((r) => r.id));
    }
    renderRuns();
    await Promise.all([...S.shown].filter((id) => !S.curves.has(id) || finished.has(id)).map(loadCurve));
    renderWatchChoices();
    renderPolicies(); // a run's policy is listed under the run's name
  });
}

export async function loadCurve(id) {
  try {
    const c = await api("GET", `/api/runs/${enc(id)}/curve`);
    S.curves.set(id, Object.fromEntries(CURVE_KEYS.map((k) => [k, c[k] || []])));
    markCurvesDirty();
  } catch (e) {
    showError("runs-error", e);
  }
}

export function renderRuns() {
  const body = $("runs-body");
  if (!S.runs.length) {
    body.replaceChildren(emptyRow(6, "No runs yet: fill in the form and press Start."));
    return;
  }
  const rows = [];
  const grouped = new Set();
  const kept = S.runs.filter((r) => runMatches(r));
  if (kept.length < S.runs.length) {
    rows.push(el("tr", { class: "empty", testid: "runs-filtered" }, el("td", { colspan: 6,
      text: `${kept.length} of ${S.runs.length} runs match the filter “${S.runFilter}” (Compare runs)` })));
  }
  for (const r of kept) { // a sweep's trials show as one group row, at its newest trial's place
    const sweep = sweepOf(r);
    if (!sweep) rows.push(runRow(r));
    else if (!grouped.has(sweep)) { grouped.add(sweep); rows.push(...sweepRows(sweep)); }
  }
  reconcileRows(body, rows);
  set("drawnRuns", S.drawnRuns + 1); // the run table follows, when it is open
  const failed = S.runs.find((r) => r.status === "failed" && r.error && !r._errorShown);
  if (failed) { failed._errorShown = true; showError("runs-error", `${failed.name || failed.id}: ${failed.error}`); }
}

/** Put ``rows`` into ``body``, keeping every row that is drawn the same already: a running run
 * refreshes its row a few times a second, and rebuilding the whole list each time would lay out
 * and repaint all of it. Rows are equal when their HTML is (their handlers depend on the id alone),
 * or, for rows with fields a person edits (whose HTML the browser changes), their ``drawn`` HTML
 * as built. */
export function reconcileRows(body, rows) {
  const old = [...body.children];
  const html = (row) => row.drawn || row.outerHTML;
  rows.forEach((row, i) => {
    if (i >= old.length) body.append(row);
    else if (html(old[i]) !== html(row)) old[i].replaceWith(row);
  });
  for (const extra of old.slice(rows.length)) extra.remove();
}

/** A run folder the studio cannot read: the reason, and a way to delete it. */
function damagedRunRow(r) {
  return el("tr", { "data-id": r.id, testid: "run-row", "data-status": "damaged", title: r.error || "" },
    el("td", {}),
    el("td", { class: "name" }, r.id, " ", el("span", { class: "muted", testid: "run-damage", text: r.error || "" })),
    el("td", {}, el("span", { class: "badge failed", testid: "run-status", text: "damaged" })),
    el("td", {}),
    el("td", {}),
    el("td", { class: "actions" },
      el("button", { class: "icon", title: "delete this damaged run folder", testid: "run-delete", onclick: () => deleteRun(r.id) }, "✕")),
  );
}

function runRow(r) {
  if (r.damaged) return damagedRunRow(r);
  const total = r.episodes_total || (r.config && r.config.episodes) || 1;
  const pct = Math.min(100, (100 * (r.episodes_done || 0)) / total);
  const live = r.status === "running" || r.status === "queued";
  const c = r.config || {};
  const title = `planning ${c.planning} n=${c.planning_steps} ε=${c.epsilon} α=${c.alpha} γ=${c.gamma}\n` +
    `${c.episodes} episodes × ${c.experiments} experiments, ${c.bins} bins, goal ${(c.goal_deg || []).join(", ")}°, seed ${c.seed}` +
    `${(c.demonstrations || []).length ? `\ndemonstrations: ${c.demonstrations.join(", ")}` : ""}` +
    `${r.error ? `\n${r.error}` : ""}`;
  return el("tr", { "data-id": r.id, testid: "run-row", "data-status": r.status, title },
    el("td", {}, el("input", {
      type: "checkbox", testid: "run-show", checked: S.shown.has(r.id),
      onchange: (e) => toggleShown(r.id, e.target.checked),
    })),
    el("td", { class: "name", title: runLabel(r) }, el("span", { class: "swatch", style: `background:${runColor(r.id)}` }), runLabel(r), tagChips(r)),
    el("td", {}, el("span", { class: `badge ${r.status}`, testid: "run-status", text: r.note ? "preparing" : r.status })),
    r.note // before its first episode: what the run does (compiling the learner, the first time)
      ? el("td", { class: "run-note", testid: "run-note", text: r.note })
      : el("td", { title: `${r.episodes_done} / ${total} episodes` },
        el("span", { class: "progress", testid: "run-progress", "data-done": r.episodes_done },
          el("span", { style: `width:${pct.toFixed(1)}%` }))),
    el("td", { class: "num", testid: "run-cpu", text: fmtCpu(r.cpu_seconds) }),
    el("td", { class: "actions" },
      live && !r.elsewhere ? el("button", { class: "icon", title: "stop", testid: "run-stop", onclick: () => stopRun(r.id) }, "■") : null,
      live && r.elsewhere ? el("button", { class: "icon", title: "another process trains it: stop it there; mark it stopped only if that process is gone", testid: "run-mark-stopped", onclick: () => markRunStopped(r.id) }, "⊘") : null,
      !live ? el("button", { class: "icon", title: "delete", testid: "run-delete", onclick: () => deleteRun(r.id) }, "✕") : null,
    ),
  );
}

/* ------------------------------------------------------------------ sweeps (`studio sweep`) */
// A sweep's trials are ordinary runs (origin "sweep", group = the sweep's id): the list shows them
// as one group row. Ticking it plots all of them; ▸ unfolds the summary figure, its table (the
// columns that matter; sweep.csv has them all), downloads, and the trials' own rows.
const SWEEP_TABLE_COLUMNS = ["trial", "seed", "status", "episodes_done", "cpu_seconds", "wall_seconds"];

function sweepOf(r) {
  return r.origin === "sweep" && r.group ? r.group : null;
}

function toggleSweep(id, on) {
  for (const r of S.runs) if (sweepOf(r) === id) toggleShown(r.id, on);
  renderRuns();
}

function foldSweep(id) {
  if (S.openSweeps.has(id)) S.openSweeps.delete(id);
  else S.openSweeps.add(id);
  renderRuns();
}

function sweepRows(id) {
  const runs = S.runs.filter((r) => sweepOf(r) === id && runMatches(r));
  const info = S.sweeps.find((s) => s.id === id);
  const open = S.openSweeps.has(id);
  const trials = info ? info.trials : runs.length;
  const finished = info ? info.finished : runs.filter((r) => r.status === "done").length;
  const status = info ? info.status : runs.some((r) => r.status === "running") ? "running" : "done";
  const cpu = runs.reduce((sum, r) => sum + (r.cpu_seconds || 0), 0);
  const about = info ? ` · ${info.swept.join(" × ")} · ${info.metric}` : "";
  const head = el("tr", { class: "sweep", "data-id": id, testid: "sweep-row", "data-status": status,
    title: `sweep ${id}: ${finished} of ${trials} trials finished; tick to plot every trial` },
    el("td", {}, el("input", {
      type: "checkbox", testid: "sweep-show", checked: runs.length > 0 && runs.every((r) => S.shown.has(r.id)),
      onchange: (e) => toggleSweep(id, e.target.checked),
    })),
    el("td", { class: "name", title: `sweep ${id}${about} (${runs.length} runs)` },
      el("button", { class: "icon", testid: "sweep-open", title: open ? "fold" : "unfold: summary, figure and trials",
        onclick: () => foldSweep(id) }, open ? "▾" : "▸"),
      `sweep ${id}${about} (${runs.length} runs)`),
    el("td", {}, el("span", { class: `badge ${status === "interrupted" ? "stopped" : status}`, testid: "sweep-status", text: status })),
    el("td", { title: `${finished} / ${trials} trials` },
      el("span", { class: "progress", testid: "sweep-progress", "data-done": finished },
        el("span", { style: `width:${(100 * finished / Math.max(trials, 1)).toFixed(1)}%` }))),
    el("td", { class: "num", text: fmtCpu(cpu) }),
    el("td", {}),
  );
  return open ? [head, sweepDetail(id, info), ...runs.map(runRow)] : [head];
}

function sweepDetail(id, info) {
  const base = `/api/sweeps/${enc(id)}`;
  const get = (path, name) => download(`${base}/${path}`, `${id}-${name}`, "runs-error");
  let table = el("div", { class: "muted", text: "No summary yet." });
  if (info && info.rows.length) {
    const cols = info.columns.filter((c) => SWEEP_TABLE_COLUMNS.includes(c) || info.swept.includes(c) || c === info.metric);
    table = el("table", { class: "list", testid: "sweep-table" },
      el("thead", {}, el("tr", {}, ...cols.map((c) => el("th", { text: c })))),
      el("tbody", {}, ...info.rows.map((row) => el("tr", {}, ...cols.map((c) => el("td", { text: row[c] }))))));
  }
  const version = info ? `${info.status}-${info.finished}` : "0";
  return el("tr", { class: "sweep-detail", "data-id": id, testid: "sweep-detail" }, el("td", { colspan: 6 },
    el("img", { src: `${base}/figure.png?v=${enc(version)}`, testid: "sweep-figure", style: "max-width:100%",
      alt: info ? `${info.metric} against ${info.swept[0]}, mean and standard error over seeds` : "sweep figure" }),
    el("div", { class: "row" },
      el("button", { type: "button", testid: "sweep-csv", onclick: () => get("sweep.csv", "sweep.csv") }, "sweep.csv"),
      el("button", { type: "button", testid: "sweep-png", onclick: () => get("figure.png", "sweep.png") }, "Figure PNG"),
      el("button", { type: "button", testid: "sweep-svg", onclick: () => get("figure.svg", "sweep.svg") }, "Figure SVG")),
    el("div", { style: "overflow-x:auto" }, table)));
}

export function toggleShown(id, on) {
  S.shownTouched = true;
  if (on) {
    S.shown.add(id);
    if (!S.curves.has(id)) loadCurve(id);
  } else {
    S.shown.delete(id);
  }
  markCurvesDirty();
}

async function stopRun(id) {
  await guarded("runs-error", async () => {
    upsertRun(await api("POST", `/api/runs/${enc(id)}/stop`));
    renderRuns();
  });
}

async function markRunStopped(id) {
  const r = S.runs.find((x) => x.id === id);
  if (!(await confirmDialog(`Mark the run ${(r && r.name) || id} stopped? Do so only if no process trains it any more (a crash, a reboot, another machine); its curve so far is kept.`, "Mark stopped"))) return;
  await guarded("runs-error", async () => {
    upsertRun(await api("POST", `/api/runs/${enc(id)}/mark-stopped`));
    renderRuns();
  });
}

async function deleteRun(id) {
  const r = S.runs.find((x) => x.id === id);
  const what = r && r.damaged ? `the damaged run folder ${id}` : `the run ${(r && r.name) || id} with its curves and policy`;
  if (!(await confirmDialog(`Delete ${what}?`))) return;
  await guarded("runs-error", async () => {
    await api("DELETE", `/api/runs/${enc(id)}`);
    S.shown.delete(id);
    S.curves.delete(id);
    await loadRuns();
    markCurvesDirty();
  });
}

/** Merge an SSE curve piece into the run's curve: replace everything from its first episode on. */
export function mergeCurve(id, piece, from, to) {
  if (!piece || !piece.episodes) return;
  let c = S.curves.get(id);
  if (!c) { c = emptyCurve(); S.curves.set(id, c); }
  if (to !== undefined && to !== null) { // episodes [from, to) changed: replace just those
    for (let e = c.episodes.length; e < from; e++) { // episodes nobody finished yet: empty
      for (const k of CURVE_KEYS) c[k].push(k === "episodes" ? e + 1 : TIME_KEY_SET.has(k) ? null : 0);
    }
    for (const k of CURVE_KEYS) c[k].splice(from, to - from, ...(piece[k] || []));
    markCurvesDirty();
    return;
  }
  // `from` is the 0-based index of the piece's first episode (episode numbers are 1-based).
  const first = from !== undefined && from !== null ? from + 1 : piece.episodes[0];
  // Episodes are numbered; drop what we already hold from `first` on, then append.
  let cut = c.episodes.length;
  if (first !== undefined) {
    cut = c.episodes.findIndex((e) => e >= first);
    if (cut < 0) cut = c.episodes.length;
  }
  for (const k of CURVE_KEYS) {
    c[k] = (c[k] || []).slice(0, cut).concat(piece[k] || []);
  }
  markCurvesDirty();
}
