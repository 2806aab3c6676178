"""``studio robots``: the robots the studio can teach, with their joints and limits."""

from __future__ import annotations

import argparse
import json
import math

NAME = "robots"
HELP = "List the robots the studio can teach (--robot NAME elsewhere), with joints and limits."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--json", action="store_true", help="print the list as JSON (for scripts) instead of text"
    )


def run(args: argparse.Namespace) -> int:
    from ..kinematics import load_robot, robot_names  # imported here so `studio --help` stays fast

    robots = []
    for name in robot_names():
        arm = load_robot(name, geometry=False)
        joints = [
            {
                "name": joint,
                "lower_deg": round(math.degrees(lo), 1),
                "upper_deg": round(math.degrees(hi), 1),
                "velocity_deg_s": round(math.degrees(v), 1),
            }
            for joint, lo, hi, v in zip(
                arm.joint_names, arm.hard_lower, arm.hard_upper, arm.velocity, strict=True
            )
        ]
        margin = round(float(arm.limit_margin.max()), 3)
        robots.append(
            {"name": name, "title": arm.spec.title, "joints": joints, "limit_margin_rad": margin}
        )
    if args.json:
        print(json.dumps(robots, indent=1))
        return 0
    for i, robot in enumerate(robots):
        default = "  (default)" if i == 0 else ""
        print(
            f"{robot['name']}: {robot['title']}, {len(robot['joints'])} joints{default}; "
            f"plans keep {robot['limit_margin_rad']:g} rad from each hard limit"
        )
        for joint in robot["joints"]:
            print(
                f"  {joint['name']:<22} {joint['lower_deg']:>7.1f} .. {joint['upper_deg']:>6.1f} deg"
                f"  up to {joint['velocity_deg_s']:.0f} deg/s"
            )
    return 0
