"""Hostile and clumsy files: every read is bounded before it allocates (issue 13, items 2, 8, 12,
13, 15, 17).

Memory laws are measured with ``tracemalloc`` (numpy registers its buffers there): a refused
file must cost a few MB at most, whatever it claims or holds.
"""

from __future__ import annotations

import json
import os
import threading
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studio import JSONFileError, StudioError, TOMLFileError, loads_json, read_json, read_toml
from studio._json import MAX_JSON_DEPTH, nesting_depth, value_depth
from studio.capture import (
    CaptureError,
    DemonstrationError,
    NetworkSource,
    RecordingError,
    RecordingWriter,
    TapeFrame,
    capture,
    load_demonstration,
    read_recording,
    recording_bytes,
    update_recording_meta,
)
from studio.capture._calibration import load_calibration, read_raw_text
from studio.capture._network import FrameSender
from studio.capture._recording_format import MAX_HEADER_BYTES, MAX_REGIONS
from studio.capture._recording_reader import read_header, summarize_recording
from studio.cli import main
from tests.conftest import require

from .conftest import synthetic_frames

SMALL_PEAK_BYTES = 4 * 1024 * 1024
"""Most a refused or streamed file may make the reader allocate at once."""
DEEP = 50_000
"""The issue's nesting depth."""
WAIT_SECONDS = 10.0


def _peak(action) -> int:
    """Peak bytes traced while ``action()`` runs (its exception, if any, is swallowed)."""
    tracemalloc.start()
    try:
        action()
    except StudioError:
        pass
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak


def _header(**changes) -> str:
    meta = {
        "format": "teach-studio-recording",
        "version": 1,
        "regions": 2,
        "tape": None,
        "operator": "",
        "notes": "",
        "name": "x",
        "rate_hz": 110.0,
        "source": "test",
        "created": "2026-11-23T00:00:00+00:00",
        **changes,
    }
    return "# teach-studio-recording " + json.dumps(meta)


def _write(path: Path, frames: list[TapeFrame]) -> Path:
    with RecordingWriter(path, frames[0].regions) as writer:
        writer.write_many(frames)
    return path


# -- item 2: header fields within bounds, checked before anything is allocated ---------------


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"regions": 1_000_000_000}, "regions is 1000000000"),
        ({"regions": 300_000}, "regions is 300000"),
        ({"regions": 0}, "from 1 to"),
        ({"regions": True}, "regions is True"),
        ({"regions": 16.0}, "whole number"),
        ({"regions": "16"}, "whole number"),
        ({"rate_hz": 1e12}, "rate_hz"),
        ({"rate_hz": -1}, "rate_hz"),
        ({"rate_hz": "fast"}, "rate_hz"),
        ({"name": 5}, "name is 5; it must be text"),
        ({"notes": ["a"]}, "notes"),
        ({"tape": [1, 2]}, "tape"),
        ({"tape": {"regions": 3}}, "a tape of 2 regions"),
        ({"version": True}, "version"),
    ],
)
def test_hostile_header_fields_are_refused_before_allocating(tmp_path, change, words):
    path = tmp_path / "bomb.tape.csv"
    # the 593-byte file: a header and a few short rows
    regions = change.get("regions", 2)
    body = [_header(**change), "t,frame,status,bend_0,bend_1,twist_0,twist_1"]
    body += ["0.0,0,0,0.0,0.0,0.0,0.0"] * 10
    path.write_text("\n".join(body) + "\n")
    for read in (read_recording, read_header, summarize_recording):
        with pytest.raises(RecordingError, match="line 1") as err:
            read(path)
        assert words in str(err.value)
    if isinstance(regions, int) and regions > MAX_REGIONS:
        assert _peak(lambda: read_recording(path)) < SMALL_PEAK_BYTES
    with pytest.raises(RecordingError):
        update_recording_meta(path, notes="x")


def test_a_header_line_longer_than_the_limit_is_refused_unread(tmp_path):
    path = tmp_path / "long.tape.csv"
    path.write_text(_header(notes="n" * (MAX_HEADER_BYTES + 10)) + "\n")
    with pytest.raises(RecordingError, match="header is longer than"):
        read_header(path)
    assert _peak(lambda: read_recording(path)) < 3 * MAX_HEADER_BYTES


