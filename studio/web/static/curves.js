/* Teach Studio page: a run's learning curve, and the one rule that averages a long curve for the
 * chart. No DOM and no state: tests/e2e/test_curve_rule.py runs this rule against the server's.
 *
 * The rule is the server's (`studio.learning.downsample_curve`, which draws the PNG/SVG figures):
 * a curve of n episodes is averaged in equal buckets of ceil(n / points) episodes, each point at
 * its bucket's mean episode, with the mean of its means and of its stds, its lowest min, highest
 * max and fewest count (a point never claims more experiments than all of its episodes had). The
 * chart's "episode" axis is that rule, with the same buckets for every run; its "log" and
 * "fraction" axes bucket the same way over other edges.
 */

export const CURVE_KEYS = ["episodes", "mean", "std", "min", "max", "count", "wall_seconds", "cpu_seconds"];

/** A curve's measured time per episode, by x axis (``studio.learning``'s TIME_COLUMNS): the mean
 * over the experiments that finished the episode of each one's own seconds up to its end. */
export const TIME_KEYS = { wall: "wall_seconds", cpu: "cpu_seconds" };

/** The curve's measured seconds for a time axis, or null when its run saved none (a run from
 * before they were measured): that axis is then an estimate. */
export function measuredSeconds(curve, xMode) {
  const t = curve[TIME_KEYS[xMode]];
  return t && t.length === curve.episodes.length && t.some((v) => v !== null) ? t : null;
}

export function emptyCurve() {
  return Object.fromEntries(CURVE_KEYS.map((k) => [k, []]));
}

/**
 * At most MAX_PLOT_POINTS points per run (the server's FIGURE_POINTS), so a 100 000-episode run
 * draws as fast as a short one and the chart never slows the page down.
 */
const MAX_PLOT_POINTS = 600;

/**
 * Bucket edges of the x axis shared by some lines (``{curve, length}``, length: the episodes per
 * experiment a fraction-of-run axis divides by): ``x[b]`` is bucket b's x value and
 * ``bucketOf(line, episode)`` its bucket. "episode": equal buckets of episodes, each at its mean
 * episode (the server's rule); "log": log-spaced buckets at their upper edges, so a 100-episode
 * run keeps its shape beside a 50 000-episode one; "fraction": each line over [0, 1] of its length.
 */
export function curveAxis(lines, xMode, points = MAX_PLOT_POINTS) {
  if (xMode === "fraction") {
    const longest = Math.max(...lines.map((line) => line.length));
    const n = Math.min(points, longest);
    const x = Array.from({ length: n }, (_, b) => (b + 1) / n);
    return { x, bucketOf: (line, e) => Math.min(n - 1, Math.floor(((e - 1) / line.length) * n)) };
  }
  let last = 0;
  for (const line of lines) {
    const e = line.curve.episodes;
    last = Math.max(last, e[e.length - 1]);
  }
  if (xMode === "log" && last > points) {
    // upper edges geometric from 1 to last (duplicates merged), so early episodes stay single
    const edges = [];
    for (let b = 1; b <= points; b++) {
      const edge = Math.ceil(Math.exp((Math.log(last) * b) / points));
      if (!edges.length || edge > edges[edges.length - 1]) edges.push(edge);
    }
    edges[edges.length - 1] = last;
    const bucketOf = (line, e) => {
      let lo = 0; let hi = edges.length - 1;
      while (lo < hi) { const mid = (lo + hi) >> 1; if (edges[mid] >= e) hi = mid; else lo = mid + 1; }
      return lo;
    };
    return { x: edges, bucketOf };
  }
  const k = Math.max(1, Math.ceil(last / points));
  const n = Math.ceil(last / k);
  const x = Array.from({ length: n }, (_, b) => (b * k + 1 + Math.min(last, (b + 1) * k)) / 2);
  return { x, bucketOf: (line, e) => Math.floor((e - 1) / k) };
}

/**
 * One line's curve averaged into the axis's ``n`` buckets: per bucket the mean of its means and
 * of its stds, its lowest min, highest max and fewest count (null where a bucket holds no
 * episode, or the curve has no counts); ``most``: the most experiments any episode averages.
 */
