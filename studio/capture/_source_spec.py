"""Build a source from a short text spec: the one factory of sources, for the CLI and the page.

Specs: ``simulator`` (or ``simulator:SEED``), a recording path (``*.tape.csv``, played back),
``udp`` / ``udp:PORT`` / ``udp:HOST:PORT`` (a :class:`NetworkSource`), ``serial:PORT`` (a
:class:`SerialSource`, with ``calibration``), and for a caller that feeds them (the studio's
page) ``camera[:SIDE]`` and ``hand[:SIDE]`` (a :class:`CameraSource`, a :class:`HandSource`).
"""

from __future__ import annotations

import os
from pathlib import Path

from ._errors import CaptureError
from ._source import ThreadedSource
from ._wire import DEFAULT_PORT

SOURCE_SPECS = (
    "simulator[:SEED] | FILE.tape.csv|.pose.csv|.hand.csv | udp[:[HOST:]PORT] | serial:PORT"
)
"""What :func:`source_from_spec` accepts (for help texts)."""
FED_KINDS = ("camera", "hand")
"""Sources whose observations are handed in by calls (the page's camera and hand guide)."""
MAX_PORT = 65535
"""The largest UDP port number."""


def source_from_spec(
    spec: str,
    *,
    seed: int = 0,
    speed: float | None = 1.0,
    loop: bool = False,
    calibration: str | os.PathLike[str] | None = None,
    token: str | None = None,
    fed: bool = False,
) -> ThreadedSource:
    """The source a spec names (not started).

    Args:
        spec: see the module docstring.
        seed: simulator seed (when the spec gives none).
        speed: playback speed (``None``: as fast as possible).
        loop: playback loops.
        calibration: serial calibration file.
        token: the network bridge's token: only frames signed with it are taken.
        fed: the caller hands observations in (``camera``, ``hand``); a command line cannot.

    Raises:
        CaptureError: an unknown spec (the message lists the valid ones), a fed source for a
            caller that cannot feed it, a bad side.
    """
    kind, _, rest = spec.partition(":")
    if kind == "simulator":
        from ._simulator import SimulatorSource

        return SimulatorSource(seed=int(rest) if rest else seed)
    if kind in FED_KINDS:
        if not fed:
            raise CaptureError(
                f"The {kind} source is fed by the studio's page; choose it there, or give one of {SOURCE_SPECS}."
            )
        from ._push_sources import CameraSource, HandSource

        return (CameraSource if kind == "camera" else HandSource)(rest or "right")
    if kind == "udp":
        host, port = "127.0.0.1", DEFAULT_PORT
        if rest:
            host_part, _, port_part = rest.rpartition(":")
            host = host_part or host
            try:
                port = int(port_part)
            except ValueError:
                port = -1
            if not 0 <= port <= MAX_PORT:
                raise CaptureError(
                    f"'{spec}' has no valid port; write udp:PORT or udp:HOST:PORT with a port from 0 to {MAX_PORT}."
                )
        from ._network import NetworkSource

        return NetworkSource(host, port, token=token)
    if kind == "serial":
        if not rest:
            raise CaptureError("'serial' needs a port; write serial:/dev/ttyUSB0.")
        from ._serial import SerialSource

        return SerialSource(rest, calibration=calibration)
    if Path(spec).is_file():
        from ._playback import PlaybackSource

        return PlaybackSource(spec, speed=speed, loop=loop)
    raise CaptureError(
        f"'{spec}' is neither a source nor an existing recording; give one of {SOURCE_SPECS}."
    )


def parse_host_port(text: str, default_port: int = DEFAULT_PORT) -> tuple[str, int]:
    """``HOST:PORT`` (or ``HOST``, or ``:PORT``) as a tuple.

    Raises:
        CaptureError: the port is not a number from 1 to 65535.
    """
    host, sep, port = text.rpartition(":")
    if not sep:
        return text or "127.0.0.1", default_port
    try:
        number = int(port)
    except ValueError:
        number = 0
    if not 1 <= number <= MAX_PORT:
        raise CaptureError(
            f"'{text}' has no valid port; write HOST:PORT with a port from 1 to {MAX_PORT}, e.g. 127.0.0.1:{default_port}."
        )
    return host or "127.0.0.1", number


def cli_speed(speed: float) -> float | None:
    """A ``--speed`` option as :class:`PlaybackSource` takes it: 0 means as fast as possible.

    Raises:
        CaptureError: a negative or non-finite speed.
    """
    if speed == 0:
        return None
    if not 0 < speed < float("inf"):
        raise CaptureError(
            f"--speed is {speed:g}; give a positive speed (2 is twice real time), or 0 for as fast as possible."
        )
    return speed
