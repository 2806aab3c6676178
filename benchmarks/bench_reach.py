"""A person's reach on every robot: frames beyond reach, the tool's path against the hand's, the
exported timing, rest, limit margin and (optionally) physics.

For each robot the studio offers (the Puma560, which maps joint to joint, aside) and each
motion - the three sample demonstrations (their recordings' segments) and a simulator minute
(``arm_motion``, 60 s at 30 Hz) - the operator's arm is retargeted as an export retargets it
(``studio.kinematics.retarget_path``; its hand targets placed by ``Retargeter``'s workspace
map, the one every live, cut, played-back and exported motion uses) and exported as the CLI does
(``studio.export.export_motion``, at the person's pace by default). Per robot, over the motions:

- ``beyond %``: frames whose hand target was drawn back into the robot's reach by more than
  ``RetargetConfig.reach_tolerance`` (the export's "the hand went beyond the robot's reach");
- ``reached %``: frames whose tool is on the hand's target (1 cm and 5 deg);
- ``DTW cm``: the tool's path against the mapped hand path (``studio.learning.dtw_distance``, per
  aligned sample), and the largest over the motions;
- ``duration x``: the export's duration over the person's, smallest and largest;
- ``rest``: the largest joint speed at the first and last samples (rad/s);
- ``margin``: the closest any joint comes to its hard (URDF) limit (rad; plans keep
  ``LIMIT_MARGIN_RAD``);
- with ``--physics``: ``studio.export.simulate_motion`` (MuJoCo) completed on every motion, the
  largest tool error (mm), saturated samples and contacts.

    python benchmarks/bench_reach.py [--robots panda ur5 ...] [--no-minute] [--physics]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from studio.capture import human_angles, read_any_recording
from studio.export import Motion, export_motion
from studio.kinematics import (
    HumanArm,
    RetargetConfig,
    Retargeter,
    arm_motion,
    load_robot,
    retarget_path,
    robot_names,
)
from studio.learning import dtw_distance
from studio.motion import checked_demonstration
from studio.samples import SAMPLES_DIR

MINUTE_RATE_HZ = 30.0


def motions() -> list[tuple[str, np.ndarray, np.ndarray, str]]:
    """(name, times, q_human, side) of the three samples and a simulator minute."""
    out = []
    for k in (1, 2, 3):
        demo = checked_demonstration(SAMPLES_DIR / f"sample-reach-{k}.demo.json")
        rec = read_any_recording(demo.recording)
        rows = rec.segment(demo.t0, demo.t1)
        out.append(
            (f"sample-reach-{k}", rec.t[rows] - rec.t[rows][0], human_angles(rec, rows), rec.side)
        )
    return out


def minute(seconds: float) -> tuple[str, np.ndarray, np.ndarray, str]:
    times = np.arange(0.0, seconds, 1.0 / MINUTE_RATE_HZ)
    return "simulator minute", times, arm_motion(times, HumanArm()), "right"


def measure(name: str, motion, physics: bool, folder: Path) -> dict:
    label, times, q_human, side = motion
    robot = load_robot(name).scratch_copy()
    config = RetargetConfig()
    path = retarget_path(robot, q_human, config, side=side)
    retargeter = Retargeter(robot=robot.scratch_copy(), arm=HumanArm(side=side))
    hand = np.array([retargeter.hand_target(q)[:3, 3] for q in q_human])
    tool = np.array([robot.forward(q)[:3, 3] for q in path.q])
    figures = {
        "beyond": float(np.mean(path.pulled_in > config.reach_tolerance)),
        "reached": float(np.mean(path.reached)),
        "dtw": dtw_distance(tool, hand),
    }
    motion_ = Motion("demonstration", label, robot, np.asarray(times, float), path.q, False, 50.0)
    done = export_motion(
        motion_, "csv", folder / f"{name}.csv", unchecked=True, simulate=physics, cache=folder
    )
    speed = np.abs(np.diff(done.q, axis=0)) / np.diff(done.times)[:, None]
    figures["duration"] = float(done.times[-1] / times[-1])
    figures["rest"] = float(max(speed[0].max(), speed[-1].max()))
    hard = (robot.hard_lower, robot.hard_upper)
    figures["margin"] = float(min((done.q - hard[0]).min(), (hard[1] - done.q).min()))
    figures["findings"] = len(done.findings)
    if done.physics is not None:
        report = done.physics
        figures["completed"] = report.completed
        figures["tool_mm"] = report.max_tool_error_m * 1000
        figures["saturated"] = report.saturated_samples
        figures["contacts"] = len(report.contacts)
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", nargs="*", default=[n for n in robot_names() if n != "puma560"])
    parser.add_argument("--no-minute", action="store_true", help="the three samples only")
    parser.add_argument("--seconds", type=float, default=60.0, help="the simulator's motion (s)")
    parser.add_argument("--physics", action="store_true", help="replay each export in MuJoCo")
    args = parser.parse_args()
    chosen = motions() + ([] if args.no_minute else [minute(args.seconds)])
    head = ("| robot | beyond % (worst) | reached % | DTW cm (worst) | duration x | rest rad/s "
            "| margin rad | findings |")  # fmt: skip
    rule = "|---|---|---|---|---|---|---|---|"
    if args.physics:
        head += " physics: completed, tool mm, saturated, contacts |"
        rule += "---|"
    print(f"motions: {', '.join(m[0] for m in chosen)}")
    print(head)
    print(rule)
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.robots:
            rows = [measure(name, m, args.physics, Path(tmp)) for m in chosen]
            total = sum(len(m[2]) for m in chosen)
            beyond = sum(r["beyond"] * len(m[2]) for r, m in zip(rows, chosen, strict=True))
            reached = sum(r["reached"] * len(m[2]) for r, m in zip(rows, chosen, strict=True))
            line = (
                f"| {name} | {100 * beyond / total:.1f} ({100 * max(r['beyond'] for r in rows):.1f})"
                f" | {100 * reached / total:.1f}"
                f" | {100 * np.mean([r['dtw'] for r in rows]):.1f} ({100 * max(r['dtw'] for r in rows):.1f})"
                f" | {min(r['duration'] for r in rows):.2f}-{max(r['duration'] for r in rows):.2f}"
                f" | {max(r['rest'] for r in rows):.3f} | {min(r['margin'] for r in rows):.3f}"
                f" | {sum(r['findings'] for r in rows)} |"
            )
            if args.physics:
                line += (
                    f" {sum(r['completed'] for r in rows)}/{len(rows)},"
                    f" {max(r['tool_mm'] for r in rows):.1f}, {sum(r['saturated'] for r in rows)},"
                    f" {sum(r['contacts'] for r in rows)} |"
                )
            print(line, flush=True)


if __name__ == "__main__":
    main()
