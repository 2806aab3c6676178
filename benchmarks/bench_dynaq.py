"""Dyna-Q speed: studio.learning's numba kernels against a plain-Python transcription of Fig. 1.

Measures, in one run (``python benchmarks/bench_dynaq.py``; ``--full-reference`` runs the
reference on all 20 experiments instead of a sample, about 30 s more):

1. all six paper configurations, 20 experiments x 100 episodes: our wall and CPU time on all cores
   and our CPU time on one thread (each the best of 3 runs) against the reference's CPU time
   (goals: >= 100x faster, < 1 s wall on 2 cores);
2. planning updates per second per core with full planning (goal: >= 50 million);
3. the disk-cached JIT: two fresh processes with an empty numba cache directory, the first compiles
   and the second loads, each timed from interpreter start to the end of its first learning run
   (goal: the second under 1 s);
4. that both learn alike: unsupervised steps in the first three episodes, mean and standard error.

The work of an experiment varies a lot (an unsupervised first episode takes anywhere from a few to
thousands of steps, with a spread about equal to its mean), so the reference's CPU over a sample of
experiments, scaled to 20, is a noisy estimate. The ratios therefore compare equal work: the
reference's CPU per Q update (real plus planning, measured over its sample) times the Q updates our
run did. The scaled sample is printed beside it.
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
from studio.learning.paper._reproduce import CONFIGURATIONS, DEMONSTRATIONS  # noqa: E402

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


def _reference_updates(steps: list[int], planning: str, planning_steps: int) -> int:
    """Q updates (real plus planning) of one reference experiment, from its steps per episode."""
    per_step = {
        "zero": [0] * len(steps),
        "full": [planning_steps] * len(steps),
        "soft": [max(planning_steps - k, 0) for k in range(len(steps))],
    }[planning]
    return sum(n * (1 + p) for n, p in zip(steps, per_step, strict=True))


def bench_configurations(sample: int) -> None:
    grid = ArmGrid()
    mdp = grid.mdp()
    demos = generate_demonstrations(grid, DEMONSTRATIONS, np.random.default_rng([0, 1]))
    warm_up()
    cores = os.cpu_count() or 1
    print(
        f"1. Six configurations, {EXPERIMENTS} experiments x {EPISODES} episodes "
        f"(reference: {sample} experiments per configuration)"
    )
    print(
        f"   {'':<14}{'---- ours, ' + str(cores) + ' threads ----':>24}{'ours, 1 thread':>16}"
        f"{'--------- reference ---------':>30}"
    )
    print(
        f"   {'configuration':<14}{'wall s':>12}{'CPU s':>12}{'CPU s':>16}{'CPU s':>12}"
        f"{'same work':>12}{'ratio':>8}"
    )
    lists = (
        mdp.next_state.tolist(),
        mdp.reward.tolist(),
        mdp.terminal.tolist(),
        mdp.start_states.tolist(),
    )
    totals = np.zeros(5)  # wall, CPU on all cores, CPU on one thread, reference, same work
    for name, (supervised, planning) in CONFIGURATIONS.items():
        config = DynaQConfig(planning=planning)
        demos_or_none = demos if supervised else None
        wall = cpu_all = cpu_one = np.inf
        for _ in range(REPEATS):  # the same seed: the same work each time
            start = time.perf_counter()
            result = run_experiments(mdp, config, EXPERIMENTS, EPISODES, 0, demos_or_none)
            wall = min(wall, time.perf_counter() - start)
            cpu_all = min(cpu_all, float(result.cpu_seconds.sum()))
            single = run_experiments(
                mdp, config, EXPERIMENTS, EPISODES, 0, demos_or_none, workers=1
            )
            cpu_one = min(cpu_one, float(single.cpu_seconds.sum()))
        ref_cpu, ref_updates = 0.0, 0
        for e in range(sample):
            steps, cpu = reference_experiment(
                *lists, planning=planning, planning_steps=config.planning_steps, episodes=EPISODES,
                seed=e, demonstrations=demos_or_none,
            )  # fmt: skip
            ref_cpu += cpu
            ref_updates += _reference_updates(steps, planning, config.planning_steps)
        # the reference's CPU for exactly our work: its cost per Q update times our Q updates
        same_work = ref_cpu / ref_updates * float(result.updates.sum())
        ref_cpu *= EXPERIMENTS / sample
        row = np.array([wall, cpu_all, cpu_one, ref_cpu, same_work])
        totals += row
        print(
            f"   {name:<14}{wall:>12.3f}{cpu_all:>12.3f}{cpu_one:>16.3f}{ref_cpu:>12.1f}"
            f"{same_work:>12.1f}{same_work / cpu_one:>7.0f}x"
        )
    wall, cpu_all, cpu_one, ref_cpu, same_work = totals
    print(
        f"   {'all six':<14}{wall:>12.3f}{cpu_all:>12.3f}{cpu_one:>16.3f}{ref_cpu:>12.1f}"
        f"{same_work:>12.1f}{same_work / cpu_one:>7.0f}x"
    )
    print(
        "   reference CPU s: its CPU over its sample scaled to "
        f"{EXPERIMENTS} experiments (noisy: first episodes vary as much as their mean);"
    )
    print(
        "   same work: its CPU per Q update times our Q updates; ratio = same work / ours on 1 thread;"
    )
    print(
        f"   ours: best of {REPEATS} runs each (the CPU of {cores} threads at once includes their contention)"
    )
    print(
        f"   reference CPU / our wall on {cores} cores: {same_work / wall:.0f}x "
        f"(goal >= {SPEED_GOAL:.0f}x: {'met' if same_work / wall >= SPEED_GOAL else 'MISSED'}); "
        f"CPU to CPU: {same_work / cpu_one:.0f}x on 1 thread, {same_work / cpu_all:.0f}x on {cores}; "
        f"our wall {wall:.3f} s (goal < {WALL_GOAL_S} s: {'met' if wall < WALL_GOAL_S else 'MISSED'})"
    )


def bench_agreement(experiments: int) -> None:
    """Do both implementations learn alike? First-episode steps, unsupervised, mean +- s.e."""
    mdp = ArmGrid().mdp()
    lists = (
        mdp.next_state.tolist(),
        mdp.reward.tolist(),
        mdp.terminal.tolist(),
        mdp.start_states.tolist(),
    )
    print(
        "4. Same learning: unsupervised steps in episodes 1-3, mean +- standard error "
        "(first episodes spread about as widely as their mean)"
    )
    for planning, n_ref in (("zero", 5 * experiments), ("full", experiments)):
        theirs = np.array(
            [
                reference_experiment(
                    *lists, planning=planning, planning_steps=100, episodes=3, seed=10_000 + e
                )[0]
                for e in range(n_ref)
            ]
        )
        ours = run_experiments(mdp, DynaQConfig(planning=planning), 1000, 3, 1).steps
        cells = []
        worst = 0.0
        for k in range(3):
            a, b = ours[:, k], theirs[:, k]
            sa, sb = a.std(ddof=1) / np.sqrt(a.size), b.std(ddof=1) / np.sqrt(b.size)
            z = (a.mean() - b.mean()) / np.hypot(sa, sb)
            worst = max(worst, abs(z))
            cells.append(
                f"ep{k + 1} {a.mean():5.0f}+-{sa:<3.0f} vs {b.mean():5.0f}+-{sb:<4.0f} ({z:+.1f} s.e.)"
            )
        print(f"   US-{planning:<5} ours (1000) vs reference ({n_ref}): " + "; ".join(cells))
        print(
            f"   {'':<9} {'same within 3 s.e.' if worst < 3 else 'DIFFERENT: more than 3 s.e. apart'}"
        )


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
    parser.add_argument(
        "--agreement-experiments",
        type=int,
        default=40,
        help="reference experiments for the full-planning learning comparison (5x for zero)",
    )
    args = parser.parse_args()
    bench_configurations(EXPERIMENTS if args.full_reference else args.reference_sample)
    print()
    bench_planning_rate()
    print()
    bench_startup()
    print()
    bench_agreement(args.agreement_experiments)


if __name__ == "__main__":
    main()
