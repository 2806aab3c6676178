"""Sources: playback, network bridge on loopback, serial on an emulated pty, simulator."""

from __future__ import annotations

import dataclasses
import socket
import time

import numpy as np
import pytest

from studio.capture import (
    Calibration,
    CaptureError,
    FrameSource,
    NetworkSource,
    PlaybackSource,
    RecordingWriter,
    SerialSource,
    ShapeTapeEmulator,
    TapeFrame,
    encode_frame,
    read_recording,
    stream_source,
)
from studio.capture._network import FrameSender, WireError, bridge_key, decode_frame
from studio.capture._serial import ProtocolError, decode_reply, encode_reply

from .conftest import synthetic_frames

WAIT_SECONDS = 10.0


def _drain(source, until, timeout=WAIT_SECONDS) -> list[TapeFrame]:
    """Read until ``until(frames)`` is true, the source stops, or the timeout passes."""
    out: list[TapeFrame] = []
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not until(out):
        got = source.read(timeout=0.05)
        out += got
        if not got and not source.running:
            break
    return out


def _wait(predicate, timeout=WAIT_SECONDS) -> None:
    """Poll ``predicate`` until it holds (fails after ``timeout`` s: only a hung source)."""
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, "timed out waiting for the source"
        time.sleep(0.01)


def _recording(tmp_path, frames):
    path = tmp_path / "p.tape.csv"
    with RecordingWriter(path, 16, rate_hz=110.0) as w:
        w.write_many(frames)
    return read_recording(path)


def test_playback_as_fast_as_possible_gives_every_frame(tmp_path, frames):
    source = PlaybackSource(_recording(tmp_path, frames), speed=None, queue_frames=16)
    assert isinstance(source, FrameSource)
    source.start()
    got = _drain(source, lambda f: len(f) >= len(frames))
    source.stop()
    assert all(a.same_as(b) for a, b in zip(frames, got, strict=True))
    assert source.status().dropped == 0 and source.status().frames == len(frames)


def test_playback_seek_pause_and_loop(tmp_path, frames):
    rec = _recording(tmp_path, frames)
    source = PlaybackSource(rec, speed=None, loop=True, queue_frames=8)
    source.pause()
    source.seek(2.0)
    source.start()
    assert source.read(timeout=0.1) == []  # paused: no frame comes while we wait for one
    source.resume()
    got = _drain(source, lambda f: len(f) >= 2 * len(frames))
    source.stop()
    first = int(round(2.0 * 110))
    assert got[0].same_as(frames[first])
    wrap = len(frames) - first
    assert got[wrap].frame == len(frames) and np.array_equal(got[wrap].bend, frames[0].bend)
    assert all(b.t > a.t for a, b in zip(got, got[1:], strict=False))

    # every frame played names the row it was read from, through the loop's later passes
    rows = [source.row_at(f.t) for f in got]
    assert rows == [(first + k) % len(frames) for k in range(len(got))]
    assert source.row_at(rec.t[0] + 0.5 / 110) is None  # between two frames: no row


def test_row_at_is_none_where_the_recordings_times_do_not_rise(tmp_path, frames):
    backwards = [*frames[:5], dataclasses.replace(frames[5], t=frames[2].t), *frames[6:10]]
    source = PlaybackSource(_recording(tmp_path, backwards), speed=None)
    assert source.row_at(frames[7].t) is None


def test_playback_real_time_is_paced_not_dumped(tmp_path, frames):
    """Frame i comes out no earlier than (t_i - t_0) / speed after the start: the recording's own
    time stamps set the pace. A busy machine can only make frames late, never early."""
    speed = 2.0
    source = PlaybackSource(_recording(tmp_path, frames), speed=speed)  # 1.4 s at speed 2
    count = 110
    got: list[TapeFrame] = []
    read_at: list[float] = []
    before = time.monotonic()
    source.start()
    try:
        deadline = before + WAIT_SECONDS
        while len(got) < count and time.monotonic() < deadline:
            batch = source.read(timeout=0.05)
            now = time.monotonic()  # after the batch was released
            got += batch
            read_at += [now] * len(batch)
    finally:
        source.stop()
    assert len(got) >= count
    assert all(a.same_as(b) for a, b in zip(frames, got, strict=False))
    early = [
        i
        for i, (frame, at) in enumerate(zip(got, read_at, strict=True))
        if at - before < (frame.t - frames[0].t) / speed - 1e-6
    ]
    assert early == []


