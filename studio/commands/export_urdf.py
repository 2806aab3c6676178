"""``studio export-urdf``: write a robot's URDF for other tools (RViz, Pinocchio, Foxglove, ...).

``studio export-urdf --robot NAME --out DIR`` writes ``DIR/<name>.urdf`` with its meshes under
``DIR/meshes/`` (relative paths: the folder loads anywhere); the :mod:`studio.export` package
does it. ``studio export-urdf [--out FILE]`` without ``--robot`` writes the Puma560's URDF alone
(primitive shapes, no meshes), to a file or to standard output, as before.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from studio import StudioError

NAME = "export-urdf"
HELP = "Write a robot's URDF: with --robot, a folder with its meshes; without, the Puma560's URDF alone."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--robot",
        help="the robot (`studio robots` lists them; puma560 carries its meshes too): --out is "
        "then a new folder for the URDF and its meshes",
    )
    parser.add_argument(
        "--out",
        "-o",
        type=Path,
        default=None,
        metavar="PATH",
        help="with --robot, the folder to create; without, the URDF file (default: standard "
        "output)",
    )


def run(args: argparse.Namespace) -> int:
    if args.robot is not None:
        from studio.export import export_urdf

        if args.out is None:
            raise StudioError(
                f"--robot {args.robot} writes a folder with meshes; give it with --out DIR."
            )
        path = export_urdf(args.robot, args.out)
        print(f"Wrote {path} and its meshes under {path.parent / 'meshes'}.", file=sys.stderr)
        return 0
    from ..kinematics import Puma560  # imported here so that `studio --help` stays fast

    text = Puma560().urdf()
    if args.out is None:
        sys.stdout.write(text)
        return 0
    out: Path = args.out
    if out.is_dir():
        raise StudioError(
            f"{out} is a folder; pass a file name such as {out / 'puma560.urdf'}, or "
            "--robot puma560 to write a folder with the meshes."
        )
    try:
        out.write_text(text, encoding="utf-8")
    except OSError as err:
        raise StudioError(
            f"cannot write {out} ({err.strerror or err}); choose a writable path with --out."
        ) from None
    print(f"Wrote the Puma560 URDF to {out}.", file=sys.stderr)
    return 0
