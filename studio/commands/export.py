"""``studio export``: a policy, a demonstration or a recording as a robot's joint trajectory.

``studio export SOURCE --robot NAME --format csv|mcap|lerobot --out PATH`` times the motion
(at the person's pace, slower only where the robot's limits need it, from rest to rest; as fast
as the limits allow with ``--fastest``; a recording keeps its capture times unless ``--retime``),
checks it (positions, velocities, accelerations, self-collision), replays it in MuJoCo and
writes it with the physics report stated in the file; the :mod:`studio.export` package does all
four. ``SOURCE`` is a path, or a name in the data folder
or among the shipped samples (``sample-reach-1``).

``studio export POLICY`` alone (no ``--format``, ``--robot``, ``--unchecked`` nor ``--retime``)
writes the policy's greedy rollout at its own pace as before: ``time,q1..q6`` CSV, not checked.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

# Only light modules here: the flags' defaults and choices. What an export needs (numpy, the robot
# models, the learners, TOPP-RA, MuJoCo) is imported where it runs, so `studio export --help` and
# a mistyped flag answer at once.
from studio._layout import physics_cache_dir, robot_cache_dir
from studio.export import FORMAT_SUFFIXES, FORMATS, LIMIT_FRACTION, ExportError
from studio.kinematics import (
    LIMIT_MARGIN_RAD,
    KinematicsError,
    robot_names,
    robot_spec,
)
from studio.learning import (
    ROLLOUT_MAX_STEPS,
    ROLLOUT_RATE_HZ,
    ROLLOUT_SECONDS_PER_STEP,
    TILE_ROLLOUT_MAX_STEPS,
    TILE_ROLLOUT_SECONDS_PER_STEP,
    LearningError,
)

if TYPE_CHECKING:
    from studio.kinematics import RobotArm
    from studio.learning import AnyPolicy, Rollout
    from studio.motion import Motion

NAME = "export"
TIMINGS = {
    "pace": "at the person's pace where the limits allow",
    "toppra": "timed within the limits (TOPP-RA)",
    "source": "at its own times",
}
"""How ``studio export`` names each timing (``Exported.timed_by``)."""
HELP = "Export a policy, demonstration or recording as a robot trajectory checked for safety (CSV, MCAP, LeRobot)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "policy",
        metavar="SOURCE",
        type=Path,
        help="a policy (.policy.npz), a demonstration (.demo.json) or a recording, by path or by "
        "name in the data folder or among the samples (sample-reach-1)",
    )
    parser.add_argument(
        "--robot",
        help="the robot to export for (default: puma560; `studio robots` lists them); a "
        "recording or demonstration retargets to any, a policy drives its own",
    )
    parser.add_argument(
        "--format",
        choices=FORMATS,
        help="csv (time,<joint names>), mcap (ROS 2 messages) or lerobot (a LeRobotDataset "
        "v3.0 folder); without it and --robot, a policy's rollout is written as before",
    )
    parser.add_argument(
        "--unchecked",
        action="store_true",
        help="write even when the safety checks find problems, stating them in the file",
    )
    parser.add_argument(
        "--retime",
        action="store_true",
        help="time a recording's path within the robot's limits at --rate, as a demonstration "
        "is (at the person's pace, slower only where needed), instead of keeping its capture "
        "times: a recording to send to a robot",
    )
    parser.add_argument(
        "--fastest",
        action="store_true",
        help="time the path as fast as the robot's limits allow (TOPP-RA, time-optimal) instead "
        "of at the person's pace",
    )
    parser.add_argument(
        "--limit-fraction",
        type=float,
        default=LIMIT_FRACTION,
        help=f"share of the velocity and acceleration limits the timing uses (default: {LIMIT_FRACTION:g})",
    )
    parser.add_argument(
        "--limit-margin",
        type=float,
        default=None,
        metavar="RAD",
        help=f"margin kept from every joint's hard limit by the retargeting, the timing and "
        f"the checks (default: {LIMIT_MARGIN_RAD:g} rad, as the learners keep)",
    )
    parser.add_argument(
        "--data-dir", type=Path, default=Path("."), help="data folder names are looked up in"
    )
    parser.add_argument("--task", default="", help="LeRobot task text (default: from the source)")
    parser.add_argument(
        "--demo",
        metavar="NAME",
        help="score a policy's likeness card against this demonstration (a path or a name, "
        "rolled out from its start); default: the run's own demonstrations, or a movement "
        "primitive's",
    )
    start = parser.add_mutually_exclusive_group()
    start.add_argument("--start-state", type=int, help="grid state number to start from")
    start.add_argument(
        "--start-deg",
        help="start joint angles in degrees, comma-separated, one per learned joint or one per "
        "joint of the robot, e.g. -90,0,0 (default: the learned joints at 0, or with --robot "
        "or --format the robot's home pose where 0 is outside its limits)",
    )
    parser.add_argument(
        "--rate",
        type=float,
        default=ROLLOUT_RATE_HZ,
        help=f"control rate in Hz of a policy, a demonstration or a recording with --retime (default: {ROLLOUT_RATE_HZ:g}); a recording otherwise keeps its capture rate",
    )
    parser.add_argument(
        "--seconds-per-step",
        type=float,
        default=None,
        help=f"seconds per step of a policy (default: {ROLLOUT_SECONDS_PER_STEP:g} per grid step, a tile-coded policy's own pace (the demonstrations' it was taught from, else {TILE_ROLLOUT_SECONDS_PER_STEP:g} a step); with --format, default: timed within the robot's limits)",
    )
    parser.add_argument(
        "--max-steps",
        type=int,
        default=None,
        help=f"cap on greedy steps (default: {ROLLOUT_MAX_STEPS} grid steps, {TILE_ROLLOUT_MAX_STEPS} joint steps)",
    )
    parser.add_argument(
        "--out",
        type=Path,
        help="the file (a folder for lerobot); default: next to a policy, <name>.rollout.csv; "
        "with --format or --robot, <name>.<robot>.csv, .mcap or .lerobot in the current folder",
    )


def _start_degrees(text: str, counts: tuple[int, ...]) -> list[float]:
    """The --start-deg angles, checked to be as many as one of ``counts`` (the learned joints,
    or every joint of the robot)."""
    wanted = " or ".join(str(n) for n in dict.fromkeys(counts))
    try:
        degrees = [float(v) for v in text.split(",")]
    except ValueError:
        raise LearningError(
            f"--start-deg is {text!r}; give {wanted} angles in degrees separated by commas."
        ) from None
    if len(degrees) not in counts:
        raise LearningError(
            f"--start-deg has {len(degrees)} angles; give {wanted}, one per learned joint or "
            "one per joint of the robot."
        )
    return degrees


def _out_path(args: argparse.Namespace) -> Path:
    return args.out or args.policy.with_name(
        args.policy.name.removesuffix(".npz").removesuffix(".policy") + ".rollout.csv"
    )


def _zero_outside(arm: RobotArm | None, joints: int) -> bool:
    """Whether a learner's own start, its learned joints at 0, lies outside ``arm``'s limits
    (the Panda's joint 4 never reaches 0): then the robot's home pose starts the rollout."""
    if arm is None:
        return False
    import numpy as np

    return bool(np.any((arm.lower[:joints] > 0.0) | (arm.upper[:joints] < 0.0)))


def _rollout(
    args: argparse.Namespace,
    policy: AnyPolicy,
    seconds_per_step: float | None,
    arm: RobotArm | None = None,
) -> tuple[Rollout, str]:
    """The policy's rollout from --start-state (a grid policy's) or --start-deg (the learned
    joints, or every joint of ``arm``; default: its learner's own start, the learned joints at
    0 or a movement primitive's demonstration's start, or ``arm``'s home pose where 0 lies
    outside its limits), and the phrase saying what it did."""
    import numpy as np

    from studio.learning import Start, learner_of

    learner = learner_of(policy)
    joints = learner.learned_joints(policy)
    if args.start_state is not None:
        if not learner.grid_states:
            raise LearningError(
                f"--start-state numbers grid states; a {learner.title} starts from --start-deg angles."
            )
        start = Start(state=args.start_state)
    elif joints == 0 or (
        args.start_deg is None
        and (not _zero_outside(arm, joints) or learner.own_demonstration(policy) is not None)
    ):
        start = Start()  # its learner's own: zeros, or a primitive's demonstration's start
    elif args.start_deg is None:
        start = learner.pose_start(policy, np.array(arm.home))
    else:
        counts = (joints,) if arm is None else (joints, arm.nq)
        q = np.radians(_start_degrees(args.start_deg, counts))
        start = Start(q=q) if len(q) == joints else learner.pose_start(policy, q)
    rollout = learner.roll_out(
        policy,
        start,
        args.rate,
        max_steps=args.max_steps,  # None: the policy's own cap
        seconds_per_step=seconds_per_step,  # None: the policy's own pace
    )
    return rollout, learner.summary(rollout)


def _run_legacy(args: argparse.Namespace, policy: AnyPolicy) -> int:
    """``studio export POLICY``: the rollout at the policy's own pace, as CSV ``time,q1..q6``."""
    from studio.learning import save_trajectory_csv

    rollout, summary = _rollout(args, policy, args.seconds_per_step)
    times, q = rollout.times, rollout.q
    out = _out_path(args)
    try:
        save_trajectory_csv(out, times, q)
    except OSError as err:
        raise LearningError(f"Cannot write {out} ({err.strerror}); choose another --out.") from None
    if rollout.states:  # grid steps: each a minimum-jerk segment
        print(
            f"{summary}; wrote {len(times)} samples ({times[-1]:.2f} s at {args.rate:g} Hz) to {out}"
        )
    else:
        print(
            f"{summary} in {times[-1]:.2f} s; wrote {len(times)} samples at {args.rate:g} Hz to {out}"
        )
    _print_likeness(args, args.policy, policy)
    return 0


