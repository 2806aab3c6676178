"""A ShapeTape on a serial port: its protocol, the source that reads it (pyserial, the optional
``serial`` extra) and an emulated tape on a pseudo-terminal (for tests and demos).

The ShapeTape serial protocol (Measurand tapeAPI, 2000). The host sends ``0x20``; the tape
answers with one frame::

    status      1 byte   bits 0-2: number of 8-channel groups G; bit 4 switch0, 5 trigger, 6 switch1
    serial      2 bytes  big-endian serial number
    [if serial > 4096:  counter 2 bytes BE, timer 3 bytes BE, filler 8 bytes]
    data        16 * G   8 x uint16 big-endian per group
    checksum    1 byte   sum of the data bytes, modulo 256

:class:`SerialSource` polls the tape at ``rate_hz`` with absolute deadlines (so the rate never
drifts), decodes each reply and calibrates it into a :class:`TapeFrame` (numbered by the tape's
own frame counter when it sends one, serial numbers above 4096). A bad checksum or a missing
reply loses that frame (counted as dropped) and the stream continues; an unplugged device ends
the source with a clear ``status().error``.

:class:`ShapeTapeEmulator` answers every ``0x20`` with a frame built from a frame generator, can
corrupt chosen replies' checksums, and can be "unplugged" (its pty closed) mid-stream.
"""

from __future__ import annotations

import contextlib
import os
import select
import threading
import time
import tty
from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType
from typing import Protocol

import numpy as np

from ._calibration import Calibration, load_calibration
from ._errors import CaptureError
from ._observations import STATUS_BITS_MASK, TapeFrame
from ._recording_format import DEFAULT_RATE_HZ  # polling rate: the paper's tape rate
from ._source import DEFAULT_QUEUE_FRAMES, ThreadedSource

REQUEST = b"\x20"
"""The byte that asks the tape for one frame."""
BAUD_RATE = 115200
"""The tape's serial speed."""
GROUP_MASK = 0x07
"""Status bits holding the group count."""
CHANNELS_PER_GROUP = 8
"""uint16 channels per group."""
GROUP_BYTES = 2 * CHANNELS_PER_GROUP
"""Bytes per group."""
EXTENDED_SERIAL = 4096
"""Tapes with a larger serial number send a counter, a timer and filler."""
EXTENDED_BYTES = 2 + 3 + 8
"""Counter, timer and filler bytes of extended frames."""


class ProtocolError(ValueError):
    """A frame that does not decode (bad checksum, wrong length)."""


@dataclass(frozen=True, eq=False)
class RawFrame:
    """One decoded reply: status byte, serial, optional counter/timer, raw channel counts."""

    status: int
    serial: int
    counter: int | None
    timer: int | None
    raw: np.ndarray

    @property
    def groups(self) -> int:
        """8-channel groups in the frame."""
        return self.status & GROUP_MASK