export function bucketCurve(line, n, bucketOf) {
  const c = line.curve;
  const sum = new Float64Array(n); const sd = new Float64Array(n); const cnt = new Uint32Array(n);
  const lo = new Float64Array(n).fill(Infinity); const hi = new Float64Array(n).fill(-Infinity);
  const count = new Array(n).fill(null);
  let most = 0;
  for (let i = 0; i < c.episodes.length; i++) {
    const b = bucketOf(line, c.episodes[i]);
    sum[b] += c.mean[i]; sd[b] += c.std[i] || 0; cnt[b] += 1;
    lo[b] = Math.min(lo[b], c.min[i]); hi[b] = Math.max(hi[b], c.max[i]);
    const k = c.count && c.count[i] !== undefined ? c.count[i] : null;
    if (k !== null) { count[b] = count[b] === null ? k : Math.min(count[b], k); most = Math.max(most, k); }
  }
  const out = { mean: [], std: [], min: [], max: [], count, most };
  for (let b = 0; b < n; b++) {
    const some = cnt[b] > 0;
    out.mean.push(some ? sum[b] / cnt[b] : null);
    out.std.push(some ? sd[b] / cnt[b] : null);
    out.min.push(some ? lo[b] : null);
    out.max.push(some ? hi[b] : null);
  }
  return out;
}

/**
 * TensorBoard's smoothing: an exponential moving average of the non-null values in x order,
 * debiased so the first points are not pulled towards zero; ``weight`` in [0, 1), 0 leaves the
 * values as they are. Nulls (gaps) stay null and do not reset the average.
 */
export function smoothed(values, weight) {
  const out = new Array(values.length).fill(null);
  let last = 0; let n = 0;
  for (let i = 0; i < values.length; i++) {
    const v = values[i];
    if (v === null || v === undefined || !Number.isFinite(v)) continue;
    last = last * weight + (1 - weight) * v; n += 1;
    out[i] = weight > 0 ? last / (1 - weight ** n) : v;
  }
  return out;
}

/** The x axes that run on with each run's own work rather than its episode number. */
export const RUNNING_AXES = new Set(["steps", "wall", "cpu"]);

/**
 * Each episode's x on a running axis. "steps": the real steps taken up to and including it (the
 * sum of the mean steps per episode: the mean over experiments of each one's own total while
 * all of them count). "wall" and "cpu": the seconds an experiment had spent by the episode's end,
 * as measured while the run trained (``measuredSeconds``; null where not stamped yet). A run saved
 * without them gets ``seconds`` (an experiment's wall or CPU time so far) shared out in proportion
 * to its steps: a Dyna-Q step costs about the same all run long (one update and n planning
 * updates), so that is an estimate, which the axis labels with "≈".
 */
export function runningX(curve, xMode, seconds = 0) {
  const measured = TIME_KEYS[xMode] ? measuredSeconds(curve, xMode) : null;
  if (measured) return measured.map((v) => (v === undefined ? null : v));
  const x = new Array(curve.episodes.length);
  let sum = 0;
  for (let i = 0; i < x.length; i++) { sum += curve.mean[i] > 0 ? curve.mean[i] : 0; x[i] = sum; }
  if (xMode === "steps") return x;
  const scale = sum > 0 && seconds > 0 ? seconds / sum : 0;
  return x.map((v) => v * scale);
}

/**
 * Lines bucketed by episode each on its own (the server's rule), then placed on one running
 * axis (``runningX``, each bucket at the mean x of its episodes), rows merged where runs share an
 * x: ``{x, stats}`` with each line's ``bucketCurve`` statistics aligned to ``x`` (null elsewhere).
 */
export function runningAxis(lines, xMode, seconds, points = MAX_PLOT_POINTS) {
  const parts = lines.map((line, i) => {
    const { x: ex, bucketOf } = curveAxis([line], "episode", points);
    const s = bucketCurve(line, ex.length, bucketOf);
    const px = runningX(line.curve, xMode, seconds[i]);
    const sum = new Float64Array(ex.length); const cnt = new Uint32Array(ex.length);
    line.curve.episodes.forEach((e, k) => {
      if (px[k] === null) return; // a time not stamped yet
      const b = bucketOf(line, e); sum[b] += px[k]; cnt[b] += 1;
    });
    return { s, bx: Array.from(sum, (v, b) => (cnt[b] ? v / cnt[b] : null)) };
  });
  const rows = [];
  parts.forEach((p, i) => p.bx.forEach((v, b) => { if (v !== null && p.s.mean[b] !== null) rows.push([v, i, b]); }));
  rows.sort((a, b) => a[0] - b[0]);
  const keys = ["mean", "std", "min", "max", "count"];
  const stats = parts.map((p) => ({ most: p.s.most, ...Object.fromEntries(keys.map((k) => [k, []])) }));
  const x = [];
  for (const [v, i, b] of rows) {
    // a row per x shared by runs; a run's own episodes at one x (ended within the same
    // millisecond) keep a row each, so none is lost
    if (!x.length || x[x.length - 1] !== v || stats[i].mean[x.length - 1] !== null) {
      x.push(v); for (const st of stats) for (const k of keys) st[k].push(null);
    }
    for (const k of keys) stats[i][k][x.length - 1] = parts[i].s[k][b];
  }
  return { x, stats };
}