def test_wire_format_round_trips_at_float32(frames):
    frame = frames[7]
    back = decode_frame(encode_frame(frame))
    assert back.frame == frame.frame and back.t == frame.t and back.status == frame.status
    assert np.array_equal(back.bend, frame.bend.astype(np.float32))
    assert len(encode_frame(frame)) == 22 + 8 * 16
    for bad in (b"", b"XXXX" + encode_frame(frame)[4:], encode_frame(frame)[:-1]):
        with pytest.raises(WireError):
            decode_frame(bad)
    nan = TapeFrame(0.0, 0, np.full(16, np.nan), np.zeros(16), 0)
    with pytest.raises(WireError, match="NaN"):
        decode_frame(encode_frame(nan))


def test_network_bridge_on_loopback(tmp_path, frames):
    receiver = NetworkSource(port=0)
    receiver.start()
    host, port = receiver.address
    try:
        sent = stream_source(PlaybackSource(_recording(tmp_path, frames), speed=20.0), host, port)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as raw:
            raw.sendto(b"not a frame", (host, port))
            raw.sendto(b"STAP\x09" + bytes(40), (host, port))
        got = _drain(receiver, lambda f: len(f) >= len(frames))
        for _ in range(100):
            if receiver.status().rejected >= 2:
                break
            time.sleep(0.02)
        status = receiver.status()
    finally:
        receiver.stop()
    assert sent == len(frames) == len(got)
    assert [f.frame for f in got] == [f.frame for f in frames]
    assert np.allclose(
        np.stack([f.bend for f in got]), np.stack([f.bend for f in frames]), atol=1e-6
    )
    assert status.rejected == 2 and status.dropped == 0 and status.running
    assert "wire version 9" in status.warning


def test_network_counts_gaps_as_dropped(frames):
    receiver = NetworkSource(port=0)
    receiver.start()
    try:
        with FrameSender(*receiver.address) as sender:
            for f in frames[:10] + frames[15:20]:
                sender.send(f)
        got = _drain(receiver, lambda f: len(f) >= 15)
    finally:
        receiver.stop()
    assert len(got) == 15 and receiver.status().dropped == 5


def test_network_port_in_use_is_a_clear_error():
    first = NetworkSource(port=0)
    first.start()
    try:
        with pytest.raises(CaptureError, match="choose another port"):
            NetworkSource(port=first.address[1]).start()
    finally:
        first.stop()


def test_bridge_verb_streams_a_recording(tmp_path, frames):
    from studio.cli import main

    path = tmp_path / "b.tape.csv"
    with RecordingWriter(path, 16) as w:
        w.write_many(frames[:100])
    receiver = NetworkSource(port=0)
    receiver.start()
    try:
        args = [
            "bridge",
            "--source",
            str(path),
            "--to",
            f"127.0.0.1:{receiver.address[1]}",
            "--speed",
            "20",
        ]
        assert main(args) == 0
        got = _drain(receiver, lambda f: len(f) >= 100)
    finally:
        receiver.stop()
    assert [f.frame for f in got] == list(range(100))


def test_serial_protocol_round_trip_and_checksum():
    raw = np.arange(32, dtype=np.uint16) * 1000
    for serial in (1234, 5001):
        reply = encode_reply(raw, serial, switches=0x30, counter=7, timer=99)
        frame = decode_reply(reply[:3], reply[3:])
        assert np.array_equal(frame.raw, raw) and frame.groups == 4 and frame.status & 0x30 == 0x30
        assert (frame.counter, frame.timer) == ((7, 99) if serial > 4096 else (None, None))
        bad = encode_reply(raw, serial, corrupt=True)
        with pytest.raises(ProtocolError, match="checksum"):
            decode_reply(bad[:3], bad[3:])


def _angles(k: int):
    return (
        np.linspace(-1, 1, 16) * np.sin(k / 20),
        np.full(16, 0.01 * (k % 30)),
        0x20 if k % 2 else 0,
    )


def test_serial_source_on_an_emulated_tape(tmp_path):
    calibration = Calibration(np.full(32, 30000.0), np.full(32, 2e-4), serial=5001)
    calibration.save(tmp_path / "cal.json")
    emulator = ShapeTapeEmulator(_angles, calibration).start()
    emulator.corrupt = {5, 6, 40}
    source = SerialSource(emulator.port, calibration=tmp_path / "cal.json")
    source.start()
    try:
        got = _drain(source, lambda f: len(f) >= 60)
        status = source.status()
    finally:
        emulator.unplug()
    assert len(got) >= 60 and status.error is None
    assert status.dropped >= 3 and "checksum" in status.warning
    numbers = [frame.frame for frame in got]  # the emulated tape's own counter
    assert not set(numbers) & emulator.corrupt and numbers == sorted(numbers)
    assert max(numbers) > max(emulator.corrupt)  # the stream went on past every bad checksum
    for frame in got:
        bend, twist, switches = _angles(frame.frame)
        assert np.allclose(frame.bend, bend, atol=1e-4) and np.allclose(
            frame.twist, twist, atol=1e-4
        )
        assert frame.trigger == bool(switches)
    for _ in range(100):
        if not source.running:
            break
        time.sleep(0.05)
    source.stop()
    status = source.status()
    assert (
        not status.running and "disconnected" in status.error and "plug it back in" in status.error
    )


