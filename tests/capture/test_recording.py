"""Recordings: exact round trips, crash recovery, malformed files, atomic edits."""

from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.capture import (
    RecordingError,
    RecordingWriter,
    TapeFrame,
    read_recording,
    rename_recording,
    update_recording_meta,
)


def _write(path: Path, frames: list[TapeFrame], **kw) -> Path:
    with RecordingWriter(path, frames[0].regions, **kw) as writer:
        writer.write_many(frames)
    return path


def test_round_trip_gives_the_very_same_frames(tmp_path, frames):
    path = _write(tmp_path / "a.tape.csv", frames, operator="ada", notes="n", source="test")
    rec = read_recording(path)
    assert not rec.recovered and rec.problems == []
    assert len(rec) == len(frames)
    assert all(a.same_as(b) for a, b in zip(frames, rec.frames(), strict=True))
    assert rec.meta["operator"] == "ada" and rec.meta["source"] == "test"
    assert rec.duration == pytest.approx(frames[-1].t - frames[0].t)


def test_simulated_capture_round_trip(tmp_path):
    from studio.capture import simulate

    sim = simulate(2.0, seed=3)
    path = _write(tmp_path / "sim.tape.csv", sim.frames, config=sim.config, source="simulator")
    rec = read_recording(path)
    assert all(a.same_as(b) for a, b in zip(sim.frames, rec.frames(), strict=True))
    assert rec.config == sim.config
    assert np.allclose(rec.config.base, sim.config.base)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(allow_nan=False, allow_infinity=False, width=64), min_size=4, max_size=4))
def test_any_finite_angle_round_trips_exactly(tmp_path_factory, values):
    path = tmp_path_factory.mktemp("h") / "h.tape.csv"
    frame = TapeFrame(0.0, 0, np.array(values[:2]), np.array(values[2:]), 0)
    rec = read_recording(_write(path, [frame]))
    assert rec.frames()[0].same_as(frame)


def test_readable_with_plain_numpy(tmp_path, frames):
    path = _write(tmp_path / "a.tape.csv", frames)
    data = np.loadtxt(path, delimiter=",", comments="#", skiprows=2)
    assert data.shape == (len(frames), 3 + 2 * 16)
    assert np.array_equal(data[:, 3:19], np.stack([f.bend for f in frames]))


def test_never_overwrites(tmp_path, frames):
    path = _write(tmp_path / "a.tape.csv", frames)
    with pytest.raises(RecordingError, match="already exists"):
        RecordingWriter(path, 16)


CHILD = r"""
import sys, numpy as np
from studio.capture import RecordingWriter, TapeFrame
w = RecordingWriter(sys.argv[1], 16, flush_seconds=0.05)
i = 0
while True:
    w.write(TapeFrame(i / 110, i, np.full(16, i * 1e-3), np.full(16, -i * 1e-3), 0))
    i += 1
    if i % 50 == 0:
        print(i, flush=True)
"""


def test_kill_9_mid_capture_recovers_every_flushed_frame(tmp_path):
    path = tmp_path / "killed.tape.csv"
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(path)], stdout=subprocess.PIPE, text=True
    )
    try:
        for _ in range(200):  # wait until many frames were written (and so several flushes ran)
            line = child.stdout.readline()
            if int(line) >= 5000:
                break
        deadline = time.monotonic() + 30  # and until they are on disk (flushed every 0.05 s)
        while path.read_text().count("\n") - 2 < 5000:
            assert time.monotonic() < deadline, "the child flushed no frames"
            time.sleep(0.02)
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait()
    raw = path.read_text()
    complete_rows = raw.count("\n") - 2
    rec = read_recording(path)
    assert rec.recovered
    assert len(rec) == complete_rows >= 5000
    assert np.array_equal(rec.frame, np.arange(len(rec)))
    assert np.array_equal(rec.bend[:, 0], rec.frame * 1e-3)


def test_interrupted_file_with_half_a_row_is_recovered(tmp_path, frames):
    path = tmp_path / "a.tape.csv"
    with RecordingWriter(path, 16) as writer:
        writer.write_many(frames)
    text = path.read_text().splitlines(keepends=True)
    body = "".join(text[:-1])  # drop the '# end' line: an interrupted capture
    path.write_text(body + text[-2][:40])  # and a row cut short by the crash
    rec = read_recording(path)
    assert rec.recovered and len(rec) == len(frames)
    assert "incomplete last row" in rec.problems[0]


