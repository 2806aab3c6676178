"""Sweep throughput: Ray Tune on a local Ray (2 workers) against a plain serial loop.

Measures, in one run (``python benchmarks/bench_sweep.py``, about a minute on 2 cores):

1. trials per minute for a fixed sweep (``TRIALS`` trials of the paper's grid, 20 experiments x
   100 episodes of full or soft planning with 1000 updates per step: about a second each): ``run_sweep`` on a local Ray with 2 workers against a plain loop that
   trains the same trials one after another through the same run folders (goal: >= 1.7x). Ray's
   start-up (``ray.init``) is timed apart: it is paid once per sweep, not per trial.
2. Ray's overhead per trial over the trial's own compute: the same sweep on a local Ray with ONE
   worker against the serial loop, (Ray wall - serial wall) / trials, relative to the serial
   loop's time per trial (goal: < 10 % for trials of >= 1 s). With one worker nothing runs in
   parallel, so the difference is what Ray adds: scheduling, the worker, the reports and the
   bookkeeping. Also printed: per trial, Ray's time outside the trial function (2-worker sweep:
   2 x wall / trials - the mean time the trial function took). ``--planning-steps`` scales the
   trials' length (1000: about a second each; 5000: about five).
3. ``--six-joint``: the cost of one six-joint trial (6 joints x 5 bins, the largest grid), and
   from it a paper estimate for a 1,000-trial six-joint sweep on a 16-node cluster.

Both sides do identical work: the same trials (``trial_record``), written as the same ordinary runs
(``RunFolder.train`` with one thread per trial); the kernels are warmed up first on both sides.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from studio.learning import warm_up
from studio.learning._runs import RunFolder
from studio.learning._sweep import (
    RAY_ENVIRONMENT,
    parse_sweep_spec,
    run_sweep,
    trial_record,
)

TRIALS = 12
THROUGHPUT_GOAL = 1.7
OVERHEAD_GOAL = 0.10
WORKERS = 2
CLUSTER_NODES = 16
CLUSTER_TRIALS = 1000

SPEC = {
    "name": "bench",
    "task": "arm-grid",
    "seeds": list(range(TRIALS // 2)),
    "experiments": 20,
    "episodes": 100,
    "fixed": {"planning_steps": 1000},
    "space": {"planning": ["full", "soft"]},
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


def serial(spec_data: dict, out: Path) -> tuple[float, list[float]]:
    """Train every trial in this process, one after another; (wall, per-trial seconds)."""
    spec = parse_sweep_spec(spec_data)
    per_trial = []
    start = time.perf_counter()
    for trial in spec.trials():
        t0 = time.perf_counter()
        run = RunFolder.create(out, trial_record(spec, trial), name=trial.key, status="running")
        run.train(workers=spec.cpus_per_trial)
        per_trial.append(time.perf_counter() - t0)
    return time.perf_counter() - start, per_trial


def on_ray(spec_data: dict, data: Path, workers: int) -> tuple[float, float, list[float]]:
    """Run the sweep on a fresh local Ray; (ray.init seconds, sweep wall, per-trial seconds)."""
    import ray

    t0 = time.perf_counter()
    ray.init(address="local", num_cpus=workers, include_dashboard=False, log_to_driver=False)
    started = time.perf_counter() - t0
    try:
        t0 = time.perf_counter()
        result = run_sweep(parse_sweep_spec(spec_data), data)
        wall = time.perf_counter() - t0
    finally:
        ray.shutdown()
    assert not result.failed and not result.interrupted, result
    return started, wall, [float(row["wall_seconds"]) for row in result.rows]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--six-joint", action="store_true", help="also time a six-joint trial")
    parser.add_argument(
        "--planning-steps",
        type=int,
        default=SPEC["fixed"]["planning_steps"],
        help="planning updates per step: scales each trial's length (1000: about a second)",
    )
    parser.add_argument(
        "--repeats",
        type=int,
        default=1,
        help="run each side this often, interleaved; keep the best",
    )
    args = parser.parse_args()
    for key, value in RAY_ENVIRONMENT.items():
        os.environ.setdefault(key, value)
    warm_up()
    print(f"cores: {os.cpu_count()}, load average {os.getloadavg()[0]:.1f}; {TRIALS} trials")
    spec = {**SPEC, "fixed": {"planning_steps": args.planning_steps}}
    serial_walls, ray2, ray1 = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for i in range(args.repeats):  # interleaved, so a busy spell hurts every side alike
            serial_walls.append(serial(spec, root / f"serial{i}")[0])
            ray2.append(on_ray(spec, root / f"ray2-{i}", WORKERS))
            ray1.append(on_ray(spec, root / f"ray1-{i}", 1))
            print(
                f"  round {i + 1}: serial {serial_walls[-1]:.2f} s, Ray x{WORKERS} {ray2[-1][1]:.2f} s, "
                f"Ray x1 {ray1[-1][1]:.2f} s (load {os.getloadavg()[0]:.1f})"
            )
        serial_wall = min(serial_walls)
        init2, wall2, in_worker2 = min(ray2, key=lambda r: r[1])
        wall1 = min(r[1] for r in ray1)
        per = serial_wall / TRIALS
        print(
            f"serial loop:        {serial_wall:6.2f} s, {60 / per:6.1f} trials/min ({per:.2f} s per trial)"
        )
        print(
            f"Ray, {WORKERS} workers:     {wall2:6.2f} s, {60 * TRIALS / wall2:6.1f} trials/min "
            f"(+ ray.init {init2:.2f} s once per sweep)"
        )
        print(
            f"throughput ratio:   {serial_wall / wall2:.2f}x the serial loop (goal >= {THROUGHPUT_GOAL}x), "
            f"{serial_wall / (wall2 + init2):.2f}x counting Ray's start-up"
        )
        overhead = (wall1 - serial_wall) / TRIALS
        print(
            f"Ray, 1 worker:      {wall1:6.2f} s; overhead per trial {overhead:.3f} s = "
            f"{overhead / per:.1%} of a {per:.2f} s trial (goal < {OVERHEAD_GOAL:.0%})"
        )
        outside = WORKERS * wall2 / TRIALS - float(np.mean(in_worker2))
        print(
            f"2-worker sweep:     Ray's time outside the trial function {outside:.3f} s per trial "
            f"(trial function {np.mean(in_worker2):.2f} s)"
        )
        if args.six_joint:
            six_wall, _ = serial(SIX_JOINT, root / "six")
            episodes = SIX_JOINT["episodes"]
            print(
                f"six-joint trial (6 joints x 5 bins, 1 experiment x {episodes} episodes, "
                f"full planning 20): {six_wall:.2f} s"
            )
            for cores in (8, 16):
                slots = CLUSTER_NODES * cores
                waves = math.ceil(CLUSTER_TRIALS / slots)
                minutes = waves * (six_wall + max(overhead, 0.0)) / 60
                print(
                    f"paper estimate: {CLUSTER_TRIALS} such trials on {CLUSTER_NODES} nodes x "
                    f"{cores} cores = {slots} slots, {waves} waves: {minutes:.1f} min "
                    f"(one core: {CLUSTER_TRIALS * six_wall / 3600:.1f} h)"
                )


if __name__ == "__main__":
    main()