def _print_likeness(args: argparse.Namespace, path: Path, policy: AnyPolicy) -> None:
    """Print the policy's likeness card against each of its demonstrations (or why none)."""
    from studio.export import likeness_motions
    from studio.learning import likeness_cards

    motions = likeness_motions(path, policy, args.demo, args.data_dir)
    if not motions:
        print(
            "no likeness card: the policy was not taught from a recorded demonstration; give --demo NAME"
        )
    for motion, card in likeness_cards(policy, motions):
        if isinstance(card, str):
            print(f"no likeness card for {motion.name}: {card}", file=sys.stderr)
        else:
            print(f"likeness to {motion.name}, from the demonstration's start:\n{card.text()}")


def _motion(args: argparse.Namespace, source: Path, robot: str) -> tuple[Motion, str]:
    """The source's motion on ``robot``, and a phrase saying what it is."""
    from studio.export import check_policy_robot, source_kind
    from studio.learning import load_any_policy, policy_obstacles
    from studio.motion import Motion, demonstration_motion, recording_motion

    kind = source_kind(source)
    if kind in ("recording", "demonstration"):
        _say_retargeting(source, robot)
    margin = args.limit_margin  # the retargeting keeps it too, not only the timing and checks
    if kind == "recording":
        motion = recording_motion(source, robot, limit_margin=margin)
        return (motion.retimed(args.rate) if args.retime else motion), "recording"
    if kind == "demonstration":
        return demonstration_motion(source, robot, args.rate, margin), "demonstration"
    policy = load_any_policy(source)
    arm = check_policy_robot(source, policy.robot, robot)
    rollout, summary = _rollout(args, policy, args.seconds_per_step, arm)
    timed = args.seconds_per_step is not None
    boxes = policy_obstacles(policy)  # its task's: the export is checked against them
    motion = Motion(
        "policy", source.name, arm, rollout.times, rollout.q, timed, args.rate, obstacles=boxes
    )
    return motion, summary


