"""``studio export``: a policy file's greedy rollout as a joint trajectory CSV (time, q1..q6)."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from studio.learning import (
    ROLLOUT_MAX_STEPS,
    ROLLOUT_RATE_HZ,
    ROLLOUT_SECONDS_PER_STEP,
    TILE_ROLLOUT_MAX_STEPS,
    TILE_ROLLOUT_SECONDS_PER_STEP,
    DmpPolicyFile,
    LearningError,
    TilePolicyFile,
    dmp_likeness_card,
    greedy_path,
    load_any_policy,
    rollout,
    rollout_dmp_policy,
    rollout_tile_policy,
    save_trajectory_csv,
)

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
        default=ROLLOUT_RATE_HZ,
        help=f"control rate in Hz (default: {ROLLOUT_RATE_HZ:g})",
    )
    parser.add_argument(
        "--seconds-per-step",
        type=float,
        default=None,
        help=f"seconds per step (default: {ROLLOUT_SECONDS_PER_STEP:g} per grid step, {TILE_ROLLOUT_SECONDS_PER_STEP:g} per joint step of a tile-coded policy)",
    )
    parser.add_argument(
        "--max-steps",
        type=int,
        default=None,
        help=f"cap on greedy steps (default: {ROLLOUT_MAX_STEPS} grid steps, {TILE_ROLLOUT_MAX_STEPS} joint steps)",
    )
    parser.add_argument(
        "--out", type=Path, help="CSV path (default: the policy's name with .rollout.csv)"
    )


def _start_degrees(text: str | None, joints: int) -> list[float]:
    """The --start-deg angles (default all 0), checked to be one per joint."""
    text = text or ",".join(["0"] * joints)
    try:
        degrees = [float(v) for v in text.split(",")]
    except ValueError:
        raise LearningError(
            f"--start-deg is {text!r}; give {joints} angles in degrees separated by commas."
        ) from None
    if len(degrees) != joints:
        raise LearningError(
            f"--start-deg has {len(degrees)} angles; give {joints}, one per learned joint."
        )
    return degrees


def _out_path(args: argparse.Namespace) -> Path:
    return args.out or args.policy.with_name(
        args.policy.name.removesuffix(".npz").removesuffix(".policy") + ".rollout.csv"
    )


def _run_tile(args: argparse.Namespace, policy: TilePolicyFile) -> int:
    """Roll out a tile-coded arm policy from --start-deg (joint steps, constant speed)."""
    if args.start_state is not None:
        raise LearningError(
            "--start-state numbers grid states; a tile-coded policy starts from --start-deg angles."
        )
    joints = policy.task.joints if policy.task is not None else 0
    start = np.radians(_start_degrees(args.start_deg, joints)) if joints else np.zeros(0)
    times, q, reached = rollout_tile_policy(
        policy,
        start,
        rate_hz=args.rate,
        max_steps=TILE_ROLLOUT_MAX_STEPS if args.max_steps is None else args.max_steps,
        seconds_per_step=TILE_ROLLOUT_SECONDS_PER_STEP
        if args.seconds_per_step is None
        else args.seconds_per_step,
    )
    out = _out_path(args)
    try:
        save_trajectory_csv(out, times, q)
    except OSError as err:
        raise LearningError(f"Cannot write {out} ({err.strerror}); choose another --out.") from None
    print(
        f"the greedy policy {'reaches the goal' if reached else 'does NOT reach the goal'} in {times[-1]:.2f} s; "
        f"wrote {len(times)} samples at {args.rate:g} Hz to {out}"
    )
    return 0


def _run_dmp(args: argparse.Namespace, policy: DmpPolicyFile) -> int:
    """Roll a movement primitive out from --start-deg (default: its demonstration's start) and
    print its likeness card (from the demonstration's start) beside the demonstration's."""
    if args.start_state is not None:
        raise LearningError(
            "--start-state numbers grid states; a movement primitive starts from --start-deg angles."
        )
    start = (
        None
        if args.start_deg is None
        else np.radians(_start_degrees(args.start_deg, len(policy.goal)))
    )
    times, q, reached = rollout_dmp_policy(policy, start, rate_hz=args.rate)
    out = _out_path(args)
    try:
        save_trajectory_csv(out, times, q)
    except OSError as err:
        raise LearningError(f"Cannot write {out} ({err.strerror}); choose another --out.") from None
    print(
        f"the movement primitive {'reaches the goal' if reached else 'does NOT reach the goal'} in {times[-1]:.2f} s; "
        f"wrote {len(times)} samples at {args.rate:g} Hz to {out}"
    )
    print(
        f"likeness to its demonstration, from the demonstration's start:\n{dmp_likeness_card(policy, args.rate).text()}"
    )
    return 0


def run(args: argparse.Namespace) -> int:
    policy = load_any_policy(args.policy)
    if isinstance(policy, TilePolicyFile):
        return _run_tile(args, policy)
    if isinstance(policy, DmpPolicyFile):
        return _run_dmp(args, policy)
    if args.max_steps is None:
        args.max_steps = ROLLOUT_MAX_STEPS
    if args.seconds_per_step is None:
        args.seconds_per_step = ROLLOUT_SECONDS_PER_STEP
    grid = policy.grid
    if args.start_state is not None:
        start = args.start_state
    else:
        start = grid.state_of_angles(np.radians(_start_degrees(args.start_deg, grid.joints)))
    times, q = rollout(
        policy,
        start,
        rate_hz=args.rate,
        max_steps=args.max_steps,
        seconds_per_step=args.seconds_per_step,
    )
    path = greedy_path(policy, start, args.max_steps)
    out = _out_path(args)
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
