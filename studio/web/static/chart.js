/* Teach Studio page: the learning-curve chart, and each run's colour and label as the lists show them.
 *
 * uPlot (vendored from npm, see static/vendor/README.md) draws on a canvas: a redraw with new data
 * takes about a millisecond, so live curves at CURVE_FPS never compete with training for the CPU.
 */

import { RUNNING_AXES, TIME_KEYS, bucketCurve, curveAxis, measuredSeconds, runningAxis, smoothed } from "./curves.js";
import { $, setProp, setText } from "./dom.js";
import { S } from "./state.js";

const PALETTE = ["#2a62b8", "#d9822b", "#23874b", "#b83280", "#6b4fbb", "#0f8b8d", "#a0522d", "#7a7a7a"];

export function runColor(id) {
  const i = S.runs.length - 1 - S.runs.findIndex((r) => r.id === id);
  return PALETTE[((i % PALETTE.length) + PALETTE.length) % PALETTE.length];
}

/** What a run learns, in words: the paper's grid (tabular) or continuous joints (tile coding).
 * A run made before the continuous task existed has no task in its config: it is a grid run. */
export function runTask(r) {
  const c = r.config || {};
  return c.task === "arm-reach" ? `continuous, ${c.joints} joints` : "grid";
}

function nameAndTask(r) {
  const c = r.config || {};
  const name = r.name || r.id;
  const demos = (c.demonstrations || []).length;
  const planning = c.planning && !name.includes(c.planning) ? ` · ${c.planning}` : "";
  return `${name} · ${runTask(r)}${planning}${demos && !/demo/.test(name) ? ` +${demos} demo` : ""}`;
}

function madeAt(r) {
  const made = new Date(r.created);
  return Number.isNaN(made.getTime()) ? r.id : made.toLocaleTimeString([], { hour12: false });
}

// Run id -> its label, for the runs whose names alone read the same; rebuilt when the list changes.
let twins = { runs: null, length: -1, labels: new Map() };