def _say_loading(robot: str, cache: Path) -> None:
    """Keep ``robot``'s built geometry in the data folder's cache, as ``studio serve`` does, and
    tell a person at a terminal when its first load will build it (a minute or more), so the
    export does not look stuck. Said only to a terminal, as :func:`_say_retargeting` is."""
    from studio.kinematics import isolate_robot_loading, robot_is_kept

    isolate_robot_loading(cache)
    if robot not in robot_names() or robot_is_kept(robot) or not sys.stderr.isatty():
        return
    print(
        f"Loading the {robot_spec(robot).title}: the first time, its collision geometry is built "
        f"(a minute or more), then kept in {cache} for the next export...",
        file=sys.stderr,
        flush=True,
    )


def _say_retargeting(source: Path, robot: str) -> None:
    """Tell a person at a terminal that a human-arm motion is being retargeted onto ``robot``:
    with its IK branches planned, that takes seconds a minute of recording, and a long one
    would otherwise look stuck. Said only to a terminal, so a script's stderr still holds
    nothing but the one sentence of a refusal. A robot whose joints follow the arm's one by one
    (joint mode: the Puma560's) takes the motion at once."""
    if not sys.stderr.isatty() or robot not in robot_names() or robot_spec(robot).joint_mode:
        return
    print(
        f"Retargeting {source.name} onto the {robot_spec(robot).title}, its IK branches planned "
        "over the whole motion (seconds a minute of recording)...",
        file=sys.stderr,
        flush=True,
    )


