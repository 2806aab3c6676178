"""``studio import-raw``: turn Measurand's raw text (``frame time raw0 ... rawN``) into a recording."""

from __future__ import annotations

import argparse
from pathlib import Path

NAME = "import-raw"
HELP = "Import a Measurand raw text file with a calibration JSON into a *.tape.csv recording."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "raw", type=Path, metavar="RAW", help="raw text file: frame time raw0 ... rawN per line"
    )
    parser.add_argument(
        "--calibration",
        type=Path,
        required=True,
        help="calibration JSON (offsets and gains per channel)",
    )
    parser.add_argument("--out", type=Path, required=True, help="the new recording (*.tape.csv)")
    parser.add_argument("--operator", default="", help="who wore the tape")
    parser.add_argument("--notes", default="", help="free text stored in the header")


def run(args: argparse.Namespace) -> int:
    from studio.capture import describe, import_raw, read_recording  # here: --help stays fast

    path = import_raw(
        args.raw, args.calibration, args.out, operator=args.operator, notes=args.notes
    )
    print(describe(read_recording(path).summary()))
    return 0
