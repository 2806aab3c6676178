"""Dyna-Q speed: studio.learning's numba kernels against a plain-Python transcription of Fig. 1.

Measures, in one run (``python benchmarks/bench_dynaq.py``; ``--full-reference`` runs the
reference on all 20 experiments instead of a sample, about 30 s more):

1. all six paper configurations, 20 experiments x 100 episodes: our wall and CPU time (both the
   best of 3 runs) on all cores against the reference's CPU time (goals: >= 100x faster, < 1 s
   wall on 2 cores);
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
    print(
        f"1. Six configurations, {EXPERIMENTS} experiments x {EPISODES} episodes "
        f"(reference: {sample} experiments per configuration)"
    )
    print(
        f"   {'configuration':<14}{'ours wall s':>12}{'ours CPU s':>12}{'ref CPU s':>11}"
        f"{'ref same work':>15}{'CPU ratio':>11}"
    )
    lists = (
        mdp.next_state.tolist(),
        mdp.reward.tolist(),
        mdp.terminal.tolist(),
        mdp.start_states.tolist(),
    )
    total_wall = total_cpu = total_ref = total_same = 0.0
    for name, (supervised, planning) in CONFIGURATIONS.items():
        config = DynaQConfig(planning=planning)
        wall = ours_cpu = np.inf
        for _ in range(REPEATS):  # the same seed: the same work each time
            start = time.perf_counter()
            result = run_experiments(
                mdp, config, EXPERIMENTS, EPISODES, 0, demos if supervised else None
            )
            wall = min(wall, time.perf_counter() - start)
            ours_cpu = min(ours_cpu, float(result.cpu_seconds.sum()))
        ref_cpu, ref_updates = 0.0, 0
        for e in range(sample):
            steps, cpu = reference_experiment(
                *lists, planning=planning, planning_steps=config.planning_steps, episodes=EPISODES,
                seed=e, demonstrations=demos if supervised else None,
            )  # fmt: skip
            ref_cpu += cpu
            ref_updates += _reference_updates(steps, planning, config.planning_steps)
        # the reference's CPU for exactly our work: its cost per Q update times our Q updates
        same_work = ref_cpu / ref_updates * float(result.updates.sum())
        ref_cpu *= EXPERIMENTS / sample
        total_wall += wall
        total_cpu += ours_cpu
        total_ref += ref_cpu
        total_same += same_work
        print(
            f"   {name:<14}{wall:>12.3f}{ours_cpu:>12.3f}{ref_cpu:>11.1f}{same_work:>15.1f}"
            f"{same_work / ours_cpu:>10.0f}x"
        )
    print(
        f"   {'all six':<14}{total_wall:>12.3f}{total_cpu:>12.3f}{total_ref:>11.1f}{total_same:>15.1f}"
        f"{total_same / total_cpu:>10.0f}x"
    )
    print(
        "   ref CPU s: the reference's CPU over its sample, scaled to "
        f"{EXPERIMENTS} experiments (noisy: first episodes vary as much as their mean);"
    )
    print(
        "   ref same work: its CPU per Q update times our Q updates; CPU ratio = ref same work / ours CPU"
    )
    print(
        f"   ref same work / our wall on {os.cpu_count()} cores: {total_same / total_wall:.0f}x "
        f"(goal >= {SPEED_GOAL:.0f}x: {'met' if total_same / total_wall >= SPEED_GOAL else 'MISSED'}); "
        f"CPU to CPU {total_same / total_cpu:.0f}x; our wall {total_wall:.3f} s "
        f"(goal < {WALL_GOAL_S} s: {'met' if total_wall < WALL_GOAL_S else 'MISSED'}; best of {REPEATS})"
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
