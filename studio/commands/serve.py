"""``studio serve``: start the studio in the browser (the default verb)."""

from __future__ import annotations

import argparse
import os
import secrets
import sys
from pathlib import Path

from studio import StudioError

NAME = "serve"
HELP = "Start the studio in the browser (the default verb)."
MAX_PORT = 65535
TOKEN_BYTES = 24
"""Random bytes of a generated token (32 URL-safe characters)."""
TOKEN_ENV = "STUDIO_TOKEN"
"""Environment variable holding the token, so that it stays out of the process list."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data-dir", type=Path, default=Path("."), help="where recordings, runs and policies live"
    )
    parser.add_argument("--host", default="127.0.0.1", help="address to bind (default: loopback)")
    parser.add_argument("--port", type=int, default=8000, help="port of the page and API")
    parser.add_argument("--viser-port", type=int, default=8080, help="port of the 3D scene")
    parser.add_argument(
        "--source",
        default="simulator",
        help="live source at start: simulator (default) or the name/path of a recording",
    )
    parser.add_argument(
        "--allow-host",
        action="append",
        default=[],
        metavar="NAME",
        help="also accept this Host name (when serving beyond loopback); repeatable",
    )
    parser.add_argument(
        "--upload-limit-mb",
        type=float,
        default=None,
        metavar="MB",
        help="largest recording or policy upload, in MB (default: 50)",
    )
    parser.add_argument(
        "--token",
        default=None,
        help=f"the secret the page, API and scene require (default: ${TOKEN_ENV}; generated and "
        "printed when --host is not loopback, where one is required)",
    )
    parser.add_argument(
        "--bridge-host",
        default="127.0.0.1",
        help="address the network-bridge source listens on (default: loopback); beyond loopback "
        "it takes only frames signed with the token (studio bridge --token)",
    )
    parser.add_argument("--no-browser", action="store_true", help="do not open a browser")


def run(args: argparse.Namespace) -> int:
    from studio.web import DEFAULT_UPLOAD_LIMIT_BYTES, Settings, is_loopback, serve

    source = args.source
    data_dir: Path = args.data_dir
    if source != "simulator" and not Path(source).is_file():
        by_name = data_dir / "recordings" / f"{source}.tape.csv"
        if not by_name.is_file():
            raise StudioError(
                f"--source {source} is neither 'simulator', a recording file nor a recording in {by_name.parent}; check the name."
            )
    token = args.token if args.token is not None else os.environ.get(TOKEN_ENV) or None
    if not is_loopback(args.host):
        print(
            f"studio serve: WARNING: binding {args.host} makes the studio reachable from other "
            "machines: it answers only requests carrying its token (an SSH tunnel to a loopback "
            "studio is safer still; see docs/remote.md).",
            file=sys.stderr,
        )
    opened = not is_loopback(args.host) or not is_loopback(args.bridge_host)
    if opened and token is None:
        token = secrets.token_urlsafe(TOKEN_BYTES)
    allowed = list(args.allow_host)
    if not is_loopback(args.host):
        import socket

        allowed += [socket.gethostname(), socket.getfqdn()]
    limit_mb = (
        args.upload_limit_mb
        if args.upload_limit_mb is not None
        else DEFAULT_UPLOAD_LIMIT_BYTES / 1e6
    )
    if not limit_mb > 0:
        raise StudioError(f"--upload-limit-mb is {limit_mb}; give a positive size in MB.")
    for flag, port in (("--port", args.port), ("--viser-port", args.viser_port)):
        if not 1 <= port <= MAX_PORT:
            raise StudioError(f"{flag} {port} is not a port number; give one from 1 to {MAX_PORT}.")
    settings = Settings(
        upload_limit_bytes=round(limit_mb * 1e6),
        data_dir=data_dir,
        host=args.host,
        port=args.port,
        viser_port=args.viser_port,
        source=source,
        allowed_hosts=tuple(allowed),
        token=token,
        bridge_host=args.bridge_host,
    )
    serve(settings, open_browser=not args.no_browser)
    return 0