def test_notes_that_would_overflow_the_header_are_refused_and_the_file_kept(tmp_path):
    path = _write(tmp_path / "a.tape.csv", synthetic_frames(20))
    before = path.read_bytes()
    with pytest.raises(RecordingError, match="shorten the notes"):
        update_recording_meta(path, notes="n" * MAX_HEADER_BYTES)
    assert path.read_bytes() == before
    with pytest.raises(RecordingError, match="regions"):
        RecordingWriter(tmp_path / "wide.tape.csv", MAX_REGIONS + 1)
    assert not (tmp_path / "wide.tape.csv").exists()


def test_every_header_the_writer_makes_is_read_back(tmp_path):
    frames = synthetic_frames(5, regions=MAX_REGIONS)
    path = _write(tmp_path / "wide.tape.csv", frames)
    assert read_recording(path).bend.shape == (5, MAX_REGIONS)


# -- item 17: a sparse or damaged file is streamed, never held ------------------------------


@pytest.fixture
def sparse(tmp_path) -> tuple[Path, int]:
    """A closed recording followed by a 64 MB hole of zero bytes (no newline in it)."""
    frames = synthetic_frames(200)
    path = _write(tmp_path / "sparse.tape.csv", frames)
    with path.open("r+b") as f:
        f.truncate(path.stat().st_size + 64 * 1024 * 1024)
    return path, len(frames)


def test_a_hole_of_zero_bytes_is_one_problem_and_costs_one_block(sparse):
    path, n = sparse
    summary = summarize_recording(path, strict=False)
    assert summary["frames"] == n
    assert any("longer than any row" in p for p in summary["problems"])
    with pytest.raises(RecordingError, match=rf"line {n + 4}: a line of 67,108,864 bytes"):
        read_recording(path)
    assert _peak(lambda: summarize_recording(path, strict=False)) < SMALL_PEAK_BYTES
    rec = read_recording(path, strict=False)
    assert len(rec) == n and not rec.recovered


def test_info_streams_a_sparse_file_and_prints_one_sentence(sparse, capsys):
    path, n = sparse
    assert main(["info", "--json", "--lenient", str(path)]) == 0
    assert json.loads(capsys.readouterr().out)["frames"] == n
    assert main(["info", str(path)]) != 0
    err = capsys.readouterr().err
    assert "longer than any row" in err and "Traceback" not in err


def test_streamed_summary_equals_the_full_read(tmp_path):
    frames = synthetic_frames(3000)  # about 1.8 MB: lines cross the reader's block boundaries
    path = _write(tmp_path / "a.tape.csv", frames)
    assert read_recording(path).summary() == summarize_recording(path)
    lines = path.read_text().split("\n")  # [..., last row, '# end ...', '']
    lines[100] = lines[100][:20]  # one damaged row
    path.write_text("\n".join(lines[:-3]) + "\n" + lines[-3][:10])  # interrupted, torn last row
    assert summarize_recording(path, False) == read_recording(path, False).summary()
    rec = read_recording(path, strict=False)
    assert rec.recovered and len(rec) == len(frames) - 2
    kept = frames[:98] + frames[99:-1]  # file line 101 held frame 98
    assert all(a.same_as(b) for a, b in zip(kept, rec.frames(), strict=True))


# -- item 13: one bounded JSON reader ---------------------------------------------------------

json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.text(alphabet='[]{}"\\ab,:'),
    lambda children: (
        st.lists(children, max_size=3)
        | st.dictionaries(st.text(alphabet='[]{}"\\x', max_size=3), children, max_size=3)
    ),
    max_leaves=20,
)


def _depth(value) -> int:
    if isinstance(value, list):
        return 1 + max((_depth(v) for v in value), default=0)
    if isinstance(value, dict):
        return 1 + max((_depth(v) for v in value.values()), default=0)
    return 0


@settings(max_examples=300, deadline=None)
@given(json_values)
def test_nesting_depth_counts_brackets_outside_strings(value):
    text = json.dumps(value)
    assert nesting_depth(text) == _depth(value) == value_depth(value)
    assert loads_json(text) == value


