"""An emulated ShapeTape on a pseudo-terminal, speaking the serial protocol (for tests and demos).

It answers every ``0x20`` with a frame built from a frame generator, can corrupt chosen replies'
checksums, and can be "unplugged" (its pty closed) mid-stream.
"""

from __future__ import annotations

import contextlib
import os
import select
import threading
import tty
from collections.abc import Callable

import numpy as np

from ._calibration import Calibration
from ._shapetape_protocol import REQUEST, encode_reply

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
