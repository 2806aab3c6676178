"""The verbs (record, info, import-raw) and the raw import with a calibration."""

from __future__ import annotations

import json

import numpy as np
import pytest

from studio.capture import Calibration, CaptureError, RecordingError, import_raw, read_recording
from studio.cli import main


def _raw_file(path, calibration, n=40, seed=0):
    rng = np.random.default_rng(seed)
    bend, twist = rng.normal(0, 0.2, (n, 16)), rng.normal(0, 0.2, (n, 16))
    raw = calibration.raw(bend, twist)
    lines = [f"{k} {k / 110:.6f} " + " ".join(map(str, row)) for k, row in enumerate(raw)]
    path.write_text("# measurand raw\n" + "\n".join(lines) + "\n")
    return bend, twist


def test_import_raw_applies_the_calibration(tmp_path):
    cal = Calibration(np.linspace(30000, 34000, 32), np.full(32, 1.5e-4))
    bend, twist = _raw_file(tmp_path / "take.txt", cal)
    out = import_raw(tmp_path / "take.txt", cal, tmp_path / "take.tape.csv")
    rec = read_recording(out)
    assert len(rec) == 40 and rec.rate_hz == pytest.approx(110, rel=1e-3)
    half_count = 1.5e-4 / 2 + 1e-12
    assert (
        np.abs(rec.bend - bend).max() <= half_count
        and np.abs(rec.twist - twist).max() <= half_count
    )
    assert rec.meta["calibration"]["gains"][0] == 1.5e-4


def test_calibration_from_flat_and_file_round_trip(tmp_path):
    flat = 32768 + np.random.default_rng(0).normal(0, 3, (200, 32))
    cal = Calibration.from_flat(flat, gains=2e-4, notes="desk")
    assert np.allclose(cal.offsets, flat.mean(axis=0))
    path = cal.save(tmp_path / "c.calibration.json")
    from studio.capture._calibration import load_calibration

    back = load_calibration(path)
    assert np.array_equal(back.offsets, cal.offsets) and back.notes == "desk"
    (tmp_path / "bad.json").write_text(json.dumps({"format": "other"}))
    with pytest.raises(CaptureError, match="not a calibration"):
        load_calibration(tmp_path / "bad.json")


def test_raw_file_with_too_few_channels_names_the_line(tmp_path):
    (tmp_path / "short.txt").write_text("0 0.0 1 2 3\n")
    with pytest.raises(RecordingError, match=r"short.txt, line 1: 3 raw channels"):
        import_raw(tmp_path / "short.txt", Calibration.identity(), tmp_path / "o.tape.csv")


