"""``studio record``: capture a source into a crash-safe recording, with progress.

Ctrl-C ends the capture early and keeps every frame captured so far (the file is closed cleanly).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from studio import StudioError
from studio.capture import SOURCE_SPECS

if TYPE_CHECKING:
    from studio.capture import SourceStatus

from ._options import add_playback_options
from .serve import TOKEN_ENV

PROGRESS_SECONDS = 0.2
"""How often the progress line is redrawn."""
WAIT_SECONDS = 10.0
"""``--wait``'s default: how long a capture waits for a frame before it gives up."""
NAME = "record"
HELP = "Record a source (simulator, recording, UDP or serial) into a recording file."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--source", default="simulator", help=f"{SOURCE_SPECS} (default: simulator)"
    )
    parser.add_argument(
        "--seconds",
        type=float,
        default=None,
        help="seconds of frames to record, by their time stamps from the first frame on (waiting "
        "for a first frame does not count; default: until Ctrl-C or the source ends)",
    )
    parser.add_argument(
        "--wait",
        type=float,
        default=WAIT_SECONDS,
        help=f"give up when no frame arrives for this many seconds, e.g. a network sender that "
        f"never starts (default: {WAIT_SECONDS:g}; the first frame is waited for at least "
        "30 s, so a sender started at the same time has time to start)",
    )
    parser.add_argument(
        "--token",
        default=None,
        help=f"for udp:HOST:PORT beyond loopback: take only frames signed with this token "
        f"(studio bridge --token; default: ${TOKEN_ENV})",
    )
    parser.add_argument(
        "--out", type=Path, required=True, help="the new recording, e.g. recordings/x.tape.csv"
    )
    add_playback_options(parser)
    parser.add_argument("--calibration", type=Path, help="calibration JSON for serial:PORT")
    parser.add_argument("--operator", default="", help="who wore the tape")
    parser.add_argument("--notes", default="", help="free text stored in the header")


def run(args: argparse.Namespace) -> int:
    # imported here, not with the flags: `studio record --help` and a mistyped flag stay fast
    from studio.capture import (
        DEFAULT_RATE_HZ,
        capture,
        check_seconds,
        cli_speed,
        describe,
        recording_path,
        source_from_spec,
        summarize_any_recording,
    )

    check_seconds(args.seconds)
    check_seconds(args.wait, "--wait")
    token = args.token if args.token is not None else os.environ.get(TOKEN_ENV) or None
    source = source_from_spec(
        args.source,
        seed=args.seed,
        speed=cli_speed(args.speed),
        calibration=args.calibration,
        **({"token": token} if args.source.startswith("udp") else {}),
    )
    out = recording_path(args.out, getattr(source, "observation_kind", "tape"))
    if out != args.out:
        print(f"recording into {out}: a name every other verb takes", file=sys.stderr)
    total = f"/{args.seconds:g} s" if args.seconds else ""
    nominal = float(getattr(source, "rate_hz", 0.0) or DEFAULT_RATE_HZ)

    last = [0.0]

    def progress(frames: int, status: SourceStatus) -> None:
        now = time.monotonic()
        if now - last[0] < PROGRESS_SECONDS:
            return
        last[0] = now
        note = f"  ({status.error})" if status.error else ""
        print(
            f"\rrecording {frames} frames ({frames / nominal:.1f} s{total}) "
            f"{status.rate_hz:6.1f} Hz, dropped {status.dropped}{note}",
            end="",
            file=sys.stderr,
            flush=True,
        )

    try:
        path = capture(
            source,
            out,
            args.seconds,
            operator=args.operator,
            notes=args.notes,
            source_name=args.source,
            on_progress=progress,
            give_up_seconds=args.wait,
        )
    except KeyboardInterrupt:
        print(f"\nstopped: every captured frame is kept in {out}.", file=sys.stderr)
        path = out
    except StudioError:
        if last[0]:  # end the progress line, so the error starts a line of its own
            print(file=sys.stderr)
        raise
    print(file=sys.stderr)
    print(describe(summarize_any_recording(path)))
    return 0
