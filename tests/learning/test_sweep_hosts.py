"""A pid names a process only on its own host: run and sweep records carry the host beside the pid,
and only the pid's own host judges whether it lives.

On a cluster the data folder is shared: the page (or a resumed driver) on one node reads the
status of a trial training on another node. Judged by this machine's process table, that trial's
pid is dead (or worse, some unrelated local process), and the page would rewrite a live trial as
stopped. These tests need no Ray: the records are written and read as any process would.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from studio.learning import ArmGrid, DynaQConfig
from studio.learning.runs._folder import RunFolder, RunRecord
from studio.learning.runs._owner import on_this_host, pid_alive, this_host
from studio.learning.sweeps._folder import prepare_folder as _prepare
from studio.learning.sweeps._list import load_sweep
from studio.learning.sweeps._spec import parse_sweep_spec

OTHER_HOST = {"hostname": f"not-{socket.gethostname()}", "node": "a0b1c2"}


def dead_pid() -> int:
    """The pid of a process that has ended (and been reaped)."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def running_run(tmp_path: Path) -> RunFolder:
    """A running run's folder as written before owner locks: judged by its pid and host."""
    record = RunRecord.for_arm_grid(ArmGrid(), DynaQConfig(), 2, 5, seed=0, origin="cli")
    run = RunFolder.create(tmp_path, record, name="r", status="running")
    run.disown()
    (run.path / "owner.lock").unlink()
    return run


def write_status(run: RunFolder, **fields) -> bytes:
    path = run.path / "status.json"
    data = json.loads(path.read_text())
    data.update(fields)
    path.write_text(json.dumps(data))
    return path.read_bytes()


def test_a_running_runs_status_names_its_process_and_host(tmp_path: Path) -> None:
    run = running_run(tmp_path)
    data = json.loads((run.path / "status.json").read_text())
    assert data["pid"] == os.getpid()
    assert data["host"] == {"hostname": socket.gethostname(), "node": None}  # no Ray here
    assert data["host"] == this_host()


def test_a_dead_pid_on_this_host_reads_as_stopped(tmp_path: Path) -> None:
    run = running_run(tmp_path)
    write_status(run, pid=dead_pid(), host=this_host())
    loaded = RunFolder.load(run.path)
    assert loaded.status == "stopped" and loaded.interrupted
    loaded.recover()
    assert json.loads((run.path / "status.json").read_text())["status"] == "stopped"


def test_a_record_without_a_host_is_judged_here(tmp_path: Path) -> None:
    run = running_run(tmp_path)  # as written before hosts were recorded
    write_status(run, pid=dead_pid(), host=None)
    assert RunFolder.load(run.path).status == "stopped"


def test_a_pid_on_another_host_is_not_judged_here(tmp_path: Path) -> None:
    run = running_run(tmp_path)
    for pid in (dead_pid(), os.getpid()):  # gone here, or this very process here: neither counts
        before = write_status(run, pid=pid, host=OTHER_HOST)
        loaded = RunFolder.load(run.path)
        assert loaded.status == "running" and not loaded.interrupted
        assert (loaded.pid, loaded.host) == (pid, OTHER_HOST)
        loaded.recover()  # what the page does with a run it reads as interrupted
        assert (run.path / "status.json").read_bytes() == before


@settings(max_examples=50, deadline=None)
@given(hostname=st.text(min_size=1, max_size=40), pid=st.integers(1, 2**22))
def test_only_the_pids_own_host_judges_it(hostname: str, pid: int) -> None:
    host = {"hostname": hostname, "node": None}
    if hostname == socket.gethostname():
        assert on_this_host(host)
        assert pid_alive(pid, host) == pid_alive(pid)
    else:
        assert not on_this_host(host) and pid_alive(pid, host)


def test_a_sweep_driver_on_another_host_is_not_judged_here(tmp_path: Path) -> None:
    spec = parse_sweep_spec(
        {
            "name": "hosts",
            "task": "arm-grid",
            "experiments": 1,
            "episodes": 2,
            "space": {"planning": ["zero"]},
        }
    )
    folder = _prepare(tmp_path, spec, resume=False)
    data = json.loads((folder / "sweep.json").read_text())
    assert data["pid"] == os.getpid() and data["host"] == this_host()

    data["pid"] = dead_pid()
    (folder / "sweep.json").write_text(json.dumps(data))
    assert load_sweep(tmp_path, "hosts").status == "interrupted"  # its driver died here

    data["host"] = OTHER_HOST
    (folder / "sweep.json").write_text(json.dumps(data))
    assert load_sweep(tmp_path, "hosts").status == "running"  # its driver's host judges it
