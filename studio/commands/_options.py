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
