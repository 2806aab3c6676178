"""``studio export``: a policy file's greedy rollout as a joint trajectory CSV (time, q1..q6)."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from studio.learning import LearningError, greedy_path, load_policy, rollout, save_trajectory_csv
from studio.learning._policy import DEFAULT_MAX_STEPS, DEFAULT_RATE_HZ, DEFAULT_SECONDS_PER_STEP

NAME = "export"
HELP = "Roll a policy file out greedily from a start pose and write the joint trajectory as CSV."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "policy", type=Path, help="a .policy.npz file (from studio train or the page)"
    )
    start = parser.add_mutually_exclusive_group()
    start.add_argument("--start-state", type=int, help="grid state number to start from")
    start.add_argument(
        "--start-deg",
        help="start joint angles in degrees, comma-separated; write --start-deg=-90,0,0 when the first is negative (default: all 0)",
    )
    parser.add_argument(
        "--rate",
        type=float,
        default=DEFAULT_RATE_HZ,
        help=f"control rate in Hz (default: {DEFAULT_RATE_HZ:g})",
    )
    parser.add_argument(
        "--seconds-per-step",
        type=float,
        default=DEFAULT_SECONDS_PER_STEP,
        help=f"seconds per grid step (default: {DEFAULT_SECONDS_PER_STEP:g})",
    )
    parser.add_argument(
        "--max-steps", type=int, default=DEFAULT_MAX_STEPS, help="cap on greedy steps"
    )
    parser.add_argument(
        "--out", type=Path, help="CSV path (default: the policy's name with .rollout.csv)"
    )


def run(args: argparse.Namespace) -> int:
    policy = load_policy(args.policy)
    grid = policy.grid
    if args.start_state is not None:
        start = args.start_state
    else:
        text = args.start_deg or ",".join(["0"] * grid.joints)
        try:
            degrees = [float(v) for v in text.split(",")]
        except ValueError:
            raise LearningError(
                f"--start-deg is {text!r}; give {grid.joints} angles in degrees separated by commas."
            ) from None
        if len(degrees) != grid.joints:
            raise LearningError(
                f"--start-deg has {len(degrees)} angles; give {grid.joints}, one per grid joint."
            )
        start = grid.state_of_angles(np.radians(degrees))
    times, q = rollout(
        policy,
        start,
        rate_hz=args.rate,
        max_steps=args.max_steps,
        seconds_per_step=args.seconds_per_step,
    )
    path = greedy_path(policy, start, args.max_steps)
    out = args.out or args.policy.with_name(
        args.policy.name.removesuffix(".npz").removesuffix(".policy") + ".rollout.csv"
    )
    try:
        save_trajectory_csv(out, times, q)
    except OSError as err:
        raise LearningError(f"Cannot write {out} ({err.strerror}); choose another --out.") from None
    reached = path[-1] == grid.goal_state
    print(
        f"{len(path) - 1} grid steps from state {start} {'reach the goal' if reached else 'do NOT reach the goal'}; "
        f"wrote {len(times)} samples ({times[-1]:.2f} s at {args.rate:g} Hz) to {out}"
    )
    return 0
