"""A run is alive while its owner process holds its ``owner.lock``, whatever its pid now names.

After a crash or a reboot, the pid in a ``running`` status may name an unrelated live process
(here: this test's own pid, or pid 1), and a folder copied from another machine names another
host. Neither may keep the run "running" forever: the lock died with its owner. Folders from
before owner locks are judged by the pid and that process's start time, and the user can mark a
stale one stopped.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from studio.learning import ArmGrid, DynaQConfig, LearningError, RunFolder, RunRecord
from studio.learning.runs._owner import owner_alive, process_started

OTHER_HOST = {"hostname": f"not-{socket.gethostname()}", "node": None}


def _record() -> RunRecord:
    return RunRecord.for_arm_grid(
        ArmGrid(joints=2, bins=5, goal=(2, 2)), DynaQConfig(planning="zero"), 2, 5, origin="cli"
    )


def _status(run: RunFolder, **fields: object) -> bytes:
    path = run.path / "status.json"
    path.write_text(json.dumps({**json.loads(path.read_text()), **fields}))
    return path.read_bytes()


@pytest.mark.parametrize(
    "owner",
    [
        {"pid": os.getpid()},  # a live process, but not the one that trained it
        {"pid": 1},
        {"pid": os.getpid(), "host": OTHER_HOST},  # a folder copied from another machine
        {"pid": 1, "host": OTHER_HOST},
    ],
)
def test_a_run_whose_owner_is_gone_reads_stopped_whatever_its_pid_names(tmp_path, owner):
    run = RunFolder.create(tmp_path, _record(), name="r", status="running")
    written = _status(run, **owner)
    run.disown()  # what the owner's death does to its lock
    loaded = RunFolder.load(run.path)
    assert loaded.status == "stopped" and loaded.interrupted
    assert (run.path / "status.json").read_bytes() == written  # reading it writes nothing
    loaded.delete()
    assert not run.path.exists()


def _owner_process(folder: Path, status: str) -> subprocess.Popen:
    """Another process that creates a run folder and owns it until killed."""
    code = (
        "import sys; from pathlib import Path\n"
        "from studio.learning import ArmGrid, DynaQConfig, RunFolder, RunRecord\n"
        "r = RunRecord.for_arm_grid(ArmGrid(joints=2, bins=5, goal=(2, 2)), DynaQConfig(), 2, 5)\n"
        f"run = RunFolder.create(Path({str(folder)!r}), r, name='r', status={status!r})\n"
        "print('ready', flush=True); sys.stdin.read()\n"
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    assert proc.stdout.readline().strip() == "ready"  # the event, not a sleep
    return proc


@pytest.mark.parametrize("status", ["queued", "running"])
def test_a_live_owner_in_another_process_keeps_its_run_alive_until_it_dies(tmp_path, status):
    proc = _owner_process(tmp_path, status)
    try:
        path = tmp_path / "r"
        _status(RunFolder.load(path), host=OTHER_HOST, pid=12345678)  # whatever the record says
        loaded = RunFolder.load(path)
        assert loaded.status == status and not loaded.interrupted
        assert owner_alive(path) is True
        with pytest.raises(LearningError, match="another live process"):
            loaded.mark_stopped()
        with pytest.raises(LearningError, match="another live process"):
            loaded.delete()
        assert (path / "config.json").exists()
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    assert owner_alive(path) is False  # the lock died with it
    assert RunFolder.load(path).status == "stopped"


def _legacy(tmp_path: Path, **owner: object) -> RunFolder:
    """A running run's folder as written before owner locks."""
    run = RunFolder.create(tmp_path, _record(), name="old", status="running")
    run.disown()
    (run.path / "owner.lock").unlink()
    _status(run, **owner)
    return RunFolder.load(run.path)


def test_an_old_folder_whose_pid_was_reused_reads_stopped(tmp_path):
    sleeper = subprocess.Popen(
        [sys.executable, "-c", "import sys; sys.stdin.read()"], stdin=subprocess.PIPE
    )
    try:
        assert process_started(sleeper.pid) is not None
        run = _legacy(tmp_path, pid=sleeper.pid, started="2020-01-01T00:00:00+00:00")
        assert run.status == "stopped" and run.interrupted  # that pid's process began later
        fresh = _legacy(tmp_path / "b", pid=sleeper.pid, started=run.created)
        assert fresh.status == "running"  # a pid whose process began before the run: it may be it
    finally:
        sleeper.kill()
        sleeper.wait()


def test_a_stale_old_folder_on_another_host_can_be_marked_stopped(tmp_path):
    run = _legacy(tmp_path, pid=1, host=OTHER_HOST)
    assert run.status == "running"  # this host cannot judge another's pid
    run.mark_stopped()
    again = RunFolder.load(run.path)
    assert again.status == "stopped" and "Marked stopped" in again.error
    assert json.loads((run.path / "status.json").read_text())["status"] == "stopped"