def _damage(path: Path, line_number: int, new_line: str) -> None:
    lines = path.read_text().splitlines()
    lines[line_number - 1] = new_line
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize(
    ("line", "make", "message"),
    [
        (10, lambda s: s[: len(s) // 2], "columns where 35 were expected"),
        (11, lambda s: s + ",1.0", "36 columns"),
        (12, lambda s: s.replace(s.split(",")[5], "nan", 1), "NaN"),
        (13, lambda s: s.replace(s.split(",")[5], "abc", 1), "'abc' is not a number"),
        (1, lambda s: s.replace('"version": 1', '"version": 99'), "unknown recording version 99"),
        (1, lambda s: "hello,world", "not a Teach Studio recording"),
        (1, lambda s: s[:-5], "not valid JSON"),
        (2, lambda s: "a,b,c", "column row"),
    ],
)
def test_malformed_files_name_the_file_line_and_problem(tmp_path, frames, line, make, message):
    path = _write(tmp_path / "bad.tape.csv", frames)
    original = path.read_text().splitlines()[line - 1]
    _damage(path, line, make(original))
    with pytest.raises(RecordingError) as err:
        read_recording(path)
    text = str(err.value)
    assert str(path) in text and f"line {line}" in text and message in text


def test_lenient_read_keeps_the_good_frames(tmp_path, frames):
    path = _write(tmp_path / "bad.tape.csv", frames)
    lines = path.read_text().splitlines()
    _damage(path, 10, lines[9][:30])
    _damage(path, 20, lines[19].replace(lines[19].split(",")[4], "inf", 1))
    rec = read_recording(path, strict=False)
    assert len(rec) == len(frames) - 2
    assert [p.split(":")[0] for p in rec.problems] == ["line 10", "line 20"]
    kept = [f for i, f in enumerate(frames) if i + 3 not in (10, 20)]
    assert all(a.same_as(b) for a, b in zip(kept, rec.frames(), strict=True))


def test_binary_and_empty_files_are_refused(tmp_path):
    (tmp_path / "bin.tape.csv").write_bytes(b"\x89PNG\x00\xff\xfe")
    (tmp_path / "empty.tape.csv").write_bytes(b"")
    for name in ("bin.tape.csv", "empty.tape.csv"):
        with pytest.raises(RecordingError, match="not a recording"):
            read_recording(tmp_path / name)


def test_meta_edit_is_atomic_and_keeps_every_data_byte(tmp_path, frames):
    path = _write(tmp_path / "a.tape.csv", frames)
    before = path.read_bytes().split(b"\n", 1)[1]
    inode = os.stat(path).st_ino
    meta = update_recording_meta(path, notes="second take", operator="bob")
    assert path.read_bytes().split(b"\n", 1)[1] == before
    assert os.stat(path).st_ino != inode  # replaced, not rewritten in place
    rec = read_recording(path)
    assert rec.meta["notes"] == "second take" == meta["notes"] and rec.meta["operator"] == "bob"
    with pytest.raises(RecordingError, match="cannot be edited"):
        update_recording_meta(path, regions=3)


def test_edits_are_refused_while_recording(tmp_path, frames):
    path = tmp_path / "live.tape.csv"
    writer = RecordingWriter(path, 16)
    writer.write_many(frames)
    with pytest.raises(RecordingError, match="being recorded"):
        update_recording_meta(path, notes="x")
    writer.close()
    update_recording_meta(path, notes="x")
    assert len(read_recording(path)) == len(frames)


def test_rename_moves_the_file_and_its_demonstrations_follow(tmp_path, frames):
    path = _write(tmp_path / "a.tape.csv", frames)
    demo = tmp_path / "a.0.00-1.00.demo.json"
    demo.write_text(json.dumps({"format": "teach-studio-demonstration", "recording": "a.tape.csv"}))
    new = rename_recording(path, "reach-1")
    assert new == tmp_path / "reach-1.tape.csv" and not path.exists()
    assert read_recording(new).meta["name"] == "reach-1"
    assert json.loads(demo.read_text())["recording"] == "reach-1.tape.csv"
    other = _write(tmp_path / "b.tape.csv", frames)
    with pytest.raises(RecordingError, match="already exists"):
        rename_recording(other, "reach-1")


def test_writer_flushes_without_new_frames(tmp_path, frames):
    path = tmp_path / "slow.tape.csv"
    writer = RecordingWriter(path, 16, flush_seconds=0.05)
    writer.write_many(frames[:10])
    for _ in range(100):  # the background flusher must put them on disk with no further writes
        if path.read_text().count("\n") >= 12:
            break
        time.sleep(0.02)
    assert len(read_recording(path)) == 10
    writer.close()


class _DiskThatFillsUp:
    """The ``os`` module, except that the disk is full once ``room`` more bytes are written."""

    def __init__(self, room: int) -> None:
        self.room = room
        self.events: list[str] = []

    def __getattr__(self, name: str):
        return getattr(os, name)

    def write(self, fd: int, data) -> int:
        if self.room <= 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        n = os.write(fd, bytes(data[: self.room]))  # a partial write, as a filling disk does
        self.room -= n
        self.events.append("write")
        return n

    def fsync(self, fd: int) -> None:
        os.fsync(fd)
        self.events.append("fsync")


def test_a_full_disk_stops_the_writer_with_one_message_and_keeps_what_was_written(
    tmp_path, monkeypatch, frames
):
    from studio.capture import _recording_writer

    disk = _DiskThatFillsUp(room=40_000)  # the header and some 50 rows, the last one cut
    monkeypatch.setattr(_recording_writer, "os", disk)
    path = tmp_path / "full.tape.csv"
    writer = RecordingWriter(path, 16, flush_seconds=1e-9)  # every write flushes
    with pytest.raises(RecordingError) as err:
        for frame in frames:
            writer.write(frame)
    message = str(err.value)
    assert str(path) in message and "No space left on device" in message
    assert "free disk space" in message
    kept = writer.frames_on_disk
    assert 0 < kept < len(frames) and f"first {kept} frames on disk" in message
    with pytest.raises(RecordingError, match="No space left"):  # it stays stopped
        writer.write(frames[0])
    writer.close()  # already reported: closing is quiet
    rec = read_recording(path, strict=False)
    assert rec.recovered and len(rec) == kept
    assert all(a.same_as(b) for a, b in zip(frames, rec.frames(), strict=False))
    assert "incomplete last row" in rec.problems[0]


def test_a_full_disk_met_by_the_background_flusher_is_raised_once_by_close(
    tmp_path, monkeypatch, frames
):
    from studio.capture import _recording_writer

    monkeypatch.setattr(_recording_writer, "os", _DiskThatFillsUp(room=2_000))
    path = tmp_path / "full.tape.csv"
    writer = RecordingWriter(path, 16, flush_seconds=0.05)
    writer.write_many(frames[:20])  # buffered; the flusher meets the full disk
    for _ in range(100):
        if writer.error:
            break
        time.sleep(0.02)
    with pytest.raises(RecordingError, match="No space left on device") as err:
        writer.close()
    assert writer.close() == path  # told once
    kept = writer.frames_on_disk
    assert f"first {kept} frames on disk ({20 - kept} not written)" in str(err.value)
    rec = read_recording(path, strict=False)
    assert rec.recovered and len(rec) == kept < 20


def test_a_disk_too_full_for_the_header_leaves_no_file(tmp_path, monkeypatch):
    from studio.capture import _recording_writer

    monkeypatch.setattr(_recording_writer, "os", _DiskThatFillsUp(room=0))
    path = tmp_path / "none.tape.csv"
    with pytest.raises(RecordingError, match=r"cannot start .*\(No space left on device\)"):
        RecordingWriter(path, 16)
    assert not path.exists()


def test_record_verb_on_a_full_disk_prints_one_sentence(tmp_path, monkeypatch, capsys):
    from studio.capture import _recording_writer
    from studio.cli import main

    monkeypatch.setattr(_recording_writer, "os", _DiskThatFillsUp(room=20_000))
    out = tmp_path / "full.tape.csv"
    args = ["record", "--source", "simulator", "--seconds", "20", "--out", str(out)]
    assert main(args) == 2
    err = capsys.readouterr().err
    [line] = [x for x in err.splitlines() if "No space left" in x]
    assert line.startswith("studio record: cannot write") and "Traceback" not in err
    assert read_recording(out, strict=False).recovered


def test_every_flush_ends_with_an_fsync(tmp_path, monkeypatch, frames):
    from studio.capture import _recording_writer

    disk = _DiskThatFillsUp(room=10**9)
    monkeypatch.setattr(_recording_writer, "os", disk)
    writer = RecordingWriter(tmp_path / "a.tape.csv", 16, flush_seconds=3600)
    for batch in (frames[:10], frames[10:20]):
        writer.write_many(batch)
        writer.flush()
        assert disk.events[-1] == "fsync"
    writer.close()
    assert disk.events[-1] == "fsync"
    assert disk.events.count("fsync") == 4  # the header, two flushes, the close


def test_damaged_bytes_in_a_row_name_that_line(tmp_path, frames):
    path = _write(tmp_path / "d.tape.csv", frames)
    lines = path.read_bytes().split(b"\n")
    lines[40] = lines[40][:30] + b"\xff\xfe\x00" + lines[40][33:]  # a damaged disk block
    path.write_bytes(b"\n".join(lines))
    with pytest.raises(RecordingError, match=r"d.tape.csv, line 41: bytes that are not text"):
        read_recording(path)
    rec = read_recording(path, strict=False)
    assert len(rec) == len(frames) - 1 and rec.problems[0].startswith("line 41")
    kept = frames[:38] + frames[39:]
    assert all(a.same_as(b) for a, b in zip(kept, rec.frames(), strict=True))


@pytest.mark.parametrize("field", ["1_000", " 0.5", "0x1p3", "1e", "--1", "1.2.3", "", "½"])
def test_only_decimal_numbers_are_numbers(tmp_path, frames, field):
    path = _write(tmp_path / "f.tape.csv", frames[:20])
    lines = path.read_text().split("\n")
    fields = lines[9].split(",")
    fields[7] = field
    lines[9] = ",".join(fields)
    path.write_text("\n".join(lines))
    with pytest.raises(RecordingError, match=r"line 10: '.*' is not a number"):
        read_recording(path)


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet="0123456789.+-eE", min_size=1, max_size=8))
def test_the_bulk_parser_reads_a_field_as_float_would(tmp_path_factory, field):
    path = tmp_path_factory.mktemp("p") / "p.tape.csv"
    frame = TapeFrame(0.0, 0, np.zeros(2), np.zeros(2), 0)
    _write(path, [frame, frame])
    lines = path.read_text().split("\n")
    fields = lines[2].split(",")
    fields[3] = field
    lines[2] = ",".join(fields)
    path.write_text("\n".join(lines))
    rec = read_recording(path, strict=False)
    try:
        value = float(field)
    except ValueError:
        value = None
    if value is None or not np.isfinite(value):
        assert len(rec) == 1 and rec.problems[0].startswith("line 3")
    else:
        assert rec.bend[0, 0] == value and len(rec) == 2


