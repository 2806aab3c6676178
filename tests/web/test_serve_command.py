"""``studio serve``: flags become Settings; a non-loopback host warns; a bad source is refused."""

from __future__ import annotations

import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest

import studio.web
from studio.cli import main


@pytest.fixture
def served(monkeypatch):
    """Capture what ``studio serve`` would serve instead of starting servers."""
    calls: list[tuple] = []
    monkeypatch.setattr(
        studio.web, "serve", lambda settings, open_browser: calls.append((settings, open_browser))
    )
    return calls


def test_defaults_bind_loopback(served, capsys):
    assert main(["serve", "--no-browser"]) == 0
    ((settings, open_browser),) = served
    assert settings.host == "127.0.0.1" and settings.port == 8000 and settings.viser_port == 8080
    assert settings.data_dir == Path(".") and settings.source == "simulator"
    assert open_browser is False and settings.upload_limit_bytes == 50_000_000
    assert "WARNING" not in capsys.readouterr().err


def test_upload_limit_flag(served, capsys):
    assert main(["serve", "--upload-limit-mb", "2.5"]) == 0
    assert served[0][0].upload_limit_bytes == 2_500_000
    assert main(["serve", "--upload-limit-mb", "0"]) == 2
    assert "positive size" in capsys.readouterr().err


def test_serve_is_the_default_verb(served):
    assert main(["--port", "9001", "--no-browser"]) == 0
    assert served[0][0].port == 9001


def test_flags_and_the_open_host_warning(served, capsys, tmp_path):
    args = ["serve", "--host", "0.0.0.0", "--port", "9000", "--viser-port", "9100"]
    args += ["--data-dir", str(tmp_path), "--allow-host", "lab-pc"]
    assert main(args) == 0
    settings, open_browser = served[0]
    assert settings.host == "0.0.0.0" and settings.port == 9000 and settings.viser_port == 9100
    assert settings.data_dir == tmp_path and open_browser is True
    assert "lab-pc" in settings.trusted_hosts()
    assert socket.gethostname() in settings.trusted_hosts()
    assert "WARNING" in capsys.readouterr().err


def test_a_missing_source_is_refused(served, capsys, tmp_path):
    assert main(["serve", "--data-dir", str(tmp_path), "--source", "nope"]) == 2
    assert "neither 'simulator'" in capsys.readouterr().err
    assert not served


def test_a_recording_source_by_name_or_path(served, tmp_path):
    (tmp_path / "recordings").mkdir()
    (tmp_path / "recordings" / "take.tape.csv").write_text("x")
    assert main(["serve", "--data-dir", str(tmp_path), "--source", "take"]) == 0
    assert served[-1][0].source == "take"
    other = tmp_path / "elsewhere.tape.csv"
    other.write_text("x")
    assert main(["serve", "--data-dir", str(tmp_path), "--source", str(other)]) == 0
    assert served[-1][0].source == str(other)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_the_real_server_starts_answers_and_stops(tmp_path):
    port, viser_port = free_port(), free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "studio", "serve", "--no-browser", "--data-dir", str(tmp_path),
         "--port", str(port), "--viser-port", str(viser_port)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
    )  # fmt: skip
    try:
        url = f"http://127.0.0.1:{port}/api/config"
        deadline = time.monotonic() + 60
        config = None
        while time.monotonic() < deadline:
            try:
                with urllib.request.urlopen(url, timeout=2) as r:
                    config = r.read().decode()
                break
            except (urllib.error.URLError, ConnectionError):
                time.sleep(0.2)
        assert config is not None and f":{viser_port}" in config
        with urllib.request.urlopen(f"http://127.0.0.1:{viser_port}/", timeout=5) as r:
            assert r.status == 200  # the viser scene is served too
        bad = urllib.request.Request(url, headers={"Host": "evil.example"})
        with pytest.raises(urllib.error.HTTPError) as err:
            urllib.request.urlopen(bad, timeout=5)
        assert err.value.code == 400
    finally:
        proc.terminate()
        proc.wait(timeout=20)
