"""A capture waits at least FIRST_FRAME_SECONDS for its first frame, whatever --wait says: a
sender started beside the recorder (``studio bridge`` and ``studio record --source udp`` at once)
may take seconds to start; after the first frame, --wait is the limit again."""

from __future__ import annotations

import numpy as np
import pytest

import studio.capture._capture_loop as loop
from studio.capture import CaptureError, SourceStatus, TapeFrame, capture


class _Clock:
    """Stands in for the loop's ``time`` module: a minute passes only when the source says."""

    def __init__(self) -> None:
        self.now = 0.0

    def monotonic(self) -> float:
        return self.now


class _LateSource:
    """A tape source whose first frame arrives ``late`` seconds after it starts, then a frame a
    read until ``frames``, then silence."""

    kind = "network"
    rate_hz = 110.0

    def __init__(self, clock: _Clock, late: float, frames: int) -> None:
        self.clock, self.late, self.frames, self.sent = clock, late, frames, 0

    def start(self) -> None:
        pass

    def stop(self) -> None:
        pass

    def read(self, timeout: float = 0.0) -> list[TapeFrame]:
        self.clock.now += 1.0  # every read waits a second of the clock
        if self.clock.now < self.late or self.sent >= self.frames:
            return []
        self.sent += 1
        zero = np.zeros(16)
        return [TapeFrame(self.sent / 110.0, self.sent, zero, zero)]

    def status(self) -> SourceStatus:
        return SourceStatus(kind="network", running=True, rate_hz=0.0, frames=self.sent, dropped=0)


@pytest.fixture
def clock(monkeypatch) -> _Clock:
    fake = _Clock()
    monkeypatch.setattr(loop, "time", fake)
    return fake


def test_a_sender_that_starts_late_is_waited_for(clock, tmp_path):
    late = loop.FIRST_FRAME_SECONDS - 5  # later than --wait's 10 s, within the first wait
    source = _LateSource(clock, late=late, frames=20)
    with pytest.raises(CaptureError, match="for 10 s") as refused:
        capture(source, tmp_path / "x.tape.csv", give_up_seconds=10.0)
    # its frames are kept; then --wait applies again, and gives up 10 s after the last one
    assert "20 frames kept" in str(refused.value)
    assert clock.now == pytest.approx(late + 20 + 10, abs=1.0)


def test_a_sender_that_never_starts_is_given_up_after_the_first_wait(clock, tmp_path):
    source = _LateSource(clock, late=10_000, frames=1)
    with pytest.raises(CaptureError, match="nothing was recorded"):
        capture(source, tmp_path / "x.tape.csv", give_up_seconds=10.0)
    assert clock.now == pytest.approx(loop.FIRST_FRAME_SECONDS, abs=1.0)
    assert not (tmp_path / "x.tape.csv").exists()