def groups_for(channels: int) -> int:
    """Groups needed to carry ``channels`` channels."""
    return -(-channels // CHANNELS_PER_GROUP)


def encode_reply(
    raw: np.ndarray,
    serial: int,
    switches: int = 0,
    counter: int = 0,
    timer: int = 0,
    corrupt: bool = False,
) -> bytes:
    """The bytes a tape sends for these raw counts (padded with zeros to whole groups).

    Args:
        raw: uint16 channel counts.
        serial: the tape's serial number (extended layout when above 4096).
        switches: status bits 4-6.
        counter: frame counter (extended layout).
        timer: timer ticks (extended layout).
        corrupt: send a wrong checksum (for testing receivers).
    """
    groups = groups_for(len(raw))
    padded = np.zeros(groups * CHANNELS_PER_GROUP, dtype=">u2")
    padded[: len(raw)] = raw
    data = padded.tobytes()
    head = bytes([(switches & 0x70) | groups]) + int(serial).to_bytes(2, "big")
    if serial > EXTENDED_SERIAL:
        head += (
            (counter & 0xFFFF).to_bytes(2, "big") + (timer & 0xFFFFFF).to_bytes(3, "big") + bytes(8)
        )
    checksum = (sum(data) + (1 if corrupt else 0)) & 0xFF
    return head + data + bytes([checksum])


def reply_length(status: int, serial: int) -> int:
    """Bytes still to read after the 3-byte status+serial prefix."""
    extra = EXTENDED_BYTES if serial > EXTENDED_SERIAL else 0
    return extra + GROUP_BYTES * (status & GROUP_MASK) + 1


def decode_reply(prefix: bytes, rest: bytes) -> RawFrame:
    """Decode a reply from its 3-byte prefix and the remaining bytes.

    Raises:
        ProtocolError: wrong length or checksum.
    """
    status, serial = prefix[0], int.from_bytes(prefix[1:3], "big")
    if len(rest) != reply_length(status, serial):
        raise ProtocolError(
            f"{len(rest)} bytes after the header, expected {reply_length(status, serial)}"
        )
    counter = timer = None
    offset = 0
    if serial > EXTENDED_SERIAL:
        counter = int.from_bytes(rest[0:2], "big")
        timer = int.from_bytes(rest[2:5], "big")
        offset = EXTENDED_BYTES
    data = rest[offset:-1]
    if (sum(data) & 0xFF) != rest[-1]:
        raise ProtocolError(f"checksum {rest[-1]} does not match the data ({sum(data) & 0xFF})")
    raw = np.frombuffer(data, dtype=">u2").astype(np.int64)
    return RawFrame(status, serial, counter, timer, raw)


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


POLL_SECONDS = 0.05
"""How often the emulator checks for a stop request."""
DEFAULT_SERIAL = 5001
"""Above 4096, so replies use the extended layout (counter, timer, filler)."""


class ShapeTapeEmulator:
    """A fake tape behind a pty; open :attr:`port` with :class:`SerialSource`.

    Args:
        angles: ``f(k) -> (bend, twist, switches)`` for the k-th reply.
        calibration: how angles become raw counts (default identity for 16 regions).
        serial: the serial number it reports.
        counter_start: its 16-bit frame counter's first value (start near 65535 to test the wrap).
    """

    def __init__(
        self,
        angles: Callable[[int], tuple[np.ndarray, np.ndarray, int]],
        calibration: Calibration | None = None,
        serial: int = DEFAULT_SERIAL,
        counter_start: int = 0,
    ) -> None:
        self.angles = angles
        self.calibration = calibration or Calibration.identity()
        self.serial = serial
        self.counter_start = counter_start
        self.master, self._slave = os.openpty()
        tty.setraw(self._slave)
        self.port = os.ttyname(self._slave)
        self.replies = 0
        self.corrupt: set[int] = set()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="shapetape-emulator", daemon=True)

    def start(self) -> ShapeTapeEmulator:
        """Start answering requests."""
        self._thread.start()
        return self

    def unplug(self) -> None:
        """Close the device side, as if the cable were pulled."""
        self._stop.set()
        if self._thread.ident is not None:  # started
            self._thread.join(1.0)
        for fd in (self.master, self._slave):
            with contextlib.suppress(OSError):
                os.close(fd)

    stop = unplug

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                ready, _, _ = select.select([self.master], [], [], POLL_SECONDS)
                if not ready:
                    continue
                requests = os.read(self.master, 1024)
            except OSError:
                return
            for byte in requests:
                if byte != REQUEST[0]:
                    continue
                k = self.replies
                bend, twist, switches = self.angles(k)
                reply = encode_reply(
                    self.calibration.raw(bend, twist),
                    self.serial,
                    switches,
                    counter=self.counter_start + k,
                    timer=k,
                    corrupt=k in self.corrupt,
                )
                try:
                    os.write(self.master, reply)
                except OSError:
                    return
                self.replies += 1
