"""Sweep throughput and Ray's overhead per trial: Ray Tune on a local Ray against a serial loop.

``python benchmarks/bench_sweep.py`` (about 3 to 4 minutes on 2 cores) runs the same sweep of
trials of about a second each (the paper's grid, 20 experiments x 100 episodes of full or soft
planning with 1000 updates per step) three ways: a plain loop training the trials one after
another in this process, ``run_sweep`` on a local Ray with ONE worker, and with 2 workers. Both
sides do identical work per trial: the same trials (``trial_record``), written as the same
ordinary runs (``RunFolder.train`` with one thread per trial); the kernels are warmed up first,
and a throwaway sweep of tiny trials takes the driver's one-time costs (first imports).

A sweep's wall time is a fixed cost per sweep plus a cost per trial. Each side runs two sweep sizes
(``--sizes``, default 4 and 16 trials); the line through the two walls gives

- the **per-trial time** (the slope: wall difference / trial difference), what a bigger sweep
  adds per trial, and
- the **fixed cost per sweep** (the intercept): Tune's set-up, starting the worker processes
  (Python, Ray, Tune, this package, loading the kernels) and writing the summary. ``ray.init`` is
  timed apart: ``studio sweep`` starts a local Ray once per sweep, a cluster pays it once.

Every Ray sweep gets its own ``ray.init``, as ``studio sweep`` does: the first sweep of a Ray
session finds worker processes Ray started in advance, later ones start their own, so sweeps
sharing one session would not share one fixed cost and the slope would be off.

Figures (goals from issue 12):

1. **Overhead per trial**: Ray's slope with ONE worker minus the serial loop's slope, relative to
   the serial time per trial (goal: < 10 % for trials of >= 1 s). With one worker nothing runs
   in parallel, so the difference is what Ray adds per trial: scheduling, re-using the worker,
   the reports, the driver's bookkeeping.
2. **Throughput**: serial slope / Ray's 2-worker slope, i.e. trials per minute of a big sweep
   (goal: >= 1.7x). Also printed honestly: the whole-sweep ratio of each size run, counting the
   fixed cost and ``ray.init``, and the sweep size from which the whole sweep reaches 1.7x.
3. ``--six-joint``: the cost of one six-joint trial (6 joints x 5 bins, the largest grid), and from
   it and the measured per-trial and fixed costs, a paper estimate for a 1,000-trial six-joint
   sweep on a 16-node cluster.

This VM's speed drifts by up to 1.5x within minutes, so the sides run interleaved (their order
and the order of the sizes alternate between repeats), each repeat's figures are computed from
that repeat's runs only, and the medians over ``--repeats`` are reported with their range.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from studio.learning import warm_up
from studio.learning.runs._folder import RunFolder
from studio.learning.sweeps._ray import _connect, _import_ray, run_sweep
from studio.learning.sweeps._spec import parse_sweep_spec, trial_record

SIZES = (4, 16)
REPEATS = 2
WORKERS = 2
PLANNING_STEPS = 1000
THROUGHPUT_GOAL = 1.7
OVERHEAD_GOAL = 0.10
CLUSTER_NODES = 16
CLUSTER_CORES = (8, 16)
CLUSTER_TRIALS = 1000
SIDES = ("serial", "ray1", f"ray{WORKERS}")
LABELS = {
    "serial": "serial loop",
    "ray1": "Ray, 1 worker",
    f"ray{WORKERS}": f"Ray, {WORKERS} workers",
}

SIX_JOINT = {
    "name": "six",
    "task": "arm-grid",
    "seeds": [0],
    "experiments": 1,
    "episodes": 20,
    "fixed": {"joints": 6, "bins": 5, "planning_steps": 20},
    "space": {"planning": ["full"]},
}


def sweep_spec(trials: int, planning_steps: int) -> dict:
    """``trials`` trials (even): full and soft planning, each over ``trials / 2`` seeds."""
    return {
        "name": "bench",
        "task": "arm-grid",
        "seeds": list(range(trials // 2)),
        "experiments": 20,
        "episodes": 100,
        "fixed": {"planning_steps": planning_steps},
        "space": {"planning": ["full", "soft"]},
    }


@dataclass
class Sweep:
    """One timed sweep: its wall time, ``ray.init``'s (0 for the serial loop), and each trial's
    time in the trial function (in the worker for Ray)."""

    wall: float
    init: float
    in_trial: list[float]


def serial(spec_data: dict, out: Path) -> Sweep:
    """Train every trial in this process, one after another, through the same run folders."""
    spec = parse_sweep_spec(spec_data)
    per_trial = []
    start = time.perf_counter()
    for trial in spec.trials():
        t0 = time.perf_counter()
        run = RunFolder.create(out, trial_record(spec, trial), name=trial.key, status="running")
        run.train(workers=spec.cpus_per_trial)
        per_trial.append(time.perf_counter() - t0)
    return Sweep(time.perf_counter() - start, 0.0, per_trial)


def on_ray(spec_data: dict, data: Path, workers: int) -> Sweep:
    """Start a local Ray as ``studio sweep`` does (timed apart), run the sweep, stop Ray."""
    ray = _import_ray()
    t0 = time.perf_counter()
    _connect(ray, None, workers)
    init = time.perf_counter() - t0
    try:
        t0 = time.perf_counter()
        result = run_sweep(parse_sweep_spec(spec_data), data)
        wall = time.perf_counter() - t0
    finally:
        ray.shutdown()
    if result.failed or result.interrupted:
        raise RuntimeError(f"the benchmark sweep did not complete: {result}")
    return Sweep(wall, init, [float(row["wall_seconds"]) for row in result.rows])


def line(points: dict[int, float]) -> tuple[float, float]:
    """Least-squares slope and intercept of wall against trials (exact for two sizes)."""
    xs, ys = list(points), list(points.values())
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True)) / sum(
        (x - mx) ** 2 for x in xs
    )
    return slope, my - slope * mx


def median_range(values: list[float], show: Callable[[float], str]) -> str:
    """``median [min..max]`` of the repeats' values."""
    if len(values) == 1:
        return show(values[0])
    return f"{show(statistics.median(values))} [{show(min(values))}..{show(max(values))}]"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--six-joint", action="store_true", help="also estimate a cluster sweep")
    parser.add_argument(
        "--sizes",
        type=int,
        nargs="+",
        default=list(SIZES),
        help="sweep sizes in trials (even numbers, at least two sizes)",
    )
    parser.add_argument(
        "--repeats", type=int, default=REPEATS, help="interleaved rounds; medians are reported"
    )
    parser.add_argument(
        "--planning-steps",
        type=int,
        default=PLANNING_STEPS,
        help="planning updates per step: scales each trial's length (1000: about a second)",
    )
    args = parser.parse_args()
    sizes = sorted(set(args.sizes))
    if len(sizes) < 2 or any(n < 2 or n % 2 for n in sizes) or args.repeats < 1:
        parser.error("give at least two different even sweep sizes and at least one repeat")
    t0 = time.perf_counter()
    _import_ray()  # the driver's import of Ray Tune: once per process
    tune_import = time.perf_counter() - t0
    warm_up()
    print(
        f"cores: {os.cpu_count()}, load average {os.getloadavg()[0]:.1f}; sweeps of "
        f"{' and '.join(map(str, sizes))} trials (20 experiments x 100 episodes, planning "
        f"{args.planning_steps}), {args.repeats} interleaved repeats"
    )
    runners: dict[str, Callable[[dict, Path], Sweep]] = {
        "serial": serial,
        "ray1": lambda spec, out: on_ray(spec, out, 1),
        f"ray{WORKERS}": lambda spec, out: on_ray(spec, out, WORKERS),
    }
    runs: list[dict[str, dict[int, Sweep]]] = []  # per repeat, per side, per size
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        # A throwaway sweep of tiny trials first: what the driver process does once (imports of
        # Tune's and matplotlib's modules on first use) must fall on no measured sweep.
        on_ray(sweep_spec(2, 1), root / "warm-up", WORKERS)
        for r in range(args.repeats):
            runs.append({})
            order = SIDES if r % 2 == 0 else SIDES[::-1]
            for s, side in enumerate(order):
                by_size = runs[-1].setdefault(side, {})
                for n in sizes if (r + s) % 2 == 0 else sizes[::-1]:
                    spec = sweep_spec(n, args.planning_steps)
                    by_size[n] = runners[side](spec, root / f"{side}-{n}-{r}")
                walls = ", ".join(f"{n} trials {by_size[n].wall:6.2f} s" for n in sizes)
                init = f" (+ ray.init {statistics.fmean(x.init for x in by_size.values()):.2f} s)"
                print(
                    f"  repeat {r + 1}: {LABELS[side]:16s} {walls}"
                    f"{init if side != 'serial' else ''}  load {os.getloadavg()[0]:.1f}"
                )
        six_wall = serial(SIX_JOINT, root / "six").wall if args.six_joint else math.nan

    fits = [
        {side: line({n: x.wall for n, x in rep[side].items()}) for side in SIDES} for rep in runs
    ]
    slopes = {side: [f[side][0] for f in fits] for side in SIDES}
    fixed = {side: [f[side][1] for f in fits] for side in SIDES}
    inits = [x.init for rep in runs for side in SIDES[1:] for x in rep[side].values()]
    init = statistics.median(inits)
    many = f"ray{WORKERS}"

    def secs(v: float) -> str:
        return f"{v:.2f} s"

    def pct(v: float) -> str:
        return f"{v:.1%}"

    def times(v: float) -> str:
        return f"{v:.2f}x"

    print("per sweep = fixed cost + trials x per-trial time (medians [range] over the repeats):")
    for side in SIDES:
        slope = statistics.median(slopes[side])
        print(
            f"  {LABELS[side]:16s} per trial {median_range(slopes[side], secs)} "
            f"({60 / slope:5.1f} trials/min), fixed per sweep {median_range(fixed[side], secs)}"
        )
    print(
        f"  Ray start-up: ray.init {median_range(inits, secs)} per local Ray, and the driver's "
        f"first import of Ray Tune {tune_import:.2f} s once per process"
    )
    overheads = [(f["ray1"][0] - f["serial"][0]) / f["serial"][0] for f in fits]
    serial_slope, one_slope = statistics.median(slopes["serial"]), statistics.median(slopes["ray1"])
    print(
        f"overhead per trial: {median_range(overheads, pct)} of a {serial_slope:.2f} s trial "
        f"(Ray 1 worker {one_slope:.3f} s - serial {serial_slope:.3f} s per trial; "
        f"goal < {OVERHEAD_GOAL:.0%})"
    )
    ratios = [f["serial"][0] / f[many][0] for f in fits]
    print(
        f"throughput per trial: {median_range(ratios, times)} the serial loop with {WORKERS} "
        f"workers (goal >= {THROUGHPUT_GOAL}x)"
    )
    whole = {
        n: [rep["serial"][n].wall / rep[many][n].wall for rep in runs] for n in sizes
    }  # fixed cost included
    whole_init = {
        n: [rep["serial"][n].wall / (rep[many][n].wall + rep[many][n].init) for rep in runs]
        for n in sizes
    }
    for n in sizes:
        print(
            f"whole sweep of {n:3d} trials: {median_range(whole[n], times)} with Ray running, "
            f"{median_range(whole_init[n], times)} counting ray.init"
        )
    s_slope, s_fixed = serial_slope, statistics.median(fixed["serial"])
    m_slope, m_fixed = statistics.median(slopes[many]), statistics.median(fixed[many])
    gain = s_slope - THROUGHPUT_GOAL * m_slope
    if gain <= 0:
        print(f"whole sweep never reaches {THROUGHPUT_GOAL}x: the per-trial ratio is below it")
    else:
        for what, cost in (("with Ray running", m_fixed), ("counting ray.init", m_fixed + init)):
            n = max(1, math.ceil((THROUGHPUT_GOAL * cost - s_fixed) / gain))
            print(
                f"whole sweep reaches {THROUGHPUT_GOAL}x from {n} trials of {s_slope:.2f} s "
                f"({what}; from the fitted lines)"
            )
    in_trial = {
        side: statistics.median(t for rep in runs for x in rep[side].values() for t in x.in_trial)
        for side in SIDES
    }
    print(
        "time in the trial function per trial: "
        + ", ".join(f"{LABELS[side]} {in_trial[side]:.2f} s" for side in SIDES)
    )
    if args.six_joint:
        # A node whose every core runs a trial takes WORKERS x the 2-worker slope per trial per
        # core: the serial cost times this factor (Ray's overhead and the cores' contention).
        factor = WORKERS * m_slope / s_slope
        episodes = SIX_JOINT["episodes"]
        print(
            f"six-joint trial (6 joints x 5 bins, 1 experiment x {episodes} episodes, full "
            f"planning 20): {six_wall:.2f} s alone; {six_wall * factor:.2f} s per core with every "
            f"core busy under Ray (x{factor:.2f}, measured above)"
        )
        for cores in CLUSTER_CORES:
            slots = CLUSTER_NODES * cores
            waves = math.ceil(CLUSTER_TRIALS / slots)
            minutes = (waves * six_wall * factor + m_fixed + init) / 60
            print(
                f"paper estimate: {CLUSTER_TRIALS} such trials on {CLUSTER_NODES} nodes x {cores} "
                f"cores = {slots} slots, {waves} waves: {minutes:.1f} min with the fixed cost "
                f"(one core: {CLUSTER_TRIALS * six_wall / 3600:.1f} h)"
            )


if __name__ == "__main__":
    main()
