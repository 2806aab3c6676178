"""Build a source from a short text spec and record it into a file: the one factory of sources
(for the CLI and the page) and the loop behind ``studio record`` (and any scripted capture).

Specs: ``simulator`` (or ``simulator:SEED``), a recording path (``*.tape.csv``, played back),
``udp`` / ``udp:PORT`` / ``udp:HOST:PORT`` (a :class:`NetworkSource`), ``serial:PORT`` (a
:class:`SerialSource`, with ``calibration``), and for a caller that feeds them (the studio's
page) ``camera[:SIDE]`` and ``hand[:SIDE]`` (a :class:`CameraSource`, a :class:`HandSource`).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path

from studio import StudioError

from ._errors import CaptureError
from ._observation_recording import ObservationWriter
from ._recording_format import (
    DEFAULT_RATE_HZ,
    DEFAULT_REGIONS,
    RecordingSummary,
    recording_path,
)
from ._recording_writer import AppendWriter, RecordingWriter
from ._source import SourceStatus, ThreadedSource, check_seconds
from ._source_specs import DEFAULT_PORT, SOURCE_SPECS

FED_KINDS = ("camera", "hand")
"""Sources whose observations are handed in by calls (the page's camera and hand guide)."""
MAX_PORT = 65535
"""The largest UDP port number."""


FIRST_FRAME_SECONDS = 30.0
"""The least a capture waits for its first frame, whatever ``give_up_seconds`` says: a sender
started at the same moment (``studio bridge`` beside ``studio record --source udp``) takes
seconds to start on a busy machine, and the recorder used to give up on it after 10 s."""


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


READ_TIMEOUT_SECONDS = 0.1
"""How long one read waits for frames (bounds how late a stop request is seen)."""


def capture(
    source: ThreadedSource,
    out: str | os.PathLike[str],
    seconds: float | None = None,
    *,
    operator: str = "",
    notes: str = "",
    source_name: str | None = None,
    on_progress: Callable[[int, SourceStatus], None] | None = None,
    stop: Callable[[], bool] | None = None,
    give_up_seconds: float | None = None,
) -> Path:
    """Record ``source`` into a new recording until ``seconds`` of frames, its end, or ``stop()``.

    The file is closed (``# end`` line) whatever ends the capture, including Ctrl-C
    (``KeyboardInterrupt`` is re-raised after the file is safe), so nothing captured is lost.

    Args:
        source: an unstarted source (started and stopped here).
        out: the new ``*.tape.csv`` file (``*.pose.csv``, ``*.hand.csv`` for a source of
            landmarks or hand poses).
        seconds: the duration of frames to record, by the frames' own time stamps from the first
            frame on; waiting for a first frame does not count (``None``: until the source ends
            or ``stop()``).
        operator: who wore the tape.
        notes: free text.
        source_name: stored in the header (default: the source's kind).
        on_progress: called with ``(frames written, source status)`` after each batch.
        stop: polled after each batch; true ends the capture.
        give_up_seconds: end with an error when no frame arrives for this long (a network
            sender that never starts or went away); the first frame is waited for at least
            :data:`FIRST_FRAME_SECONDS`. A capture that fails before its first frame
            leaves no file.

    Returns:
        The recording's path.

    Raises:
        CaptureError: the source failed or went silent for ``give_up_seconds`` (the frames up to
            then are kept in the file), or a bad ``seconds``.
    """
    check_seconds(seconds)
    check_seconds(give_up_seconds, "the wait for frames")
    rate = float(getattr(source, "rate_hz", DEFAULT_RATE_HZ) or DEFAULT_RATE_HZ)
    writer = _writer_for(source, out, rate, operator, notes, source_name or source.kind)
    first_t: float | None = None
    failed = False

    def kept() -> str:
        return (
            f"{writer.frames} frames kept in {writer.path}"
            if writer.frames
            else "nothing was recorded"
        )

    try:
        source.start()
        last_frame = time.monotonic()
        while True:
            frames = source.read(timeout=READ_TIMEOUT_SECONDS)
            if frames:
                last_frame = time.monotonic()
                if first_t is None:
                    first_t = frames[0].t
                if seconds is not None:
                    frames = [f for f in frames if f.t - first_t < seconds - 0.5 / rate]
                writer.write_many(frames)
            status = source.status()
            if on_progress is not None:
                on_progress(writer.frames, status)
            if status.error and not status.running:  # a running source may recover (network)
                raise CaptureError(f"{status.error} ({kept()})")
            quiet = time.monotonic() - last_frame
            limit = give_up_seconds
            if limit is not None and first_t is None:  # a sender started beside us may be slow
                limit = max(limit, FIRST_FRAME_SECONDS)
            if limit is not None and quiet >= limit:
                raise CaptureError(
                    f"no frame arrived from the {source.kind} source for {quiet:.0f} s, so the capture gave up ({kept()}); start the sender first (for the network bridge: studio bridge --to HOST:PORT)."
                )
            if (
                seconds is not None
                and first_t is not None
                and writer.frames >= round(seconds * rate)
            ):
                break
            if not frames and not status.running:
                break
            if stop is not None and stop():
                break
    except StudioError:
        failed = True
        raise
    finally:
        source.stop()
        writer.close()
        if failed and writer.frames == 0:  # a capture that got no frame leaves no empty file
            writer.path.unlink(missing_ok=True)
    return writer.path


def _writer_for(
    source: ThreadedSource,
    out: str | os.PathLike[str],
    rate: float,
    operator: str,
    notes: str,
    source_name: str,
) -> AppendWriter:
    """A new recording of ``source``'s observation kind at ``out``: a tape's with its config and
    regions, or a pose or hand recording (played back, or any fed source) of the same kind."""
    kind = getattr(source, "observation_kind", "tape")
    out = recording_path(out, kind)
    if kind == "tape":
        config = getattr(source, "config", None)
        regions = int(getattr(config, "regions", DEFAULT_REGIONS) or DEFAULT_REGIONS)
        return RecordingWriter(
            out,
            regions,
            config=config,
            operator=operator,
            notes=notes,
            rate_hz=rate,
            source=source_name,
        )
    side = str(getattr(source, "side", "right"))
    return ObservationWriter(
        out, kind, side=side, operator=operator, notes=notes, source=source_name
    )


def describe(summary: RecordingSummary) -> str:
    """A few human lines about a recording summary (for ``studio info``)."""
    lines = [
        f"{summary['path']}",
        f"  name      {summary['name']}",
        f"  frames    {summary['frames']} ({summary['duration']:.2f} s at {summary['rate_hz']:g} Hz, {_what(summary)})",
        f"  source    {summary['source']}",
        f"  operator  {summary['operator'] or '-'}",
        f"  created   {summary['created']}",
        f"  recovered {_recovered_text(summary)}",
    ]
    if summary["notes"]:
        lines.append(f"  notes     {summary['notes']}")
    for problem in summary["problems"]:
        lines.append(f"  problem   {problem}")
    for warning in summary.get("warnings", []):
        lines.append(f"  warning   {warning}")
    return "\n".join(lines)


def _what(summary: RecordingSummary) -> str:
    """What each frame holds, by the recording's kind."""
    kind = summary.get("kind", "tape")
    if kind == "pose":
        return "pose landmarks from a camera, no images"
    if kind == "hand":
        return "hand-guide poses"
    return f"{summary['regions']} regions"


def _recovered_text(summary: RecordingSummary) -> str:
    if summary.get("live"):
        return "no (still being recorded: the frames flushed so far are shown)"
    if summary["recovered"]:
        return "yes (the capture was interrupted; every flushed frame is here)"
    return "no"