def run(args: argparse.Namespace) -> int:
    from studio.capture import DEMO_SUFFIX, RECORDING_SUFFIXES
    from studio.export import export_motion, find_source
    from studio.learning import POLICY_SUFFIX, load_any_policy

    if args.retime and args.seconds_per_step is not None:
        raise ExportError(
            "--retime times the path within the robot's limits and --seconds-per-step sets a "
            "fixed pace; give one of them (a policy's rollout with --format is timed by default)."
        )
    legacy = args.format is None and args.robot is None and not (args.unchecked or args.retime)
    if legacy and str(args.policy).endswith(".npz"):
        return _run_legacy(args, load_any_policy(args.policy))
    source = find_source(args.policy, args.data_dir)
    fmt = args.format or "csv"
    robot = args.robot or robot_names()[0]
    _say_loading(robot, robot_cache_dir(args.data_dir))
    motion, summary = _motion(args, source, robot)
    if args.limit_margin is not None:
        try:
            motion = replace(motion, robot=motion.robot.with_limit_margin(args.limit_margin))
        except KinematicsError as err:
            raise ExportError(f"--limit-margin: {err}") from None
    stem = source.name
    for ending in (POLICY_SUFFIX, DEMO_SUFFIX, *RECORDING_SUFFIXES):
        stem = stem.removesuffix(ending)
    # by default in the current folder (a shipped sample's folder is the installed package)
    out = args.out or Path(f"{stem}.{motion.robot.name}{FORMAT_SUFFIXES[fmt]}")
    done = export_motion(
        motion,
        fmt,
        out,
        unchecked=args.unchecked,
        fraction=args.limit_fraction,
        task=args.task,
        simulate=True,
        cache=physics_cache_dir(args.data_dir),
        fastest=args.fastest,
    )
    timing = TIMINGS[done.timed_by]
    checks = (
        "passed the safety checks"
        if not done.findings
        else f"NOT safe: {len(done.findings)} finding(s) stated in the file"
    )
    print(
        f"{summary}: {len(done.times)} samples over {done.times[-1]:.2f} s for the "
        f"{motion.robot.spec.title}, {timing}, {checks}; wrote {fmt} to {out}"
    )
    for note in motion.notes:
        print(f"  note: {note}")
    for slowdown in done.slowdowns:
        print(f"  note: {slowdown.sentence}")
    if done.physics is not None:
        for line in done.physics.sentences():
            print(f"  {line}")
    for finding in done.findings:
        print(f"  {finding.sentence}", file=sys.stderr)
    if motion.kind == "policy":
        _print_likeness(args, source, load_any_policy(source))
    return 0