def test_kill_9_of_studio_record_leaves_a_recovered_recording(tmp_path):
    out = tmp_path / "killed.tape.csv"
    child = subprocess.Popen(
        [sys.executable, "-m", "studio.cli", "record", "--out", str(out)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        seen = 0
        deadline = time.monotonic() + 60
        while seen < 120 and time.monotonic() < deadline:  # two flushes of the default 0.5 s
            time.sleep(0.05)
            seen = out.read_text().count("\n") - 2 if out.exists() else 0
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait()
    rec = read_recording(out, strict=False)
    assert rec.recovered and len(rec) >= seen >= 120
    assert np.array_equal(rec.frame, np.arange(len(rec)))  # every flushed frame, in order
    assert rec.meta["source"] == "simulator"


def _with_times(path, changes: dict[int, float]):
    """A copy of a shipped sample with the times of some rows (0-based) changed."""
    from studio.samples import SAMPLES_DIR

    lines = (SAMPLES_DIR / "sample-reach-1.tape.csv").read_text().split("\n")
    for row, t in changes.items():
        cells = lines[2 + row].split(",")
        cells[0] = repr(t)
        lines[2 + row] = ",".join(cells)
    path.write_text("\n".join(lines))
    return path


def test_negative_or_backward_times_load_with_a_warning(tmp_path):
    from studio.capture._recording_reader import summarize_recording

    odd = _with_times(tmp_path / "odd.tape.csv", {0: -0.5, 38: 0.01, 200: 0.02})
    rec = read_recording(odd)
    assert len(rec) == 385 and not rec.problems  # every frame kept, nothing refused
    negative, backwards = rec.warnings
    assert negative.startswith("1 frame with a negative time (first at line 3)")
    assert backwards.startswith("time goes backwards 2 times (first at line 41: 0.010 s after")
    assert summarize_recording(odd)["warnings"] == rec.warnings == rec.summary()["warnings"]
    fine = _with_times(tmp_path / "fine.tape.csv", {})
    assert read_recording(fine).warnings == [] and summarize_recording(fine)["warnings"] == []


def test_studio_info_shows_time_warnings(tmp_path, capsys):
    from studio.cli import main

    odd = _with_times(tmp_path / "odd.tape.csv", {5: 0.0})
    assert main(["info", str(odd)]) == 0
    out = capsys.readouterr().out
    assert "  warning   time goes backwards 1 time (first at line 8" in out