def test_record_info_and_import_verbs(tmp_path, capsys):
    out = tmp_path / "x.tape.csv"
    assert (
        main(
            [
                "record",
                "--source",
                "simulator",
                "--seconds",
                "0.5",
                "--out",
                str(out),
                "--operator",
                "ada",
            ]
        )
        == 0
    )
    rec = read_recording(out)
    assert len(rec) == 55 and not rec.recovered and rec.meta["operator"] == "ada"
    assert main(["info", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["frames"] == 55
    cal = Calibration.identity()
    cal.save(tmp_path / "cal.json")
    _raw_file(tmp_path / "raw.txt", cal)
    assert (
        main(
            [
                "import-raw",
                str(tmp_path / "raw.txt"),
                "--calibration",
                str(tmp_path / "cal.json"),
                "--out",
                str(tmp_path / "r.tape.csv"),
            ]
        )
        == 0
    )
    assert len(read_recording(tmp_path / "r.tape.csv")) == 40
    # a user error is one sentence on stderr and exit code 2, never a traceback
    (tmp_path / "junk.tape.csv").write_text("hello\n")
    assert main(["info", str(tmp_path / "junk.tape.csv")]) == 2
    assert "line 1: not a Teach Studio recording" in capsys.readouterr().err


def test_ctrl_c_during_record_keeps_every_frame(tmp_path):
    import signal
    import subprocess
    import sys
    import time

    from tests.conftest import interruptible, signal_masks

    out = tmp_path / "interrupted.tape.csv"
    child = subprocess.Popen(
        [sys.executable, "-m", "studio.cli", "record", "--out", str(out)],
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=interruptible,
    )
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:  # wait for frames on disk
        if out.exists() and out.read_text().count("\n") > 60:
            break
        time.sleep(0.1)
    masks = signal_masks(child.pid)
    child.send_signal(signal.SIGINT)
    try:  # it then summarises the file: slow on a busy machine
        _, err = child.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        child.kill()
        raise AssertionError(f"Ctrl-C did not stop studio record; its signals: {masks}") from None
    rec = read_recording(out)
    assert not rec.recovered and len(rec) > 50  # closed cleanly with its '# end' line
    assert "every captured frame is kept" in err


def test_record_a_recording_as_fast_as_possible_copies_its_frames(tmp_path, capsys):
    from studio.capture import RecordingWriter, simulate

    source = tmp_path / "src.tape.csv"
    frames = simulate(3.0, seed=1).frames  # 3 s: real-time playback would take that long
    with RecordingWriter(source, 16) as w:
        w.write_many(frames)
    copy = tmp_path / "copy.tape.csv"
    args = ["record", "--source", str(source), "--speed", "0", "--out", str(copy)]
    assert main(args) == 0
    got = read_recording(copy).frames()
    assert all(a.same_as(b) for a, b in zip(frames, got, strict=True))
    args = ["record", "--source", str(source), "--speed", "-1", "--out", str(tmp_path / "n")]
    assert main(args) == 2
    assert "--speed is -1; give a positive speed" in capsys.readouterr().err


def test_info_tells_a_capture_in_progress_from_an_interrupted_one(tmp_path, capsys):
    from studio.capture import RecordingWriter, TapeFrame

    path = tmp_path / "live.tape.csv"
    writer = RecordingWriter(path, 16)
    writer.write_many([TapeFrame(i / 110, i, np.zeros(16), np.zeros(16)) for i in range(30)])
    writer.flush()
    assert main(["info", "--json", str(path)]) == 0
    live = json.loads(capsys.readouterr().out)
    assert live["live"] and not live["recovered"] and live["frames"] == 30
    killed = tmp_path / "killed.tape.csv"  # the same bytes with no writer: an interrupted capture
    killed.write_bytes(path.read_bytes())
    writer.close()
    assert main(["info", "--json", str(killed)]) == 0
    gone = json.loads(capsys.readouterr().out)
    assert gone["recovered"] and not gone["live"]


def _one_sentence(capsys, verb: str) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"studio {verb}: ") and "Traceback" not in err[0]
    return err[0]


@pytest.mark.parametrize(
    ("to", "says"),
    [
        ("notanaddress", "notanaddress:47110 is not an address"),
        ("256.1.1.1:8650", "256.1.1.1:8650 is not an address"),
        ("127.0.0.1:99999", "no valid port"),
        ("127.0.0.1:0", "no valid port"),
    ],
)
def test_a_bad_bridge_address_is_one_sentence(to, says, capsys):
    assert main(["bridge", "--to", to, "--seconds", "1"]) == 2
    assert says in _one_sentence(capsys, "bridge")


@pytest.mark.parametrize("seconds", ["-3", "0", "nan", "inf"])
def test_record_refuses_a_duration_that_is_not_positive(seconds, tmp_path, capsys):
    out = tmp_path / "x.tape.csv"
    assert main(["record", "--seconds", seconds, "--out", str(out)]) == 2
    assert "--seconds is" in _one_sentence(capsys, "record")
    assert not out.exists()  # no empty recording


def test_record_from_a_silent_network_gives_up_with_a_sentence(tmp_path, capsys, monkeypatch):
    """--seconds counts the frames' time from the first frame on, so without a sender it would
    never end: --wait gives up, and leaves no empty recording behind.

    The least wait for a first frame (30 s, tests/capture/test_first_frame_wait.py) is set to
    --wait's here, so the test waits --wait's half second, not 30 s of real time."""
    import socket

    import studio.capture._capture_loop as loop

    monkeypatch.setattr(loop, "FIRST_FRAME_SECONDS", 0.5)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    out = tmp_path / "x.tape.csv"
    args = ["record", "--source", f"udp:{port}", "--seconds", "3", "--wait", "0.5"]
    assert main([*args, "--out", str(out)]) == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert "no frame arrived from the network source" in line and "nothing was recorded" in line
    assert "studio bridge" in line and not out.exists()


def test_record_creates_only_the_last_folder_of_out(tmp_path, capsys):
    out = tmp_path / "missing" / "dir" / "x.tape.csv"
    assert main(["record", "--seconds", "0.1", "--out", str(out)]) == 2
    assert f"the folder {tmp_path / 'missing'} does not exist" in _one_sentence(capsys, "record")
    assert not (tmp_path / "missing").exists()
    out = tmp_path / "new" / "x.tape.csv"  # one new level is what --out asks for
    assert main(["record", "--seconds", "0.1", "--out", str(out)]) == 0
    assert len(read_recording(out)) == 11


def test_info_shows_a_demonstrations_times_in_seconds_and_its_fit_in_millimetres(capsys):
    from studio.samples import SAMPLES_DIR

    assert main(["info", str(SAMPLES_DIR / "sample-reach-2.demo.json")]) == 0
    out = capsys.readouterr().out
    assert "segment       1.000 s to 3.491 s (2.491 s)" in out
    assert "reached_at    2.245 s" in out and "residual_max  9.7 mm" in out
    assert "3.4909090909090907" not in out and "np.float64" not in out
    assert main(["info", "--json", str(SAMPLES_DIR / "sample-reach-2.demo.json")]) == 0
    assert json.loads(capsys.readouterr().out)["segment"] == [1.0, 3.4909090909090907]


def test_record_beyond_loopback_needs_a_token_and_leaves_no_file(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("STUDIO_TOKEN", raising=False)
    out = tmp_path / "x.tape.csv"
    assert main(["record", "--source", "udp:0.0.0.0:0", "--out", str(out)]) == 2
    assert "needs a token" in _one_sentence(capsys, "record") and not out.exists()
