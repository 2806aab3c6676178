"""A real ShapeTape on a serial port (pyserial, the optional ``serial`` extra).

The source polls the tape at ``rate_hz`` with absolute deadlines (so the rate never drifts),
decodes each reply (:mod:`._shapetape_protocol`) and calibrates it into a :class:`TapeFrame`
(numbered by the tape's own frame counter when it sends one, serial numbers above 4096). A
bad checksum or a missing reply loses that frame (counted as dropped) and the stream continues; an
unplugged device ends the source with a clear ``status().error``.
"""

from __future__ import annotations

import contextlib
import os
import time
from types import ModuleType
from typing import Protocol

from ._calibration import Calibration, load_calibration
from ._errors import CaptureError
from ._frames import STATUS_BITS_MASK, TapeFrame
from ._shapetape_protocol import (
    BAUD_RATE,
    REQUEST,
    ProtocolError,
    RawFrame,
    decode_reply,
    reply_length,
)
from ._source import DEFAULT_QUEUE_FRAMES, ThreadedSource

DEFAULT_RATE_HZ = 110.0
"""Polling rate (the paper's 110 Hz)."""
REPLY_TIMEOUT_SECONDS = 0.1
"""How long to wait for one reply before counting the frame lost: a 16-region reply takes 7 ms at
115200 baud, so this only trips when the tape (or a loaded host) really stalls; the schedule's
catch-up absorbs the wait."""
COUNTER_MODULUS = 1 << 16
"""The tape's frame counter is 16 bits."""
PREFIX_BYTES = 3
"""Status byte and serial number, which tell the reply's length."""
MAX_BACKLOG_SECONDS = 0.25
"""A poll this late is caught up by polling at once (a short stall costs no frames); a longer
stall resynchronises the schedule instead of bursting requests at the tape."""
SILENT_SECONDS = 1.0
"""No valid reply for this long: the tape is off or unplugged (the source stops with an error)."""


class _Port(Protocol):
    """What the source uses of a ``serial.Serial`` port."""

    def read(self, size: int = 1) -> bytes: ...

    def write(self, data: bytes) -> int | None: ...

    def reset_input_buffer(self) -> None: ...

    def close(self) -> None: ...


def _import_serial() -> ModuleType:
    try:
        import serial
    except ImportError:
        raise CaptureError(
            'reading a ShapeTape needs pyserial; install it with `pip install -e ".[serial]"` '
            "in the studio's folder, then restart the studio."
        ) from None
    return serial


class SerialSource(ThreadedSource[TapeFrame]):
    """Frames from a ShapeTape on a serial port.

    Args:
        port: the device (``/dev/ttyUSB0``, ``COM3``, a pty path).
        calibration: a :class:`Calibration` or the path of its JSON file (default: identity).
        rate_hz: polling rate.
        baudrate: serial speed (the tape's is 115200).
        config: the tape config the frames belong to (informational).
        queue_frames: frames buffered before dropping.

    Raises:
        CaptureError: pyserial missing, bad calibration; from :meth:`start`, a port that won't open.
    """

    kind = "serial"

    def __init__(
        self,
        port: str | os.PathLike[str],
        calibration: Calibration | str | os.PathLike[str] | None = None,
        rate_hz: float = DEFAULT_RATE_HZ,
        baudrate: int = BAUD_RATE,
        config: object = None,
        queue_frames: int = DEFAULT_QUEUE_FRAMES,
    ) -> None:
        super().__init__(queue_frames)
        self._serial_module = _import_serial()
        self.port = str(port)
        self.calibration = (
            Calibration.identity() if calibration is None else load_calibration(calibration)
        )
        if not rate_hz > 0:
            raise CaptureError(f"rate_hz is {rate_hz}; give a positive polling rate.")
        self.rate_hz = float(rate_hz)
        self.baudrate = int(baudrate)
        self.config = config
        self.serial_number: int | None = None
        self._port: _Port | None = None
        self._reply_bytes: int | None = None

    def _open(self) -> None:
        serial = self._serial_module
        try:
            self._port = serial.Serial(self.port, self.baudrate, timeout=REPLY_TIMEOUT_SECONDS)
        except (serial.SerialException, OSError) as err:
            raise CaptureError(
                f"cannot open the tape on {self.port} ({err}); check the cable and the port name."
            ) from None

    def _close(self) -> None:
        if self._port is not None:
            # closing an unplugged port may fail; nothing is left to release then
            with contextlib.suppress(Exception):
                self._port.close()
            self._port = None

    def _produce(self) -> None:
        serial = self._serial_module
        port = self._port
        if port is None:  # stopped before the port opened
            return
        period = 1.0 / self.rate_hz
        start = time.monotonic()
        last_good = start
        tick = 0
        count = 0
        wraps = 0
        last_counter = -1
        try:
            while not self._stop_event.is_set():
                due = start + tick * period
                delay = due - time.monotonic()
                if delay > 0:
                    self._stop_event.wait(delay)
                tick += 1
                now = time.monotonic()
                if now - due > MAX_BACKLOG_SECONDS:  # stalled long: resynchronise, don't burst
                    skipped = int((now - start) / period) + 1 - tick
                    self._count_dropped(skipped)  # frames the tape was never asked for
                    tick += skipped
                port.write(REQUEST)
                frame = self._read_reply(port)
                if frame is None:
                    self._count_dropped()
                    port.reset_input_buffer()
                    if time.monotonic() - last_good > SILENT_SECONDS:
                        raise CaptureError(
                            f"no valid reply from the tape on {self.port} for {SILENT_SECONDS:.0f} s; check its power and cable, then restart the source."
                        )
                    continue
                last_good = time.monotonic()
                bend, twist = self.calibration.angles(frame.raw[: self.calibration.channels])
                self.serial_number = frame.serial
                if frame.counter is not None:  # the tape's own counter, unwrapped from 16 bits
                    wraps += frame.counter < last_counter
                    last_counter = frame.counter
                    number = wraps * COUNTER_MODULUS + frame.counter
                else:
                    number = count
                self._push(
                    TapeFrame(
                        last_good - start, number, bend, twist, frame.status & STATUS_BITS_MASK
                    )
                )
                count += 1
        except (serial.SerialException, OSError) as err:
            if self._stop_event.is_set():
                return
            raise CaptureError(
                f"the tape on {self.port} was disconnected ({err}); plug it back in and restart the source."
            ) from None

    def _read_reply(self, port: _Port) -> RawFrame | None:
        # one read of the whole reply once its length is known (fewer wake-ups per frame)
        data = port.read(self._reply_bytes or PREFIX_BYTES)
        if len(data) < PREFIX_BYTES:
            return None
        needed = PREFIX_BYTES + reply_length(data[0], int.from_bytes(data[1:3], "big"))
        if len(data) < needed:
            data += port.read(needed - len(data))
            if len(data) < needed:
                return None
        self._reply_bytes = needed
        try:
            frame = decode_reply(data[:PREFIX_BYTES], data[PREFIX_BYTES:needed])
        except ProtocolError as err:
            with self._lock:
                self._warning = f"dropped a frame from {self.port}: {err}."
            return None
        if frame.raw.shape[0] < self.calibration.channels:
            raise CaptureError(
                f"the tape on {self.port} sends {frame.raw.shape[0]} channels but the calibration has {self.calibration.channels}; use this tape's calibration."
            )
        return frame