def test_toml_files_are_bounded_too(tmp_path):
    path = tmp_path / "spec.toml"
    path.write_text('name = "x"\n[grid]\nbins = [5, 7]\n')
    assert read_toml(path) == {"name": "x", "grid": {"bins": [5, 7]}}
    for deep in ("x = " + "[" * 5000 + "]" * 5000, "a" + ".a" * 3000 + " = 1"):
        path.write_text(deep)
        with pytest.raises(TOMLFileError, match="more than 64 levels deep"):
            read_toml(path)
    path.write_text("x = [1,")
    with pytest.raises(TOMLFileError, match="not valid TOML"):
        read_toml(path)
    with pytest.raises(StudioError, match="not a regular file"):
        read_toml("/dev/zero")


@pytest.mark.parametrize("wrap", ["[{}]", '{{"a": {}}}'])
def test_json_deeper_than_the_limit_is_refused_without_recursion(wrap):
    def nest(depth: int) -> str:
        text = "0"
        for _ in range(depth):
            text = wrap.format(text)
        return text

    assert loads_json(nest(MAX_JSON_DEPTH)) is not None
    with pytest.raises(JSONFileError, match=f"{MAX_JSON_DEPTH + 1} levels deep"):
        loads_json(nest(MAX_JSON_DEPTH + 1))
    err = pytest.raises(JSONFileError, loads_json, "[" * DEEP + "]" * DEEP, "x.json").value
    assert isinstance(err, StudioError) and isinstance(err, ValueError)
    assert str(err).startswith(f"x.json nests JSON {DEEP} levels deep")


def test_json_files_are_bounded_by_size_and_type(tmp_path):
    big = tmp_path / "big.json"
    big.write_text("[" + "0," * 600 + "0]")
    with pytest.raises(StudioError, match="more than"):
        read_json(big, max_bytes=1000)
    with pytest.raises(StudioError, match="not a regular file"):
        read_json("/dev/zero")
    with pytest.raises(StudioError, match="not valid JSON"):
        loads_json("[1,", "the text")


def test_deep_json_in_every_studio_file_is_a_clear_error(tmp_path, capsys):
    deep = "[" * DEEP + "]" * DEEP
    recording = tmp_path / "deep.tape.csv"
    recording.write_text("# teach-studio-recording " + deep + "\n")
    with pytest.raises(RecordingError, match="line 1: the header nests JSON"):
        read_recording(recording)
    end = _write(tmp_path / "end.tape.csv", synthetic_frames(5))
    end.write_text(end.read_text().rsplit("# end", 1)[0] + "# end " + deep + "\n")
    with pytest.raises(RecordingError, match="'# end' line is not valid JSON"):
        read_recording(end)
    demo = tmp_path / "deep.demo.json"
    demo.write_text(deep)
    with pytest.raises(DemonstrationError, match="nests JSON") as err:
        load_demonstration(demo)
    assert err.value.reason == "bad_file"
    calibration = tmp_path / "deep.calibration.json"
    calibration.write_text(deep)
    with pytest.raises(CaptureError, match="nests JSON"):
        load_calibration(calibration)
    for path in (recording, demo):
        assert main(["info", str(path)]) != 0
        err_text = capsys.readouterr().err
        assert "nests JSON" in err_text and "Traceback" not in err_text


# -- item 12: only regular files of a sane size are read --------------------------------------


@pytest.fixture
def fifo(tmp_path) -> Path:
    path = tmp_path / "pipe"
    os.mkfifo(path)
    return path


def test_devices_and_pipes_are_refused_unread(tmp_path, fifo):
    for path in ("/dev/zero", fifo, tmp_path):
        with pytest.raises(CaptureError, match="not a regular file"):
            load_calibration(path)
        with pytest.raises(RecordingError, match="not a regular file"):
            read_recording(path)
        with pytest.raises(RecordingError, match="not a regular file"):
            read_raw_text(path, 32)
        with pytest.raises(DemonstrationError, match="not a regular file"):
            load_demonstration(path)
        with pytest.raises(RecordingError, match="not a regular file"):
            update_recording_meta(path, notes="x")  # never blocks on a pipe


