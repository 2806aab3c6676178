"""``studio bridge``: stream the simulator or a recording over UDP in the network wire format.

It plays the part of a device-side program, so the network path can be exercised end to end:
run ``studio bridge --source simulator --to 127.0.0.1:47110`` and pick the ``udp`` source.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

from studio import StudioError
from studio.capture import DEFAULT_PORT

from ._options import add_playback_options
from .serve import TOKEN_ENV

PROGRESS_SECONDS = 0.2
"""How often the progress line is redrawn."""

NAME = "bridge"
HELP = "Stream the simulator or a recording to a Teach Studio network source over UDP."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--source",
        default="simulator",
        help="simulator[:SEED] or FILE.tape.csv (default: simulator)",
    )
    parser.add_argument(
        "--to",
        default=f"127.0.0.1:{DEFAULT_PORT}",
        help=f"receiver HOST:PORT (default: 127.0.0.1:{DEFAULT_PORT})",
    )
    parser.add_argument(
        "--seconds",
        type=float,
        default=None,
        help="stop after this long (default: until the source ends or Ctrl-C)",
    )
    add_playback_options(parser)
    parser.add_argument("--loop", action="store_true", help="loop a recording")
    parser.add_argument(
        "--token",
        default=None,
        help="the receiving studio's token, to sign every frame with (needed when its bridge "
        f"listens beyond loopback; default: ${TOKEN_ENV})",
    )


def run(args: argparse.Namespace) -> int:
    # imported here, not with the flags: `studio bridge --help` and a mistyped flag stay fast
    from studio.capture import (
        check_seconds,
        cli_speed,
        parse_host_port,
        source_from_spec,
        stream_source,
    )

    host, port = parse_host_port(args.to)
    check_seconds(args.seconds)
    token = args.token if args.token is not None else os.environ.get(TOKEN_ENV) or None
    source = source_from_spec(
        args.source, seed=args.seed, speed=cli_speed(args.speed), loop=args.loop
    )
    sent = [0]
    last = [0.0]

    def progress(frames: list) -> None:
        sent[0] += len(frames)
        now = time.monotonic()
        if now - last[0] < PROGRESS_SECONDS:  # a few updates a second, not one per frame
            return
        last[0] = now
        print(f"\rsent {sent[0]} frames to {host}:{port}", end="", file=sys.stderr, flush=True)

    try:
        total = stream_source(source, host, port, args.seconds, on_frames=progress, token=token)
    except KeyboardInterrupt:
        total = sent[0]
    except StudioError:
        if sent[0]:  # end the progress line, so the error starts a line of its own
            print(file=sys.stderr)
        raise
    print(f"\nsent {total} frames to {host}:{port}.", file=sys.stderr)
    return 0
