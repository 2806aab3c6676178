"""``studio export-urdf``: write the Puma560 as a URDF for other tools (RViz, Pinocchio, ...)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from studio import StudioError

NAME = "export-urdf"
HELP = "Write a URDF of the Puma560 (joints, limits, visuals) to a file or to standard output."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--out",
        "-o",
        type=Path,
        default=None,
        metavar="FILE",
        help="where to write the URDF (default: standard output)",
    )


def run(args: argparse.Namespace) -> int:
    from ..kinematics import Puma560  # imported here so that `studio --help` stays fast

    text = Puma560().urdf()
    if args.out is None:
        sys.stdout.write(text)
        return 0
    out: Path = args.out
    if out.is_dir():
        raise StudioError(f"{out} is a folder; pass a file name such as {out / 'puma560.urdf'}.")
    try:
        out.write_text(text, encoding="utf-8")
    except OSError as err:
        raise StudioError(
            f"cannot write {out} ({err.strerror or err}); choose a writable path with --out."
        ) from None
    print(f"Wrote the Puma560 URDF to {out}.", file=sys.stderr)
    return 0
