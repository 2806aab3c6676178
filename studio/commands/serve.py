"""``studio serve``: start the studio (the default verb)."""

from __future__ import annotations

import argparse

NAME = "serve"
HELP = "Start the studio in the browser (the default verb)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--data-dir", default=".", help="where recordings, runs and policies live")


def run(args: argparse.Namespace) -> int:
    print("Teach Studio: the web page is not built yet. Available verbs: studio --help")
    return 0
