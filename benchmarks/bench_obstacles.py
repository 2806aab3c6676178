"""Around an obstacle (issue 40): a box where a shipped demonstration's arm passes mid-motion.

``python benchmarks/bench_obstacles.py [--episodes 100] [--experiments 20] [--starts 200]``
trains the Puma560 on the paper's grid (3 joints, 11 bins, goal bins (5, 6, 2), the paper's
reward, full planning) with the box :data:`BOX` in its workspace, taught by the three shipped
samples, and again without demonstrations at the same budget, through the same run request
``studio train`` makes::

    studio train --obstacle 0.56,0.18,1.08,0.12,0.12,0.12 \\
        --demos sample-reach-1 --demos sample-reach-2 --demos sample-reach-3 --out runs/around
    studio evaluate runs/around

It prints, for each run's policy from ``--starts`` held-out random starts (``studio evaluate``'s
starts, seed 0): the share reaching the goal, the share whose rollout touches the box anywhere
along it, the share touching the table or itself at a sample (the paper's grid spans joints 2
and 3 over +-180 degrees, beyond the arm's limits, so many of its states lie in the table: this
share is the grid's, obstacles or not), and the mean steps to the goal; then whether replaying
each demonstration's grid path (the teacher) would pass through the box.

With ``--task arm-reach`` the same for the six-joint continuous task with its defaults (the
paper's reward plus shaping 5 toward the goal's joint angles, no demonstration potential; one
joint a step and the follow action; full planning of 100 steps; the tiles of a task with
obstacles: each joint alone, joint 1 with joint 2 and with joint 3; the greedy policy of a task
with obstacles stepping around refused moves), its teacher being the demonstrations followed,
taught by ``sample-reach-2`` alone (``--samples`` to choose): the three samples end at wrist
angles 147 degrees apart about the forearm (joint 4 at -158, -11 and -116 degrees), so at six
joints the goal pose of one is not the goal of the others and the task refuses them together.
Each run's row also gives the same weights' greedy success pressing refused moves again, and
``--per-joint-tiles`` trains both runs on each joint's tiles alone (the features before).
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import time
from pathlib import Path

import numpy as np

from studio.commands.train import demonstration_file
from studio.kinematics import Obstacle, load_robot
from studio.learning import (
    DemonstrationPath,
    RunFolder,
    RunRequest,
    evaluate_policy,
    load_any_policy,
    obstacle_guard,
    resolve_run,
)
from studio.learning.linear._greedy import greedy_success, steps_around
from studio.learning.linear._policy import DEFAULT_MAX_STEPS, TilePolicyFile
from studio.motion import training_demonstration

BOX = Obstacle((0.56, 0.18, 1.08), (0.12, 0.12, 0.12))
"""Where sample-reach-2's wrist passes between its fourth and fifth grid states (joint 3 from
+16 to -16 degrees, joints 1 and 2 at 33 and 0), 12 cm a side: clear of the goal pose."""
SAMPLES = ("sample-reach-1", "sample-reach-2", "sample-reach-3")


def _demonstrations(robot: str, names: list[str]) -> list[DemonstrationPath]:
    return [training_demonstration(demonstration_file(Path(n)), robot, n) for n in names]


def _run(request: RunRequest, root: Path, per_joint: bool = False):
    record = resolve_run(request)
    if per_joint:  # the features before a box added joint 1 with joints 2 and 3
        singles = tuple((j,) for j in range(record.arm_reach().joints))
        record = dataclasses.replace(
            record, coding=dataclasses.replace(record.tile_coding(), groups=singles)
        )
    folder = RunFolder.create(root, record)
    start = time.process_time()
    folder.train()
    return folder, time.process_time() - start


def _judge(folder: RunFolder, starts: int, robot: str) -> dict:
    policy = load_any_policy(folder.path / "policy.policy.npz")
    guard = obstacle_guard(robot, (BOX,))
    arm = load_robot(robot)
    boxed = evaluate_policy(policy, starts, 0, lambda r, q: guard.path_collides(np.atleast_2d(q)))
    other = evaluate_policy(
        policy, starts, 0, lambda r, q: any(arm.contacts(row) for row in np.atleast_2d(q))
    )
    seeds = np.random.default_rng(0).integers(0, 2**31 - 1, size=starts)
    alone = None
    if isinstance(policy, TilePolicyFile) and steps_around(policy.task):  # the same weights,
        task = policy.task  # the greedy policy pressing refused moves again
        q = np.array([task.random_start(np.random.default_rng(int(s))) for s in seeds])
        alone = greedy_success(
            task, policy.coder, policy.weights, q, DEFAULT_MAX_STEPS, True, False
        )
    return {"judged": boxed, "table_or_self": other.policy.collisions, "alone": alone}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", choices=("arm-grid", "arm-reach"), default="arm-grid")
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--experiments", type=int, default=20)
    parser.add_argument("--starts", type=int, default=200)
    parser.add_argument("--samples", nargs="+", help="the demonstrations (default: see above)")
    parser.add_argument(
        "--per-joint-tiles",
        action="store_true",
        help="arm-reach: tile each joint alone, as before a box added joint 1 with joints 2 and 3",
    )
    args = parser.parse_args()
    robot = "puma560"
    names = args.samples or (list(SAMPLES) if args.task == "arm-grid" else ["sample-reach-2"])
    demos = _demonstrations(robot, names)
    common = {
        "task": args.task,
        "robot": robot,
        "experiments": args.experiments,
        "episodes": args.episodes,
        "obstacles": [BOX],
    }
    guard = obstacle_guard(robot, (BOX,))
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        per_joint = args.task == "arm-reach" and args.per_joint_tiles
        taught, cpu_taught = _run(
            RunRequest(**common, demonstrations=demos, name="taught"), root, per_joint
        )
        record = taught.record
        goal = {"goal": record.arm_reach().goal} if args.task == "arm-reach" else None
        bare_request = RunRequest(**common, name="bare", reach=goal or {})
        bare, cpu_bare = _run(bare_request, root, per_joint)
        print(
            f"{args.task}, box {BOX.text()}, {args.experiments} x {args.episodes} episodes, "
            f"{args.starts} held-out starts"
        )
        if args.task == "arm-reach":
            task, coding = record.arm_reach(), record.tile_coding()
            config = record.config
            print(
                f"  reward: the paper's (+100 at the goal, -1 a step) plus shaping "
                f"{task.shaping:g} toward the goal's joint angles, no demonstration potential; "
                f"actions {task.actions!r} (one joint a step, and with demonstrations the "
                f"follow action); tiles {coding.tilings} x {coding.tiles}, groups "
                f"{coding.groups} (and the follow cost's); planning {config.planning} "
                f"{config.planning_steps}; the greedy policy steps around refused moves"
            )
        how = ""
        if args.task == "arm-reach":
            tiles = "each joint's tiles" if per_joint else "tiles of each joint, joint 1 x 2, 1 x 3"
            how = f" ({tiles}; greedy stepping around refused moves)"
        for label, folder, cpu in (
            ("taught by " + ", ".join(names) + how, taught, cpu_taught),
            ("no demonstrations, same budget" + how, bare, cpu_bare),
        ):
            out = _judge(folder, args.starts, robot)
            p, t = out["judged"].policy, out["judged"].teacher
            print(
                f"  {label}: success {p.success:.1%}, box collisions "
                f"{p.collisions:.1%}, table/self {out['table_or_self']:.1%}, mean steps "
                f"{p.mean_steps:.1f} ({p.mean_seconds:.2f} s), CPU {cpu:.1f} s"
            )
            if out["alone"] is not None:
                print(
                    f"    the same weights, the greedy policy pressing refused moves again: "
                    f"success {out['alone'].mean():.1%}"
                )
            if t is not None:
                print(
                    f"    its teacher (the demonstrations followed, no learning): success "
                    f"{t.success:.1%}, box collisions {t.collisions:.1%}, mean steps "
                    f"{t.mean_steps:.1f}"
                )
        for demo in demos:
            touches = guard.path_collides(demo.q_robot)
            print(f"  {demo.label}'s recorded motion touches the box: {touches}")
        if args.task == "arm-grid":
            grid = record.arm_grid()
            for name, path in zip(names, record.demonstrations, strict=True):
                poses = grid.poses()[path]
                print(
                    f"  replaying {name}'s grid path touches the box: {guard.path_collides(poses)}"
                )


if __name__ == "__main__":
    main()
