"""Six-joint continuous learning on today's arms: does the Panda's and the UR5's greedy policy
reach the goal as the Puma560's does, and at what CPU cost?

``python benchmarks/bench_robots_learning.py [--episodes 1000,2000,4000] [--experiments 2]
[--robots puma560,panda,ur5]``. For each robot, the continuous reach task
(``TeachStudio/ArmReach-v0``) over its first six joints with every default: the robot's default
goal (the paper's for the Puma560, the ready pose for the others), 2-degree steps, the tool within
2 cm and 10 degrees, shaping 5, one joint per action, per-joint tilings (8 x 32); linear Dyna-Q
with zero planning and the paper's alpha 0.1, gamma 0.95, epsilon 0.1, episodes capped at 3,000
steps, no demonstrations. Each budget is trained afresh (same seeds); every experiment's greedy
policy is judged from 200 held-out random starts drawn across the robot's limits. Printed per
robot and budget: the mean greedy success (and each experiment's), the CPU seconds per experiment,
and that CPU time over the Puma560's at the same budget (measured in the same run). The goal:
>= 95% for the Panda and the UR5.
"""

from __future__ import annotations

import argparse

import gymnasium
import numpy as np

from studio.learning import ArmReach, DynaQConfig, run_experiments
from studio.learning.linear._linear import greedy_success
from studio.learning.tasks._gym import ARM_REACH_ID

SEED = 0
STARTS = 200
JOINTS = 6
SUCCESS = 0.95
CAP = 3_000


def measure(robot: str, episodes: int, experiments: int) -> tuple[list[float], float]:
    """Per experiment greedy success from :data:`STARTS` held-out starts, and the mean CPU
    seconds of an experiment."""
    task = ArmReach(joints=JOINTS, robot=robot)
    rng = np.random.default_rng([SEED, 99])  # not the training episodes' generator
    starts = np.array([task.random_start(rng) for _ in range(STARTS)])
    config = DynaQConfig(planning="zero", max_steps_per_episode=CAP)
    result = run_experiments(
        lambda: gymnasium.make(ARM_REACH_ID, joints=JOINTS, robot=robot),
        config,
        experiments,
        episodes,
        SEED,
        [],
        task.features(),
    )
    success = [
        float(greedy_success(task, result.coder, w, starts, CAP).mean()) for w in result.weights
    ]
    return success, float(result.cpu_seconds.mean())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", default="1000,2000,4000")
    parser.add_argument("--experiments", type=int, default=2)
    parser.add_argument("--robots", default="puma560,panda,ur5")
    args = parser.parse_args()
    robots = args.robots.split(",")
    budgets = [int(b) for b in args.episodes.split(",")]
    print(
        f"{JOINTS} joints, defaults (2 deg steps, 2 cm / 10 deg, shaping 5, zero planning), "
        f"{args.experiments} experiments, greedy success from {STARTS} held-out starts"
    )
    print(
        "| robot | episodes | greedy success (per experiment) | CPU s per experiment | CPU / Puma560's |"
    )
    print("|---|---|---|---|---|")
    for episodes in budgets:
        baseline = None
        for robot in robots:
            success, cpu = measure(robot, episodes, args.experiments)
            if robot == "puma560":
                baseline = cpu
            ratio = f"{cpu / baseline:.2f}" if baseline else "-"
            mark = "" if np.mean(success) >= SUCCESS else " (below 95%)"
            shares = ", ".join(f"{s:.1%}" for s in success)
            print(
                f"| {robot} | {episodes:,} | {np.mean(success):.1%}{mark} ({shares}) | {cpu:.2f} | {ratio} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