def test_serial_port_that_does_not_exist():
    with pytest.raises(CaptureError, match="cannot open the tape"):
        SerialSource("/dev/does-not-exist").start()


def test_dropped_frames_are_counted_when_the_consumer_stalls():
    from studio.capture._source import ThreadedSource

    class Burst(ThreadedSource):
        kind = "burst"

        def _produce(self):
            for frame in synthetic_frames(50):
                self._push(frame)

    source = Burst(queue_frames=10)
    source.start()
    _wait(lambda: not source.running)  # the producer pushed all 50 frames and returned
    assert len(source.read()) == 10 and source.status().dropped == 40


class _FakeClock:
    """``time.monotonic`` for a module under test, moved by the test alone."""

    def __init__(self) -> None:
        self.now = 1000.0

    def monotonic(self) -> float:
        return self.now


def test_the_rate_is_measured_over_the_last_second_and_falls_to_zero_when_frames_stop(
    monkeypatch,
):
    """A paused recording or a silent bridge must not keep showing its last rate.

    The rate is measured on a fake clock, so the test checks the arithmetic (frames per second
    over the last second) exactly, whatever the machine is doing.
    """
    from studio.capture import _source
    from studio.capture._source import ThreadedSource

    clock = _FakeClock()
    monkeypatch.setattr(_source, "time", clock)

    class Pushed(ThreadedSource):
        kind = "pushed"

        def _produce(self):
            self._stop_event.wait()

    source = Pushed()
    source.start()
    try:
        for frame in synthetic_frames(300):  # 3 s at 100 Hz
            clock.now += 0.01
            source._push(frame)
        status = source.status()
        assert status.rate_hz == pytest.approx(100.0)  # only the last second's frames count
        assert status.frames == 300
        clock.now += 0.5  # half a second of silence: the frames of the last half second remain
        assert source.status().rate_hz == pytest.approx(100.0)
        clock.now += 0.6  # over a second of silence
        status = source.status()
        assert status.running and status.rate_hz == 0.0 and status.frames == 300
        source._push(synthetic_frames(1)[0])  # one frame alone gives no rate yet
        assert source.status().rate_hz == 0.0
    finally:
        source.stop()


def test_a_slow_camera_reads_its_rate_between_frames():
    """The camera's pose model runs 1-3 frames a second without a GPU: the top bar read "rate
    0 Hz" between its frames while landmarks arrived. A steady slow source reads its rate; a
    frame after a pause, or a source gone quiet for two of its intervals, reads 0."""
    from studio.capture._source import measured_rate

    frames = [10.0, 10.8, 11.6, 12.4]  # 1.25 frames a second, steady
    assert measured_rate(frames, 12.9) == pytest.approx(1.25)  # half a second after the last
    assert measured_rate(frames, 12.4 + 1.7) == 0.0  # two intervals of silence
    assert measured_rate([10.0, 10.01, 10.02, 11.5], 11.5) == 0.0  # one frame after a pause
    assert measured_rate([10.0, 10.01, 10.02], 10.5) == pytest.approx(100.0)  # the last second


def test_a_crashing_producer_reports_its_error():
    from studio.capture._source import ThreadedSource

    class Broken(ThreadedSource):
        kind = "broken"

        def _produce(self):
            raise OSError("wire cut")

    source = Broken()
    source.start()
    _wait(lambda: not source.running)
    assert not source.running and "wire cut" in source.status().error


def test_a_silent_network_sender_is_a_status_error_that_clears(monkeypatch, frames):
    from studio.capture import _network

    monkeypatch.setattr(_network, "SILENCE_SECONDS", 0.2)
    receiver = NetworkSource(port=0)
    receiver.start()
    try:
        _wait(lambda: receiver.status().error is not None)
        silent = receiver.status()
        with FrameSender(*receiver.address) as sender:
            sender.send(frames[0])
        _drain(receiver, lambda f: len(f) >= 1)
        back = receiver.status()
    finally:
        receiver.stop()
    assert silent.running and "no frames yet on UDP" in silent.error
    assert back.running and back.error is None


