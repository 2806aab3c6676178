"""Dyna-Q speed: studio.learning's numba kernels against a plain-Python transcription of Fig. 1.

Measures, in one run (``python benchmarks/bench_dynaq.py``; ``--full-reference`` runs the
reference on all experiments instead of extrapolating from a sample, about 70 s more):

1. all six paper configurations, 20 experiments x 100 episodes: our wall and CPU time on all cores
   against the reference's CPU time (goals: >= 100x faster, < 1 s wall on 2 cores);
2. planning updates per second per core with full planning (goal: >= 50 million);
3. the disk-cached JIT: two fresh processes with an empty numba cache directory, the first compiles
   and the second loads, each timed from interpreter start to the end of its first learning run
   (goal: the second under 1 s).

Experiments are independent and identically distributed, so by default the reference runs
``--reference-sample`` experiments per configuration and its CPU time is scaled to 20.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from dynaq_reference import run_experiment as reference_experiment  # noqa: E402

from studio.learning import ArmGrid, DynaQConfig, generate_demonstrations, run_experiments, warm_up  # noqa: E402
from studio.learning._reproduce import CONFIGURATIONS, DEMONSTRATIONS  # noqa: E402

EXPERIMENTS = 20
EPISODES = 100
SPEED_GOAL = 100.0
WALL_GOAL_S = 1.0
UPDATES_GOAL = 50e6
STARTUP_GOAL_S = 1.0
REPEATS = 3

STARTUP_SCRIPT = """
import time
start = time.perf_counter()
from studio.learning import ArmGrid, DynaQConfig, run_experiments
grid = ArmGrid()
run_experiments(grid.mdp(), DynaQConfig(planning="full"), 1, 1, 0)
run_experiments(grid.mdp(), DynaQConfig(planning="prioritized"), 1, 1, 0)
print(time.perf_counter() - start)
"""


def bench_configurations(sample: int) -> None:
    grid = ArmGrid()
    mdp = grid.mdp()
    demos = generate_demonstrations(grid, DEMONSTRATIONS, np.random.default_rng([0, 1]))
    warm_up()
    print(
        f"1. Six configurations, {EXPERIMENTS} experiments x {EPISODES} episodes "
        f"(reference: {sample} experiments per configuration, scaled to {EXPERIMENTS})"
    )
    print(
        f"   {'configuration':<14}{'ours wall s':>12}{'ours CPU s':>12}{'ref CPU s':>12}{'ratio':>9}"
        f"{'ours ep1':>10}{'ref ep1':>9}"
    )
    lists = (
        mdp.next_state.tolist(),
        mdp.reward.tolist(),
        mdp.terminal.tolist(),
        mdp.start_states.tolist(),
    )
    total_wall = total_cpu = total_ref = 0.0
    for name, (supervised, planning) in CONFIGURATIONS.items():
        config = DynaQConfig(planning=planning)
        start = time.perf_counter()
        result = run_experiments(
            mdp, config, EXPERIMENTS, EPISODES, 0, demos if supervised else None
        )
        wall = time.perf_counter() - start
        ref_cpu, ref_first = 0.0, []
        for e in range(sample):
            steps, cpu = reference_experiment(
                *lists, planning=planning, planning_steps=config.planning_steps, episodes=EPISODES,
                seed=e, demonstrations=demos if supervised else None,
            )  # fmt: skip
            ref_cpu += cpu
            ref_first.append(steps[0] if not supervised else steps[DEMONSTRATIONS])
        ref_cpu *= EXPERIMENTS / sample
        ours_cpu = float(result.cpu_seconds.sum())
        ours_first = result.steps[:, 0 if not supervised else DEMONSTRATIONS].mean()
        total_wall += wall
        total_cpu += ours_cpu
        total_ref += ref_cpu
        print(
            f"   {name:<14}{wall:>12.3f}{ours_cpu:>12.3f}{ref_cpu:>12.1f}{ref_cpu / ours_cpu:>8.0f}x"
            f"{ours_first:>10.0f}{np.mean(ref_first):>9.0f}"
        )
    print(
        f"   {'all six':<14}{total_wall:>12.3f}{total_cpu:>12.3f}{total_ref:>12.1f}{total_ref / total_cpu:>8.0f}x"
    )
    print(
        f"   ratio ref CPU / our wall on {os.cpu_count()} cores: {total_ref / total_wall:.0f}x "
        f"(goal >= {SPEED_GOAL:.0f}x: {'met' if total_ref / total_wall >= SPEED_GOAL else 'MISSED'}); "
        f"wall {total_wall:.3f} s (goal < {WALL_GOAL_S} s: {'met' if total_wall < WALL_GOAL_S else 'MISSED'})"
    )
    print(
        f"   (ep1: mean steps of the first episode, or of episode {DEMONSTRATIONS + 1} after the demonstrations:"
    )
    print("   both implementations learn the same task alike; our wall is the best of 3 runs)")


def bench_planning_rate() -> None:
    mdp = ArmGrid().mdp()
    warm_up()
    print("2. Planning updates per second per core, full planning, one thread")
    for n in (100, 1000):
        result = run_experiments(
            mdp, DynaQConfig(planning="full", planning_steps=n), EXPERIMENTS, EPISODES, 0, workers=1
        )
        planning = int(result.updates.sum() - result.steps.sum())
        rate = planning / result.cpu_seconds.sum()
        # the reference's rate on the same task, from one short experiment
        lists = (
            mdp.next_state.tolist(),
            mdp.reward.tolist(),
            mdp.terminal.tolist(),
            mdp.start_states.tolist(),
        )
        steps, cpu = reference_experiment(
            *lists, planning="full", planning_steps=n, episodes=3, seed=0
        )
        ref_rate = sum(steps) * n / cpu
        print(
            f"   {n:>5} planning steps: ours {rate / 1e6:6.1f} M/s, reference {ref_rate / 1e6:6.3f} M/s "
            f"({rate / ref_rate:.0f}x); goal >= {UPDATES_GOAL / 1e6:.0f} M/s: "
            f"{'met' if rate >= UPDATES_GOAL else 'MISSED'}"
        )


def bench_startup() -> None:
    print(
        "3. Disk-cached JIT: fresh processes, interpreter start to the end of the first learning run"
    )
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        times = []
        for label in ("first (compiles)", "second (cached)"):
            start = time.perf_counter()
            out = subprocess.run(
                [sys.executable, "-c", STARTUP_SCRIPT],
                env=env,
                check=True,
                capture_output=True,
                text=True,
            )
            process = time.perf_counter() - start
            inside = float(out.stdout.strip())
            times.append(inside)
            print(f"   {label:<18} import + learn {inside:6.2f} s, whole process {process:6.2f} s")
    print(
        f"   compile / cached = {times[0] / times[1]:.0f}x; second start {times[1]:.2f} s "
        f"(goal < {STARTUP_GOAL_S} s: {'met' if times[1] < STARTUP_GOAL_S else 'MISSED'})"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--reference-sample", type=int, default=5, help="reference experiments per configuration"
    )
    parser.add_argument(
        "--full-reference", action="store_true", help=f"run the reference on all {EXPERIMENTS}"
    )
    args = parser.parse_args()
    bench_configurations(EXPERIMENTS if args.full_reference else args.reference_sample)
    print()
    bench_planning_rate()
    print()
    bench_startup()


if __name__ == "__main__":
    main()
