"""The serial source through the API: a calibrated tape on a pty, and a bad calibration file."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np

from studio.capture import Calibration, ShapeTapeEmulator, read_recording
from studio.samples import SAMPLES_DIR
from tests.web.conftest import wait_captured, wait_for

SAMPLE = SAMPLES_DIR / "sample-reach-1.tape.csv"
GAIN = 2e-4
"""rad per count: the calibration's resolution, so angles come back within one count."""


def _angles(k: int) -> tuple[np.ndarray, np.ndarray, int]:
    return np.linspace(-0.6, 0.6, 16) * np.cos(k / 25), np.full(16, 0.002 * (k % 40)), 0


def test_a_serial_tape_with_its_calibration_is_captured_in_radians(client, tmp_path):
    calibration = Calibration(np.full(32, 30000.0), np.full(32, GAIN), serial=5001)
    calibration.save(tmp_path / "tape.calibration.json")
    emulator = ShapeTapeEmulator(_angles, calibration).start()
    try:
        r = client.put(
            "/api/source",
            json={
                "kind": "serial",
                "device": emulator.port,
                "calibration": f" {tmp_path / 'tape.calibration.json'} ",
            },
        )
        assert r.status_code == 200, r.text
        assert r.json()["kind"] == "serial" and r.json()["error"] is None
        assert wait_for(lambda: client.get("/api/source").json()["frames"] > 10, 10)
        assert client.post("/api/capture/start", json={"name": "serial-take"}).status_code == 200
        wait_captured(client, 1.0)
        assert client.post("/api/capture/stop").status_code == 200
    finally:
        emulator.unplug()
    rec = read_recording(client.app.state.studio.recordings.path("serial-take"))
    assert len(rec.frame) > 20
    for k, bend, twist in zip(rec.frame, rec.bend, rec.twist, strict=True):
        want_bend, want_twist, _ = _angles(int(k))  # the tape's own counter numbers the frames
        assert np.allclose(bend, want_bend, atol=GAIN) and np.allclose(twist, want_twist, atol=GAIN)
    # Unplugged: the source says so, and the studio goes on.
    assert wait_for(lambda: client.get("/api/source").json()["error"] is not None, 10)
    assert "disconnected" in client.get("/api/source").json()["error"]


def _playing(client, tmp_path) -> None:
    (tmp_path / "recordings").mkdir(exist_ok=True)
    shutil.copy(SAMPLE, tmp_path / "recordings" / "take.tape.csv")
    assert client.put("/api/source", json={"kind": "recording", "recording": "take"}).is_success
    assert wait_for(lambda: client.get("/api/source").json()["frames"] > 0, 10)


def _switched_to_serial_with_one_error(client, answer, words: str) -> None:
    """A failed switch leaves one state: the old source stopped, serial selected, one error."""
    assert answer.status_code == 200, answer.text
    for source in (answer.json(), client.get("/api/source").json()):
        assert source["kind"] == "serial" and source["running"] is False
        assert source["recording"] is None and source["frames"] == 0
        assert words in source["error"]
    assert client.app.state.studio.pipeline.source is None  # the recording no longer plays


def test_a_missing_calibration_file_switches_to_serial_showing_why(client, tmp_path):
    _playing(client, tmp_path)
    r = client.put(
        "/api/source",
        json={"kind": "serial", "device": "/dev/ttyUSB0", "calibration": "/nowhere/cal.json"},
    )
    _switched_to_serial_with_one_error(client, r, "/nowhere/cal.json")


def test_without_pyserial_the_switch_names_the_readme_install(client, tmp_path, monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_serial(name, *args, **kwargs):
        if name == "serial" or name.startswith("serial."):
            raise ImportError("No module named 'serial'")
        return real_import(name, *args, **kwargs)

    _playing(client, tmp_path)
    monkeypatch.setattr(builtins, "__import__", no_serial)
    r = client.put("/api/source", json={"kind": "serial", "device": "/dev/ttyUSB0"})
    monkeypatch.undo()
    _switched_to_serial_with_one_error(client, r, "pyserial")
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    (install,) = re.findall(r"`(pip install [^`]*\[serial\][^`]*)`", r.json()["error"])
    assert f"`{install}`" in readme  # the page's hint is the README's command, word for word


def test_a_switch_without_a_device_is_refused_and_changes_nothing(client, tmp_path):
    _playing(client, tmp_path)
    r = client.put("/api/source", json={"kind": "serial", "device": ""})
    assert r.status_code == 422 and "device is missing" in r.json()["detail"]
    source = client.get("/api/source").json()
    assert source["kind"] == "recording" and source["error"] is None and source["running"]
