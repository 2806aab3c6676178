"""Options that several verbs share, defined once so their names, defaults and help agree."""

from __future__ import annotations

import argparse


def add_playback_options(parser: argparse.ArgumentParser) -> None:
    """``--seed`` (the simulator's) and ``--speed`` (a recording's playback), as ``--source``
    takes them."""
    parser.add_argument("--seed", type=int, default=0, help="simulator seed (default: 0)")
    parser.add_argument(
        "--speed",
        type=float,
        default=1.0,
        help="playback speed for a recording source: 1 real time, 2 twice as fast, "
        "0 as fast as possible (default: 1)",
    )


def _obstacle(text: str) -> object:
    """``--obstacle``'s value as a box, or argparse's one-line refusal."""
    from studio.kinematics import KinematicsError, Obstacle

    try:
        return Obstacle.parse(text)
    except KinematicsError as err:
        raise argparse.ArgumentTypeError(str(err).rstrip(".")) from None


def add_obstacle_option(parser: argparse.ArgumentParser, what: str) -> None:
    """``--obstacle CX,CY,CZ,SX,SY,SZ``, repeatable: a box in the robot's base frame."""
    parser.add_argument(
        "--obstacle",
        type=_obstacle,
        action="append",
        metavar="CX,CY,CZ,SX,SY,SZ",
        help=f"a box {what}, centre and full sizes in metres in the robot's base frame "
        "(e.g. 0.56,0.18,1.08,0.12,0.12,0.12); repeatable",
    )