def test_network_counts_single_lost_datagrams_and_the_counter_wrap():
    receiver = NetworkSource(port=0)
    receiver.start()
    counters = [2**32 - 3, 2**32 - 2, 0, 1, 3, 4]  # 2**32 - 1 and 2 lost; the counter wraps
    try:
        with FrameSender(*receiver.address) as sender:
            for c in counters:
                sender.send(TapeFrame(0.0, c, np.zeros(16), np.zeros(16)))
        got = _drain(receiver, lambda f: len(f) >= len(counters))
    finally:
        receiver.stop()
    assert [f.frame for f in got] == counters and receiver.status().dropped == 2


def test_serial_frame_numbers_keep_counting_across_the_tape_counter_wrap():
    emulator = ShapeTapeEmulator(_angles, counter_start=65530).start()
    source = SerialSource(emulator.port)
    source.start()
    try:
        got = _drain(source, lambda f: len(f) >= 12)
    finally:
        source.stop()
        emulator.unplug()
    assert [f.frame for f in got[:12]] == list(range(65530, 65542))


def test_a_silent_tape_stops_the_serial_source_with_a_reason(monkeypatch):
    from studio.capture import _serial

    monkeypatch.setattr(_serial, "SILENT_SECONDS", 0.3)
    mute = ShapeTapeEmulator(_angles)  # a port that never answers: tape off, cable loose
    source = SerialSource(mute.port)
    source.start()
    try:
        for _ in range(100):
            if not source.running:
                break
            time.sleep(0.05)
        status = source.status()
    finally:
        source.stop()
        mute.unplug()
    assert not status.running and status.frames == 0 and status.dropped >= 1
    assert "no valid reply" in status.error and "check its power and cable" in status.error


def test_a_datagram_built_from_the_readme_layout_decodes():
    import struct

    rng = np.random.default_rng(3)
    bend, twist = rng.normal(0, 1, 16), rng.normal(0, 1, 16)
    # docs/network-bridge.md's recipe, written independently of the encoder
    datagram = (
        struct.pack("!4sBBHIdH", b"STAP", 1, 0, 16, 4242, 1.25, 0x20)
        + np.concatenate([bend, twist]).astype(">f4").tobytes()
    )
    assert len(datagram) == 150
    frame = decode_frame(datagram)
    assert (frame.frame, frame.t, frame.status, frame.trigger) == (4242, 1.25, 0x20, True)
    assert np.array_equal(frame.bend, bend.astype(np.float32))
    assert np.array_equal(frame.twist, twist.astype(np.float32))
    assert encode_frame(frame) == datagram


def test_a_signed_datagram_decodes_only_with_its_key(frames):
    key = bridge_key("s3cret")
    signed = encode_frame(frames[3], key)
    assert len(signed) == len(encode_frame(frames[3])) + 16
    assert decode_frame(signed, key).frame == frames[3].frame
    assert decode_frame(signed).frame == frames[3].frame  # a receiver without a key ignores it
    with pytest.raises(WireError, match="unsigned"):
        decode_frame(encode_frame(frames[3]), key)
    with pytest.raises(WireError, match="another token"):
        decode_frame(encode_frame(frames[3], bridge_key("guess")), key)
    tampered = bytearray(signed)
    tampered[30] ^= 1  # a bend angle changed on the way
    with pytest.raises(WireError, match="another token"):
        decode_frame(bytes(tampered), key)


def test_the_bridge_listens_beyond_loopback_only_with_a_token():
    with pytest.raises(CaptureError, match="needs a token"):
        NetworkSource("0.0.0.0", port=0).start()


def test_a_bridge_beyond_loopback_takes_only_frames_signed_with_its_token(frames):
    receiver = NetworkSource("0.0.0.0", port=0, token="s3cret")
    receiver.start()
    port = receiver.address[1]
    try:
        with FrameSender("127.0.0.1", port) as unsigned:
            unsigned.send(frames[0])
        with FrameSender("127.0.0.1", port, token="guess") as stranger:
            stranger.send(frames[1])
        _wait(lambda: receiver.status().rejected >= 2)
        with FrameSender("127.0.0.1", port, token="s3cret") as owner:
            for frame in frames[2:12]:
                owner.send(frame)
        got = _drain(receiver, lambda f: len(f) >= 10)
        status = receiver.status()
    finally:
        receiver.stop()
    assert [f.frame for f in got] == [f.frame for f in frames[2:12]]
    assert status.rejected == 2 and "another token" in status.warning
