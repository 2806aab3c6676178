"""``studio simulate``: replay an exported trajectory in MuJoCo on the robot's own model.

``studio simulate FILE --robot NAME [--json]`` reads a CSV or MCAP file ``studio export`` wrote
(:func:`studio.export.read_trajectory`), replays it in physics (:func:`studio.export.simulate_trajectory`:
the robot's URDF in MuJoCo, its motors' force limits, gravity, the table it stands on) and reports
whether the motion completed, the largest joint and tool tracking errors, the samples where a motor
saturates and every contact: with the table, between links, and with each ``--obstacle``
box (``CX,CY,CZ,SX,SY,SZ``, repeatable, as ``studio train`` takes it; a contact of ``kind``
``"obstacle"`` naming ``obstacle_1``, ...). ``--json`` prints one JSON object with exactly the keys
``completed``, ``max_joint_error_rad``, ``max_tool_error_m``, ``saturated_samples`` and
``contacts``. The exit status is 0 once the motion is simulated, whatever the report says, and 2
for a bad input (a missing or malformed file, a robot it was not exported for).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ._options import add_obstacle_option

NAME = "simulate"
HELP = "Replay an exported CSV or MCAP trajectory in MuJoCo physics and report tracking, saturation and contacts."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "file", metavar="FILE", type=Path, help="a .csv or .mcap from `studio export`"
    )
    parser.add_argument(
        "--robot", required=True, help="the robot it was exported for (`studio robots` lists them)"
    )
    parser.add_argument(
        "--json", action="store_true", help="print one JSON object instead of sentences"
    )
    add_obstacle_option(parser, "in the robot's workspace, reported when the arm touches it")
    parser.add_argument(
        "--data-dir",
        type=Path,
        default=Path("."),
        help="data folder whose cache keeps each robot's built model and MuJoCo files (default: .)",
    )


def run(args: argparse.Namespace) -> int:
    # imported here so that `studio --help` stays fast (MuJoCo, Pinocchio)
    from studio._layout import physics_cache_dir, robot_cache_dir
    from studio.export import read_trajectory, simulate_trajectory
    from studio.kinematics import isolate_robot_loading, robot_spec

    robot_spec(args.robot)  # an unknown name: one sentence before the file is read
    trajectory = read_trajectory(args.file)
    isolate_robot_loading(robot_cache_dir(args.data_dir))  # built once per machine, as export's
    report = simulate_trajectory(
        args.robot,
        trajectory.times,
        trajectory.q,
        names=trajectory.names,
        cache=physics_cache_dir(args.data_dir),
        obstacles=tuple(args.obstacle or ()),
    )
    if args.json:
        print(json.dumps(report.as_json()))
    else:
        print(f"{args.file}:")
        for line in report.sentences():
            print(f"  {line}")
    return 0
