"""``studio info``: what a recording (``*.tape.csv``, ``*.pose.csv``, ``*.hand.csv``) or a
demonstration (``*.demo.json``) holds."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

NAME = "info"
HELP = "Show a recording's or demonstration's metadata, length and any problems."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "files",
        type=Path,
        nargs="+",
        metavar="FILE",
        help="*.tape.csv, *.pose.csv, *.hand.csv or *.demo.json files, or their names in the "
        "data folder's recordings/ or among the samples (sample-reach-1, "
        "sample-reach-1.tape.csv)",
    )
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")
    parser.add_argument(
        "--lenient",
        action="store_true",
        help="list a damaged recording's problems instead of stopping at the first",
    )


def run(args: argparse.Namespace) -> int:
    # imported here, not with the flags: `studio info --help` and a mistyped flag stay fast
    from studio.capture import being_recorded, describe, summarize_any_recording

    for given in args.files:
        path = _file(given)
        if path.name.endswith(".demo.json"):
            from studio.motion import checked_demonstration

            demo = checked_demonstration(path).summary()
            shown = {k: _shown(k, v) for k, v in demo.items()}
            text = "\n".join([str(path), *(f"  {k:<13} {v}" for k, v in shown.items())])
            print(json.dumps(demo) if args.json else text)
        else:
            # streamed: memory stays one block however long (or damaged) the file is
            summary = summarize_any_recording(path, strict=not args.lenient)
            # a file still being captured has no '# end' line yet, but it was not interrupted
            summary["live"] = summary["recovered"] and being_recorded(path)
            if summary["live"]:
                summary["recovered"] = False
            print(json.dumps(summary) if args.json else describe(summary))
    return 0


def _file(given: Path) -> Path:
    """The recording or demonstration ``given`` names: a path, or a name as ``studio export`` and
    ``studio train --demos`` take it (the data folder's, then the samples')."""
    from studio.capture import RECORDING_SUFFIXES
    from studio.export import ExportError, find_source

    if given.exists():
        return given
    path = find_source(given)
    if not path.name.endswith((".demo.json", *RECORDING_SUFFIXES)):
        raise ExportError(
            f"{given} names {path}, which is not a recording or a demonstration; studio info "
            "shows those (give a *.tape.csv, *.pose.csv, *.hand.csv or *.demo.json)."
        )
    return path


def _shown(key: str, value: object) -> object:
    """A demonstration's summary field as text: times in seconds to the millisecond, the fit's
    residual in millimetres (``--json`` keeps the exact values)."""
    if key == "segment" and isinstance(value, list) and len(value) == 2:
        return f"{value[0]:.3f} s to {value[1]:.3f} s ({value[1] - value[0]:.3f} s)"
    if key == "reached_at" and isinstance(value, float):
        return f"{value:.3f} s"
    if key == "residual_max" and isinstance(value, float):
        return f"{value * 1000:.1f} mm"
    return value