function twinLabels() {
  if (twins.runs === S.runs && twins.length === S.runs.length) return twins.labels;
  const groups = new Map();
  for (const r of S.runs) {
    const label = nameAndTask(r);
    if (!groups.has(label)) groups.set(label, []);
    groups.get(label).push(r);
  }
  const labels = new Map();
  for (const [label, runs] of groups) {
    if (runs.length < 2) continue;
    const oldestFirst = [...runs].reverse();
    const times = oldestFirst.map(madeAt);
    oldestFirst.forEach((r, i) => {
      const clash = times.filter((t) => t === times[i]).length > 1; // made in the same second
      labels.set(r.id, `${label} · ${times[i]}${clash ? ` #${i + 1}` : ""}`);
    });
  }
  twins = { runs: S.runs, length: S.runs.length, labels };
  return labels;
}

/** A run's name as the legend, the run list and the Compare table show it: its name (its
 * settings when unnamed) and task; runs that would read the same (the same settings run twice,
 * unnamed) each add the time they were made, and their order when made in the same second. */
export function runLabel(r) {
  return twinLabels().get(r.id) || nameAndTask(r);
}

/** The runs to plot, oldest first (so colours and legend order stay put as runs are added). */
export function plottedRuns() {
  return [...S.runs].reverse().filter((r) => {
    const c = S.curves.get(r.id);
    return S.shown.has(r.id) && c && c.episodes.length > 0;
  });
}

/** An experiment's seconds so far on a time axis, for a run saved without times per episode:
 * its CPU time over its experiments, or its wall time from start to finish (to now while it
 * trains) over the experiments each thread ran in turn (one thread per core); 0 before it starts. */
export function runSeconds(r, xMode) {
  const experiments = Math.max(1, (r.config && r.config.experiments) || 1);
  if (xMode === "cpu") return (r.cpu_seconds || 0) / experiments;
  if (xMode !== "wall" || !r.started) return 0;
  const end = r.finished ? Date.parse(r.finished) : Date.now();
  const threads = Math.min(experiments, navigator.hardwareConcurrency || 1);
  return (Math.max(0, (end - Date.parse(r.started)) / 1000) * threads) / experiments;
}

/** Whether a time axis is an estimate for some of these runs (saved without times per episode). */
export function estimatedTime(runs, xMode) {
  return Boolean(TIME_KEYS[xMode]) && runs.some((r) => !measuredSeconds(S.curves.get(r.id), xMode));
}

/** Episodes per experiment of a run (its fraction-of-run axis divides by this). */
function runLength(r) {
  const c = S.curves.get(r.id);
  const planned = r.config && r.config.episodes;
  return Math.max(1, planned || (c.episodes.length ? c.episodes[c.episodes.length - 1] : 1));
}

/**
 * The chart's columns: the x axis, then per run its mean and, with a band, its low and high
 * edges. Missing episodes are null (a gap); on a log axis nothing below one step is drawn. Also
 * per run the fewest experiments any point of a bucket averages (``counts``) and the run's most
 * (``full``), so the legend and a marker say where the band stops averaging every experiment.
 * With ``smoothing`` (an EMA weight, see ``smoothed``) each run also gets its smoothed mean, last.
 * On a running axis (real steps, wall or CPU time) each run keeps its own buckets: null elsewhere.
 */
export function chartData(runs, band, log, xMode = "episode", smoothing = 0) {
  const lines = runs.map((r) => ({ curve: S.curves.get(r.id), length: runLength(r) }));
  let x; let stats;
  if (RUNNING_AXES.has(xMode)) {
    ({ x, stats } = runningAxis(lines, xMode, runs.map((r) => runSeconds(r, xMode))));
  } else {
    const axis = curveAxis(lines, xMode);
    x = axis.x;
    stats = lines.map((line) => bucketCurve(line, x.length, axis.bucketOf));
  }
  const n = x.length;
  const cols = [x];
  const counts = [];
  const full = [];
  const floor = (v) => (log && v < 1 ? null : v);
  runs.forEach((r, i) => {
    const s = stats[i];
    const mean = new Array(n).fill(null); const low = new Array(n).fill(null); const high = new Array(n).fill(null);
    for (let b = 0; b < n; b++) {
      if (s.mean[b] === null) continue;
      const m = s.mean[b];
      mean[b] = floor(m);
      if (band === "minmax") {
        low[b] = floor(s.min[b]); high[b] = floor(s.max[b]);
      } else {
        low[b] = floor(Math.max(m - s.std[b], log ? Math.max(s.min[b], 1) : 0)); high[b] = floor(m + s.std[b]);
      }
    }
    cols.push(mean);
    if (band !== "none") cols.push(low, high);
    if (smoothing > 0) cols.push(smoothed(mean, smoothing));
    counts.push(s.count);
    full.push(s.most || (r.config && r.config.experiments) || 0);
  });
  cols.counts = counts;
  cols.full = full;
  return cols;
}

/** Where each run's points stop averaging all its experiments: the first such x, or null. */
export function fewerFrom(data, i) {
  const counts = data.counts[i];
  for (let b = 0; b < counts.length; b++) {
    if (counts[b] !== null && counts[b] < data.full[i]) return data[0][b];
  }
  return null;
}

function hexAlpha(hex, a) {
  const n = parseInt(hex.slice(1), 16);
  return `rgba(${(n >> 16) & 255},${(n >> 8) & 255},${n & 255},${a})`;
}

const X_LABELS = {
  episode: "episode", log: "episode", fraction: "fraction of run", steps: "real steps",
  wall: "wall time per experiment", cpu: "CPU time per experiment",
};

/** The x axis's label; a time axis on which some run's time is estimated says so with "≈". */
export function xLabelOf(runs, xMode) {
  if (estimatedTime(runs, xMode)) return `${xMode === "cpu" ? "CPU" : "wall"} time ≈ per experiment (older runs: their time shared out by steps)`;
  return X_LABELS[xMode] || "episode";
}

/** The last value of a column (the legend shows it while the cursor is off the chart). */
function lastValue(col) {
  for (let k = col.length - 1; k >= 0; k--) if (col[k] != null) return col[k];
  return null;
}

/** A time axis's tick: seconds, or milliseconds below one second (a short run's ticks would
 * otherwise all round to 0). */
function fmtSeconds(v) {
  if (v == null) return "";
  return Math.abs(v) < 1 && v !== 0 ? `${+(v * 1000).toPrecision(3)} ms` : `${+v.toPrecision(4)} s`;
}

function fmtX(xMode, v) {
  if (v == null) return ""; // off the chart: the runs' values are their last ones
  if (xMode === "fraction") return v.toFixed(3);
  if (xMode === "wall" || xMode === "cpu") return fmtSeconds(v);
  return xMode === "steps" ? String(Math.round(v)) : String(v);
}

/** uPlot options for these runs: a mean line per run and, with a band, two unlabelled edges filled;
 * with smoothing, the mean is drawn faint and the smoothed line over it carries the run's name;
 * a dashed marker where a run's points start averaging fewer experiments than it has. The legend
 * names every run all the time, with its last value until the cursor points at an x. */
function chartOptions(runs, band, log, width, height, xMode = "episode", smoothing = 0) {
  const xLabel = xLabelOf(runs, xMode);
  const gaps = RUNNING_AXES.has(xMode); // runs have their own x: join their points across others' rows
  const series = [{ label: xLabel.split(" (")[0], value: (u, v) => fmtX(xMode, v) }];
  const bands = [];
  const valueOf = (i, what) => (u, v, si, di) => {
    if (di == null) v = lastValue(u.data[si]);
    if (v == null) return "–";
    const n = di == null || !u.data.counts ? null : u.data.counts[i][di];
    const of = u.data.full ? u.data.full[i] : null;
    return `${di == null ? "last " : ""}${v.toFixed(1)} steps${what}${n != null && of ? ` · ${n} of ${of} exp.` : ""}`;
  };
  runs.forEach((r, i) => {
    const color = runColor(r.id);
    const meanIdx = series.length;
    series.push(smoothing > 0
      ? { label: `${runLabel(r)} raw`, class: "band-edge", stroke: hexAlpha(color, 0.3), width: 1, spanGaps: gaps, points: { show: false } }
      : { label: runLabel(r), stroke: color, width: 1, spanGaps: gaps, value: valueOf(i, "") });
    if (band !== "none") {
      for (const edge of ["low", "high"]) {
        series.push({ label: `${runLabel(r)} ${edge}`, class: "band-edge", stroke: "transparent", width: 0, spanGaps: gaps, points: { show: false } });
      }
      bands.push({ series: [meanIdx + 2, meanIdx + 1], fill: hexAlpha(color, smoothing > 0 ? 0.1 : 0.16) });
    }
    if (smoothing > 0) series.push({ label: runLabel(r), stroke: color, width: 1, spanGaps: gaps, value: valueOf(i, " smoothed") });
  });
  const axis = { stroke: "#555", grid: { stroke: "#eceef1", width: 1 }, ticks: { stroke: "#d6d9de", width: 1 }, font: "11px system-ui, sans-serif", labelFont: "11px system-ui, sans-serif" };
  return {
    width, height, series, bands,
    scales: {
      x: xMode === "log" ? { time: false, distr: 3, log: 10 } : { time: false },
      y: log ? { distr: 3, log: 10 } : { range: (u, min, max) => [0, max > 0 ? max * 1.05 : 1] },
    },
    axes: [
      { ...axis, label: xLabel, labelSize: 16, size: 30, ...(TIME_KEYS[xMode] ? { values: (u, ticks) => ticks.map(fmtSeconds) } : {}) },
      { ...axis, label: "steps", labelSize: 16, size: 48 },
    ],
    legend: { live: true },
    cursor: { drag: { x: true, y: false } },
    hooks: {
      init: [(u) => {
        // Drag to zoom into episodes (the zoom then survives live updates); double-click resets.
        u.over.addEventListener("dblclick", () => { zoomed = false; });
      }],
      setSelect: [(u) => { if (u.select.width > 0) zoomed = true; }],
      draw: [(u) => {
        // Mark where each run's band stops averaging all of its experiments (runs of different
        // lengths, or a stopped run): the band goes on, over fewer experiments, as the legend says.
        const ctx = u.ctx;
        runs.forEach((r, i) => {
          const at = u.data.counts ? fewerFrom(u.data, i) : null;
          if (at === null) return;
          const px = Math.round(u.valToPos(at, "x", true));
          ctx.save();
          ctx.strokeStyle = runColor(r.id);
          ctx.setLineDash([4, 4]);
          ctx.lineWidth = 1;
          ctx.beginPath();
          ctx.moveTo(px, u.bbox.top);
          ctx.lineTo(px, u.bbox.top + u.bbox.height);
          ctx.stroke();
          ctx.restore();
        });
      }],
    },
  };
}

/** The chart's key: what the line, the band and the dashed marker mean (each run's name and
 * colour are in uPlot's own legend under the chart). Written only when it changes. */
function renderCurveKey(runs, data, band) {
  setProp("curve-key", "hidden", runs.length === 0);
  setProp("curve-key-band", "hidden", band === "none");
  setText("curve-key-band-text", band === "minmax" ? "min–max" : "± 1 std");
  setProp("curve-key-fewer", "hidden", !runs.some((r, i) => fewerFrom(data, i) !== null));
}

let chart = null;
let chartKey = "";
let chartRuns = []; // run ids of the chart's mean columns, in order
let chartSmooth = false; // each run has a smoothed mean column, its last
let chartStride = 1; // columns per run: mean, or mean, low and high; then the smoothed mean
let zoomed = false; // the user dragged to zoom: live updates keep the x range

/** Size the chart to its pane, leaving room for the legend under it. */
export function fitChart() {
  if (!chart) return;
  const box = $("curve-plot");
  const legend = chart.root.querySelector(".u-legend");
  const height = Math.max(80, box.clientHeight - (legend ? legend.offsetHeight : 0) - 2);
  chart.setSize({ width: box.clientWidth, height });
}

export function renderCurves() {
  if (!S.curveDirty || typeof uPlot === "undefined") return;
  S.curveDirty = false;
  const band = $("curve-band").value;
  const log = $("curve-log").checked;
  const xMode = $("curve-x").value;
  const smoothing = Number($("curve-smooth").value) || 0;
  const runs = plottedRuns();
  setProp("curve-empty", "hidden", runs.length > 0);
  if (!runs.length) {
    if (chart) { chart.destroy(); chart = null; chartKey = ""; chartRuns = []; }
    setProp("curve-key", "hidden", true);
    return;
  }
  const key = JSON.stringify([runs.map((r) => [r.id, runLabel(r), runColor(r.id)]), band, log, xMode, smoothing > 0, xLabelOf(runs, xMode)]);
  const data = chartData(runs, band, log, xMode, smoothing);
  renderCurveKey(runs, data, band);
  if (chart && key === chartKey) {
    chart.setData(data, !zoomed);
  } else {
    if (chart) chart.destroy();
    const box = $("curve-plot");
    chart = new uPlot(chartOptions(runs, band, log, box.clientWidth, box.clientHeight, xMode, smoothing), data, box);
    chartKey = key;
    chartRuns = runs.map((r) => r.id);
    chartSmooth = smoothing > 0;
    chartStride = (band === "none" ? 1 : 3) + (chartSmooth ? 1 : 0);
    zoomed = false;
    fitChart();
  }
  S.curveRenders += 1;
}

/** Ids of the runs in the chart, in legend order (used by the browser tests). */
export const drawnRuns = () => (chart ? [...chartRuns] : []);

/** The x where a plotted run starts averaging fewer experiments than it has, or null (tests). */
export const drawnFewerFrom = (id) => (chart && chartRuns.includes(id) ? fewerFrom(chart.data, chartRuns.indexOf(id)) : null);

/** Number of plotted mean-curve points of a run, or of all runs (used by the browser tests). */
export const drawnPoints = (id) => {
  if (!chart) return 0;
  let n = 0;
  chartRuns.forEach((run, i) => {
    if (id === undefined || run === id) n += chart.data[1 + i * chartStride].filter((v) => v !== null).length;
  });
  return n;
};

/** A plotted run's columns as drawn: x, its mean and its smoothed mean (null without smoothing). */
export const drawnLine = (id) => {
  const i = chart ? chartRuns.indexOf(id) : -1;
  if (i < 0) return null;
  const base = 1 + i * chartStride;
  return { x: [...chart.data[0]], mean: [...chart.data[base]], smooth: chartSmooth ? [...chart.data[base + chartStride - 1]] : null };
};
