"""``studio evaluate``: a run's policy judged from held-out random starts, beside its teacher.

``studio evaluate RUN|POLICY [--starts N] [--seed S] [--json]`` rolls the policy out greedily from
N random starts (drawn as its task draws its episodes' starts, from ``--seed``) on its own robot
and goal, and says the share of starts that reach the goal, the share whose rollout would touch
the robot itself, the table or one of the task's boxes (its obstacles, checked along the whole
rollout), and the mean steps and seconds to the goal. For a continuous run
taught from demonstrations it says the same of the teacher (the demonstrations followed, no
learning) on the very same starts: the baseline the policy has to beat.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from studio import StudioError

if TYPE_CHECKING:
    import numpy as np

NAME = "evaluate"
HELP = "Judge a policy from held-out random starts (success, collisions, time to the goal) beside its teacher."
DEFAULT_STARTS = 200
"""How many held-out starts by default, as the benchmarks' tables use."""
MAX_STARTS = 100_000
"""The most starts one evaluation rolls out."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "policy",
        metavar="RUN|POLICY",
        help="a run (runs/NAME, or its name) or a policy file (*.policy.npz)",
    )
    parser.add_argument(
        "--starts",
        type=int,
        default=DEFAULT_STARTS,
        help=f"how many random starts (default: {DEFAULT_STARTS})",
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="the seed the starts are drawn from (default: 0)"
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--data-dir",
        type=Path,
        default=Path("."),
        help="the data folder a run's name is looked for in (default: the current folder)",
    )


def _policy_file(given: str, data_dir: Path) -> Path:
    """The policy file ``given`` names: a run's folder, a run's name, or a policy file."""
    from studio.export import find_source
    from studio.learning import POLICY_SUFFIX

    path = Path(given)
    if path.is_dir():
        path = path / f"policy{POLICY_SUFFIX}"
        if not path.is_file():
            raise StudioError(
                f"The run {given} has no policy yet ({path.name} is missing); wait for it to "
                "finish, or give another run."
            )
        return path
    found = find_source(given, data_dir)
    if not found.name.endswith(POLICY_SUFFIX):
        raise StudioError(
            f"{given} names {found.name}, which is not a policy; give a run or a *{POLICY_SUFFIX} "
            "file."
        )
    return found


def _collides_with(obstacles: tuple) -> Callable[[str, np.ndarray], bool]:
    """Whether a rollout touches the robot itself or the table at a sample, or the task's
    boxes anywhere along it (its samples joined by straight moves)."""

    def collides(robot: str, q: np.ndarray) -> bool:
        import numpy as np  # with the robot models, when a rollout is judged: not for --help

        from studio.kinematics import load_robot
        from studio.learning import obstacle_guard

        arm = load_robot(robot)
        path = np.atleast_2d(q)
        if obstacles and obstacle_guard(robot, obstacles).path_collides(path):
            return True
        return any(arm.contacts(row) for row in path)

    return collides


def run(args: argparse.Namespace) -> int:
    if not 1 <= args.starts <= MAX_STARTS:
        raise StudioError(f"--starts is {args.starts}; give a whole number from 1 to {MAX_STARTS}.")
    from studio.learning import evaluate_policy, load_any_policy, policy_obstacles

    path = _policy_file(args.policy, args.data_dir)
    policy = load_any_policy(path)
    collides = _collides_with(policy_obstacles(policy))
    result = evaluate_policy(policy, args.starts, args.seed, collides)
    if args.json:
        out = {"policy": result.policy.as_json()}
        if result.teacher is not None:
            out["teacher"] = result.teacher.as_json()
        print(json.dumps(out))
        return 0
    print(f"{path}: from {result.starts} random starts (seed {result.seed})")
    rows = [("policy", result.policy)]
    if result.teacher is not None:
        rows.append(("teacher", result.teacher))
    for who, judged in rows:
        steps = "-" if judged.mean_steps != judged.mean_steps else f"{judged.mean_steps:.1f}"
        seconds = (
            "-" if judged.mean_seconds != judged.mean_seconds else f"{judged.mean_seconds:.2f} s"
        )
        print(
            f"  {who:<8} success {judged.success:6.1%}  collisions {judged.collisions:6.1%}  "
            f"mean steps {steps}  mean time {seconds}"
        )
    if result.teacher is None:
        print("  (no teacher: the policy was not taught by following demonstrations)")
    return 0