def test_a_serial_source_refuses_dev_zero_as_its_calibration():
    import importlib.util

    require(importlib.util.find_spec("serial") is not None, "pyserial is not installed")
    from studio.capture import SerialSource

    with pytest.raises(CaptureError, match="calibration /dev/zero is a device"):
        SerialSource("/dev/null", calibration="/dev/zero")


def test_an_oversized_calibration_is_refused_unread(tmp_path):
    path = tmp_path / "huge.calibration.json"
    with path.open("wb") as f:
        f.truncate(64 * 1024 * 1024)
    with pytest.raises(CaptureError, match="more than the"):
        load_calibration(path)
    assert _peak(lambda: load_calibration(path)) < SMALL_PEAK_BYTES


# -- item 8: a datagram of another tape is rejected, the capture goes on ----------------------


def test_a_datagram_of_another_tape_is_rejected_and_the_capture_goes_on(tmp_path):
    frames = synthetic_frames(30)
    stray = synthetic_frames(1, regions=3)[0]
    receiver = NetworkSource(port=0)
    out = tmp_path / "live.tape.csv"
    receiver.start()
    address = receiver.address
    done = threading.Event()

    def send() -> None:
        with FrameSender(*address) as sender:
            for i, frame in enumerate(frames):
                sender.send(frame)
                if i == 10:
                    sender.send(stray)
        done.set()

    def enough() -> bool:
        return done.is_set() and receiver.status().frames >= len(frames)

    receiver.stop()  # capture() starts it again on the same port
    receiver.port = address[1]
    threading.Timer(0.2, send).start()
    capture(receiver, out, stop=enough)
    rec = read_recording(out)
    status = receiver.status()
    assert len(rec) == len(frames) and rec.bend.shape[1] == 16
    assert status.rejected == 1 and status.error is None
    assert "3 regions where this stream has 16" in status.warning


def test_the_configured_region_count_wins_over_the_first_datagram():
    class Config:
        regions = 3

    receiver = NetworkSource(port=0, config=Config())
    receiver.start()
    try:
        with FrameSender(*receiver.address) as sender:
            sender.send(synthetic_frames(1)[0])
            for frame in synthetic_frames(4, regions=3):
                sender.send(frame)
        got: list[TapeFrame] = []
        while len(got) < 4:
            got += receiver.read(timeout=WAIT_SECONDS)
    finally:
        receiver.stop()
    assert [f.bend.shape[0] for f in got] == [3] * 4 and receiver.status().rejected == 1


# -- item 15: a consistent prefix of a live recording -----------------------------------------


def test_a_live_recording_is_served_up_to_its_last_complete_line(tmp_path):
    frames = synthetic_frames(100)
    path = tmp_path / "live.tape.csv"
    writer = RecordingWriter(path, 16)
    try:
        writer.write_many(frames[:60])
        writer.flush()
        with path.open("ab") as torn:  # a row whose write is under way
            torn.write(b"0.5,60,0,0.1")
        snapshot = recording_bytes(path)
        writer.write_many(frames[60:])  # appended after the download started
        writer.flush()
        data = b"".join(snapshot)
    finally:
        writer.close()
    assert len(data) == snapshot.size and data.endswith(b"\n")
    assert path.read_bytes().startswith(data)
    copy = tmp_path / "copy.tape.csv"
    copy.write_bytes(data)
    rec = read_recording(copy)
    assert rec.recovered and len(rec) == 60
    assert all(a.same_as(b) for a, b in zip(frames, rec.frames(), strict=False))
    closed = recording_bytes(path)
    assert b"".join(closed) == path.read_bytes()


def test_a_download_snapshot_survives_an_atomic_header_edit(tmp_path):
    path = _write(tmp_path / "a.tape.csv", synthetic_frames(50))
    before = path.read_bytes()
    snapshot = recording_bytes(path)
    update_recording_meta(path, notes="edited while downloading")
    assert b"".join(snapshot) == before and np.asarray(snapshot.size) == len(before)
