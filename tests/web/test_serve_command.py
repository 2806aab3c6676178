"""``studio serve``: flags become Settings; a non-loopback host warns; a bad source is refused."""

from __future__ import annotations

import socket
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest

import studio.web
from studio.cli import main
from tests.conftest import free_port


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
            except (urllib.error.URLError, OSError):  # refused, or queued until the app is up
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


def test_a_taken_port_is_one_sentence(capsys, tmp_path):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        code = main(["serve", "--no-browser", "--data-dir", str(tmp_path), "--port", str(port)])
    out, err = capsys.readouterr()
    assert code != 0
    assert "open http" not in out
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and f"Port {port}" in lines[0] and "--port" in lines[0]
    assert "Errno" not in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("flags", "words"),
    [
        (["--port", "99999"], ("--port 99999", "65535")),
        (["--viser-port", "0"], ("--viser-port 0", "65535")),
        (["--data-dir", "/proc/x/y"], ("/proc/x/y", "--data-dir")),
    ],
)
def test_bad_flags_are_one_sentence(capsys, flags, words):
    assert main(["serve", "--no-browser", *flags]) == 2
    out, err = capsys.readouterr()
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and all(w in lines[0] for w in words), err
    assert "Traceback" not in err and "open http" not in out


def _start(tmp_path: Path, port: int, viser_port: int) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [sys.executable, "-m", "studio", "serve", "--no-browser", "--data-dir", str(tmp_path),
         "--port", str(port), "--viser-port", str(viser_port)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
    )  # fmt: skip


def _config(port: int, proc: subprocess.Popen[bytes]) -> dict:
    import json

    deadline = time.monotonic() + 90
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/config", timeout=2) as r:
                return json.loads(r.read())
        except (urllib.error.URLError, OSError):  # refused, or queued until the app is up
            assert proc.poll() is None, proc.stdout.read().decode() if proc.stdout else ""
            time.sleep(0.2)
    raise AssertionError("the studio did not start")


def test_two_studios_each_embed_their_own_scene(tmp_path):
    """The second studio's scene port is taken by the first: it reports the port it really
    bound, and each scene answers its own studio's instance id."""
    import json

    viser_port = free_port()
    procs = []
    try:
        configs = []
        for k in range(2):
            folder = tmp_path / f"studio{k}"
            folder.mkdir()
            port = free_port()
            procs.append(_start(folder, port, viser_port))
            configs.append((port, _config(port, procs[-1])))
        scene_ports = set()
        for port, config in configs:
            scene = config["viser_url"].rstrip("/")
            scene_ports.add(int(scene.rsplit(":", 1)[1]))
            page = f"http://127.0.0.1:{port}"
            req = urllib.request.Request(f"{scene}/studio-instance", headers={"Origin": page})
            with urllib.request.urlopen(req, timeout=5) as r:
                assert json.loads(r.read())["instance"] == config["scene_instance"]
        assert len(scene_ports) == 2 and viser_port in scene_ports
        assert configs[0][1]["scene_instance"] != configs[1][1]["scene_instance"]
    finally:
        for proc in procs:
            proc.terminate()
        for proc in procs:
            proc.wait(timeout=20)


@pytest.mark.parametrize("comes_up", [True, False])
def test_the_learner_is_compiled_in_the_background_once_the_api_is_up(monkeypatch, comes_up):
    import types

    from studio.web import _serve

    calls: list[int] = []
    monkeypatch.setattr(_serve, "prepare_in_background", lambda: calls.append(1))
    monkeypatch.setattr(_serve, "prepare_arm_ik_in_background", lambda: calls.append(2))
    http = types.SimpleNamespace(started=False, should_exit=False)
    waiter = threading.Thread(target=_serve._prepare_when_up, args=(http,))
    waiter.start()
    if comes_up:
        http.started = True
    else:  # stopped before it ever answered: nothing to prepare for
        http.should_exit = True
    waiter.join(30)
    assert calls == ([1, 2] if comes_up else [])  # the learners' kernels, then the arms' IK


def test_a_data_folder_under_a_missing_folder_is_refused_not_created(tmp_path):
    from studio.web._serve import ServeError, prepare_data_dir

    with pytest.raises(ServeError, match="does not exist; create it first"):
        prepare_data_dir(tmp_path / "missing" / "data")
    assert not (tmp_path / "missing").exists()
    prepare_data_dir(tmp_path / "data")  # the last level is created, with its subfolders
    assert (tmp_path / "data" / "recordings").is_dir()
