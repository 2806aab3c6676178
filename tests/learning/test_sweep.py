"""Sweeps on Ray Tune: spec checks, trials equal serial runs, retries, resumption, two nodes.

One local Ray (2 CPUs) is shared by the in-process tests of this module; the interrupted sweep
and the two-node cluster run ``studio sweep`` in subprocesses, as a user would.
"""

from __future__ import annotations

import ipaddress
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from studio.learning import ArmGrid, DynaQConfig, generate_demonstrations, run_experiments
from studio.learning.runs._folder import RunFolder
from studio.learning.sweeps._folder import (
    SUMMARY_FILE,
    record_trial_end,
    sweep_folder,
    trial_records,
    trial_run_path,
)
from studio.learning.sweeps._ray import _await_stopped_saves, run_sweep
from studio.learning.sweeps._spec import SweepError, load_sweep_spec, parse_sweep_spec, trial_record
from tests.conftest import free_port as _free_port
from tests.conftest import require

try:
    import ray
except ImportError:  # pragma: no cover - the test extra installs it
    ray = None

REPO = Path(__file__).resolve().parents[2]
RAY_ENV = {
    "RAY_USAGE_STATS_ENABLED": "0",
    "RAY_AUTH_MODE": "disabled",  # a loopback test cluster; `ray start` would enable tokens
    # no idle worker per CPU when a driver connects: Tune's trials never use them (a sweep's own
    # local Ray is started so too)
    "RAY_prestart_worker_first_driver": "0",
}
WAIT_SECONDS = 120.0


def wait_for(condition, what: str, timeout: float = WAIT_SECONDS, proc=None):
    """Poll ``condition`` until it returns a truthy value (the event, never a fixed sleep)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        if proc is not None and proc.poll() is not None:
            out = proc.stdout.read() if proc.stdout else ""
            raise AssertionError(f"process ended (rc {proc.returncode}) before {what}: {out}")
        time.sleep(0.02)
    raise AssertionError(f"timed out waiting for {what}")


def spec_dict(**overrides) -> dict:
    data = {
        "name": "s",
        "task": "arm-grid",
        "seeds": [0, 1],
        "experiments": 2,
        "episodes": 20,
        "fixed": {"planning_steps": 10},
        "space": {"planning": ["zero", "full"]},
    }
    data.update(overrides)
    return {k: v for k, v in data.items() if v is not None}


def write_spec(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def run_python(script: str) -> subprocess.CompletedProcess:
    """``script`` run by a new Python of this checkout, which must end well."""
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=WAIT_SECONDS,
        cwd=REPO, env={**os.environ, "PYTHONPATH": str(REPO)},
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    return proc


# ----------------------------------------------------------------------------- the spec


def test_example_spec_is_valid_and_is_the_papers_figure_5() -> None:
    spec = load_sweep_spec(REPO / "sweeps" / "planning.toml")
    trials = spec.trials()
    settings = {(t.settings["planning"], t.settings["demonstrations"]) for t in trials}
    assert settings == {(p, d) for p in ("zero", "full", "soft") for d in (0, 20)}
    assert len(trials) == 6 * len(spec.seeds)
    assert len({t.key for t in trials}) == len(trials)


def test_grid_search_is_every_combination_times_every_seed() -> None:
    spec = parse_sweep_spec(
        spec_dict(seeds=3, space={"planning": ["zero", "full"], "alpha": [0.1, 0.2, 0.3]})
    )
    trials = spec.trials()
    assert len(trials) == 2 * 3 * 3
    assert {(t.settings["planning"], t.settings["alpha"], t.seed) for t in trials} == {
        (p, a, s) for p in ("zero", "full") for a in (0.1, 0.2, 0.3) for s in range(3)
    }


def test_random_search_draws_within_the_bounds_and_repeats_with_its_seed() -> None:
    space = {
        "alpha": {"uniform": [0.05, 0.5]},
        "epsilon": {"loguniform": [0.01, 0.3]},
        "planning_steps": {"randint": [1, 5]},
        "planning": ["zero", "soft"],
    }
    data = spec_dict(space=space, fixed={}, search={"kind": "random", "samples": 40, "seed": 7})
    trials = parse_sweep_spec(data).trials()
    assert len(trials) == 40 * 2
    for t in trials:
        assert 0.05 <= t.settings["alpha"] <= 0.5
        assert 0.01 <= t.settings["epsilon"] <= 0.3
        assert t.settings["planning_steps"] in range(1, 6)
        assert t.settings["planning"] in ("zero", "soft")
    assert {t.settings["planning_steps"] for t in trials} == set(range(1, 6))
    assert parse_sweep_spec(data).trials() == trials
    other = parse_sweep_spec({**data, "search": {"kind": "random", "samples": 40, "seed": 8}})
    assert other.trials() != trials


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"space": {"alhpa": [0.1]}}, "alhpa"),  # an unknown setting
        ({"fixed": {"planing": "full"}}, "planing"),
        ({"space": {"planning": []}}, "planning"),  # an empty space
        ({"space": {}}, "[space]"),
        ({"space": {"alpha": [0.1, 1.5]}}, "alpha"),  # out of range, as DynaQConfig says
        ({"space": {"bins": [11, 1]}}, "bins"),  # as ArmGrid says
        ({"space": {"planning": ["zero", "dreaming"]}}, "planning"),
        ({"space": {"joints": [3, 6]}, "fixed": {"bins": 11}}, "joints"),  # too big a table
        ({"experiments": 5000}, "experiments"),  # as check_budget says
        ({"space": {"demonstrations": [0, 30]}}, "demonstrations"),  # more than episodes
        ({"seeds": [-1]}, "seed"),
        ({"task": None}, "task"),  # a missing task
        ({"task": "juggling"}, "task"),
        ({"space": {"alpha": {"uniform": [0.1, 0.5]}}}, "alpha"),  # a distribution in a grid
        (
            {
                "space": {"alpha": {"uniform": [0.5, 2.0]}},
                "search": {"kind": "random", "samples": 3},
            },
            "alpha",
        ),
        ({"metric": {"name": "happiness"}}, "metric"),
        ({"scheduler": {"grace_episodes": 0}}, "grace_episodes"),
        ({"episodes": None}, "episodes"),
        ({"task": "arm-reach", "space": {"tiles": [8, 0]}}, "tiles"),  # as TileCoding says
        ({"task": "arm-reach", "space": {"joints": [2]}}, "joints"),  # as ArmReach says
        ({"task": "arm-reach", "space": {"demonstrations": [1]}}, "demonstrations"),
        ({"task": "arm-reach"}, "level_steps"),  # no shortest path to scale a level by
    ],
)
def test_a_bad_spec_is_one_sentence_naming_the_field(change: dict, field: str) -> None:
    data = spec_dict()
    for key, value in change.items():
        if value is None:
            data.pop(key, None)
        else:
            data[key] = value
    with pytest.raises(SweepError) as err:
        parse_sweep_spec(data, "bad.toml")
    message = str(err.value)
    assert field in message and message.startswith("bad.toml"), message
    assert "\n" not in message and message.endswith("."), message


def test_a_huge_seed_count_is_refused_before_any_seed_is_listed() -> None:
    """seeds = 1000000000 is refused by counting; the address space of the process that parses it
    is capped at 256 MB above what it holds, so building the list of seeds would fail."""
    script = (
        "import resource\n"
        "from studio.learning.sweeps._spec import SweepError, parse_sweep_spec\n"
        "from tests.learning.test_sweep import spec_dict\n"
        "size = next(int(line.split()[1]) * 1024 for line in open('/proc/self/status')\n"
        "            if line.startswith('VmSize:'))\n"
        "resource.setrlimit(resource.RLIMIT_AS, (size + 256 * 2**20, resource.RLIM_INFINITY))\n"
        "try:\n"
        "    parse_sweep_spec(spec_dict(seeds=1_000_000_000), 'big.toml')\n"
        "except SweepError as err:\n"
        "    print(err)\n"
    )
    proc = run_python(script)
    assert proc.stdout.strip() == (
        "big.toml makes 2,000,000,000 trials, over the limit of 100,000; sweep fewer values or seeds."
    ), proc.stdout


def test_a_spec_file_that_is_not_toml_is_refused(tmp_path: Path) -> None:
    path = write_spec(tmp_path / "broken.toml", "task = arm-grid\n")
    with pytest.raises(SweepError, match="not valid TOML"):
        load_sweep_spec(path)
    with pytest.raises(SweepError, match="does not exist"):
        load_sweep_spec(tmp_path / "missing.toml")


def test_without_ray_the_error_says_how_to_install_it(monkeypatch, tmp_path: Path) -> None:
    from studio.learning.sweeps import _ray as _sweep

    monkeypatch.setitem(sys.modules, "ray", None)
    with pytest.raises(SweepError, match=r"pip install -e '\.\[cluster\]'"):
        _sweep._import_ray()


def test_an_unreachable_address_is_one_sentence(tmp_path: Path) -> None:
    spec = write_spec(tmp_path / "s.toml", 'task = "arm-grid"\nexperiments = 1\nepisodes = 2\n'
                      '[space]\nplanning = ["zero"]\n')  # fmt: skip
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # nothing listens once it is closed
    proc = subprocess.run(
        [sys.executable, "-m", "studio", "sweep", str(spec), "--data-dir", str(tmp_path),
         "--address", f"127.0.0.1:{port}", "--no-progress"],
        capture_output=True, text=True, timeout=120, env={**os.environ, **RAY_ENV},
    )  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    line = proc.stderr.strip()
    assert "\n" not in line and f"127.0.0.1:{port}" in line and "Traceback" not in line, line
    assert not (tmp_path / "sweeps").exists()  # nothing written for a sweep that cannot run


def test_a_trials_worker_starts_without_scipy_signal() -> None:
    """Every Ray worker of a sweep imports the trial function, so the learners; scipy.signal (a
    second of CPU, only for the likeness's filter) is imported when a path is filtered, not then."""
    script = (
        "import sys\n"
        "from studio.learning.sweeps._ray import _trainable\n"
        "print(sorted(m for m in sys.modules if m.startswith('scipy.signal')))\n"
    )
    proc = run_python(script)
    assert proc.stdout.strip() == "[]", proc.stdout


def test_a_sweep_that_cannot_start_is_refused_before_ray_is_imported(tmp_path: Path) -> None:
    """A second start, or a resume, of a running sweep is refused at once: without importing Ray
    and Tune (seconds of CPU) first. The sweep's driver here is this test's process: alive. So is
    a sweep on a cluster out of reach."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # nothing listens once it is closed
    script = (
        "import json, os, sys\n"
        "from pathlib import Path\n"
        "from studio.learning.sweeps._folder import prepare_folder\n"
        "from studio.learning.sweeps._ray import run_sweep\n"
        "from studio.learning.sweeps._spec import SweepError, parse_sweep_spec\n"
        f"spec = parse_sweep_spec({spec_dict()!r})\n"
        f"data = Path({str(tmp_path)!r})\n"
        "sweep_file = prepare_folder(data, spec, False) / 'sweep.json'\n"
        "stored = json.loads(sweep_file.read_text())\n"
        "sweep_file.write_text(json.dumps({**stored, 'pid': os.getppid()}))\n"
        "for resume in (False, True):\n"
        "    try:\n"
        "        run_sweep(spec, data, resume=resume)\n"
        "    except SweepError as err:\n"
        "        print(err)\n"
        "try:\n"
        f"    run_sweep(spec, data / 'other', address='127.0.0.1:{port}')\n"
        "except SweepError as err:\n"
        "    print(err)\n"
        "print('ray' in sys.modules)\n"
    )
    lines = run_python(script).stdout.strip().splitlines()
    assert len(lines) == 4, lines
    assert all("'s' is still running" in line for line in lines[:2]), lines
    assert lines[2].startswith(f"Cannot reach a Ray cluster at 127.0.0.1:{port}"), lines
    assert lines[3] == "False", lines


# ----------------------------------------------------------------------------- on a local Ray


@pytest.fixture(scope="module")
def local_ray():
    """One local Ray with 2 CPUs for this module's in-process sweeps."""
    require(ray is not None, "ray[tune] is not installed (pip install -e '.[cluster]')")
    for key, value in RAY_ENV.items():
        os.environ.setdefault(key, value)
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        yield ray
    finally:
        ray.shutdown()


def test_trials_equal_serial_runs_seed_for_seed(local_ray, tmp_path: Path) -> None:
    """A 2-worker sweep's curves are exactly those of run_experiments with the same settings."""
    data = spec_dict(
        name="same",
        seeds=[0, 1],
        experiments=3,
        episodes=15,
        space={"planning": ["zero", "full"], "demonstrations": [0, 2]},
    )
    spec = parse_sweep_spec(data)
    seen = []
    result = run_sweep(spec, tmp_path, on_progress=lambda p: seen.append(p.done))
    assert not result.interrupted and not result.failed
    assert seen[-1] == len(spec.trials()) and seen == sorted(seen)
    grid = ArmGrid()
    for trial in spec.trials():
        run = RunFolder.load(trial_run_path(tmp_path, "same", trial.key))
        assert run.status == "done" and run.has_policy
        assert run.record.group == "same" and run.record.origin == "sweep"
        demos = generate_demonstrations(
            grid, trial.settings["demonstrations"], np.random.default_rng([trial.seed, 1])
        )
        config = DynaQConfig(planning=trial.settings["planning"], planning_steps=10)
        serial = run_experiments(grid.mdp(), config, 3, 15, trial.seed, demos, workers=1)
        np.testing.assert_array_equal(run.steps(), serial.steps)
    folder = sweep_folder(tmp_path, "same")
    lines = (folder / SUMMARY_FILE).read_text().splitlines()
    assert len(lines) == 1 + len(spec.trials())
    assert lines[0].startswith("trial,seed,planning,demonstrations,status,")
    assert all(",done," in line for line in lines[1:])
    assert (folder / "sweep.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert b"<svg" in (folder / "sweep.svg").read_bytes()[:500]
    nodes = {node["NodeID"] for node in local_ray.nodes()}
    for record in trial_records(folder).values():  # where each trial ran: node, host, worker
        assert record["node"] in nodes and record["hostname"] == socket.gethostname()
        assert isinstance(record["pid"], int) and record["pid"] != os.getpid()
    stored = json.loads((folder / "sweep.json").read_text())
    assert stored["pid"] == os.getpid() and stored["host"]["hostname"] == socket.gethostname()
    assert stored["host"]["node"] in nodes  # the driver's node


def test_continuous_joint_trials_equal_serial_runs(local_ray, tmp_path: Path) -> None:
    """The tile-coded continuous task sweeps too, each trial equal to run_experiments."""
    import gymnasium

    from studio.learning import ArmReach
    from studio.learning.tasks._gym import ARM_REACH_ID

    spec = parse_sweep_spec(
        spec_dict(
            name="reach",
            task="arm-reach",
            seeds=[0, 1],
            experiments=1,
            episodes=3,
            fixed={"joints": 3, "tiles": 4, "max_steps_per_episode": 300},
            space={"planning": ["zero", "full"]},
            metric={"name": "final_steps"},
        )
    )
    result = run_sweep(spec, tmp_path)
    assert not result.interrupted and not result.failed
    task = ArmReach(joints=3)
    for trial in spec.trials():
        run = RunFolder.load(trial_run_path(tmp_path, "reach", trial.key))
        assert run.status == "done" and run.has_policy and run.record.kind == "arm-reach"
        config = DynaQConfig(planning=trial.settings["planning"], max_steps_per_episode=300)
        serial = run_experiments(
            lambda: gymnasium.make(ARM_REACH_ID, **task.to_dict()),
            config,
            1,
            3,
            trial.seed,
            None,
            task.features(tiles=4),
            workers=1,
        )
        np.testing.assert_array_equal(run.steps(), serial.steps)


def test_a_killed_worker_is_retried_and_the_sweep_completes(local_ray, tmp_path: Path) -> None:
    spec = parse_sweep_spec(
        spec_dict(
            name="kill",
            seeds=[0, 1],
            experiments=4,
            episodes=60,
            fixed={"planning_steps": 1000},  # about a second a trial: killed mid-training
            space={"planning": ["full", "soft"]},
        )
    )
    killed: dict[str, int] = {}

    def kill_one_running_trial() -> None:
        def running():
            for status in (tmp_path / "runs" / "kill").glob("*/status.json"):
                try:
                    data = json.loads(status.read_text())
                except (OSError, ValueError):
                    continue
                if data.get("status") == "running" and data.get("pid"):
                    host = data["host"]  # the trial's worker: this machine, a Ray node
                    assert host["hostname"] == socket.gethostname() and host["node"], host
                    return status.parent.name, data["pid"]
            return None

        name, pid = wait_for(running, "a running trial")
        os.kill(pid, signal.SIGKILL)
        killed[name] = pid

    killer = threading.Thread(target=kill_one_running_trial, daemon=True)
    killer.start()
    result = run_sweep(spec, tmp_path)
    killer.join(5)
    assert killed, "no trial was killed"
    assert not result.interrupted and not result.failed
    records = trial_records(sweep_folder(tmp_path, "kill"))
    (name, pid), *_ = killed.items()
    key = name.rsplit("-", 1)[1]
    assert records[key]["attempts"] == 2, records[key]
    assert [row["status"] for row in result.rows] == ["done"] * 4
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)
    for trial in spec.trials():
        assert RunFolder.load(trial_run_path(tmp_path, "kill", trial.key)).status == "done"


def descendants(pid: int) -> set[int]:
    """``pid`` and every process under it, from ``/proc/*/stat``."""
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:  # the process ended meanwhile
            continue
        children.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    found, todo = set(), [pid]
    while todo:
        here = todo.pop()
        found.add(here)
        todo.extend(children.get(here, []))
    return found


def listening_sockets(pids: set[int]) -> list[tuple[str, str, int]]:
    """Every TCP socket listening and every UDP socket bound by ``pids``: (process name, local
    address, port), read from the processes' file descriptors and ``/proc/net/{tcp,udp}{,6}``."""
    owner: dict[str, str] = {}
    for pid in pids:
        try:
            name = Path(f"/proc/{pid}/comm").read_text().strip()
            for fd in Path(f"/proc/{pid}/fd").iterdir():
                link = os.readlink(fd)
                if link.startswith("socket:["):
                    owner[link[8:-1]] = name
        except OSError:  # the process ended meanwhile
            continue
    found = []
    for table in ("tcp", "tcp6", "udp", "udp6"):
        lines = Path(f"/proc/net/{table}").read_text().splitlines()[1:]
        for line in lines:
            cols = line.split()
            local, state, inode = cols[1], cols[3], cols[9]
            if inode not in owner or (table.startswith("tcp") and state != "0A"):  # 0A: LISTEN
                continue
            address, port = local.split(":")
            raw = b"".join(
                bytes.fromhex(address[i : i + 8])[::-1] for i in range(0, len(address), 8)
            )
            found.append((owner[inode], str(ipaddress.ip_address(raw)), int(port, 16)))
    return found


def is_loopback(address: str) -> bool:
    ip = ipaddress.ip_address(address)
    mapped = getattr(ip, "ipv4_mapped", None)
    return (mapped or ip).is_loopback


def test_a_running_sweep_listens_on_loopback_only_and_cannot_be_resumed_twice(
    tmp_path: Path,
) -> None:
    """Every socket of every process the local Ray started (GCS, raylet, agents, the worker running
    a trial) listens on loopback; ``--resume`` of the running sweep is refused, as a second start is."""
    require(ray is not None, "ray[tune] is not installed (pip install -e '.[cluster]')")
    spec_path = write_spec(
        tmp_path / "long.toml",
        'task = "arm-grid"\nseeds = [0]\nexperiments = 4\nepisodes = 100000\n'
        '[fixed]\nplanning_steps = 1000\n[space]\nplanning = ["full"]\n',
    )  # fmt: skip
    data = tmp_path / "data"
    env = {**os.environ, "RAY_USAGE_STATS_ENABLED": "0"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "studio", "sweep", str(spec_path), "--data-dir", str(data),
         "--workers", "1", "--no-progress"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
    )  # fmt: skip
    try:
        status = trial_run_path(data, "long", "t0000") / "status.json"
        wait_for(lambda: status.is_file() and '"running"' in status.read_text(), "a running trial",
                 proc=proc)  # fmt: skip
        sockets = listening_sockets(descendants(proc.pid))
        names = {name for name, _, _ in sockets}
        assert {"gcs_server", "raylet"} <= names, sockets  # the listing sees Ray's processes
        assert [s for s in sockets if not is_loopback(s[1])] == [], sockets

        again = subprocess.run(
            [sys.executable, "-m", "studio", "sweep", "--resume", "long", "--data-dir", str(data),
             "--no-progress"],
            capture_output=True, text=True, timeout=WAIT_SECONDS, env=env,
        )  # fmt: skip
        assert again.returncode == 2, again.stdout + again.stderr
        line = again.stderr.strip()
        assert "is still running" in line and "\n" not in line, line
        assert proc.poll() is None  # the first driver goes on
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=WAIT_SECONDS)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, out
    assert "studio sweep --resume long" in out, out


def test_an_interrupted_sweep_resumes_with_only_the_unfinished_trials(
    local_ray, tmp_path: Path
) -> None:
    """``studio sweep``, interrupted by Ctrl-C, then resumed. Its driver joins this module's local
    Ray (2 CPUs) rather than starting a Ray of its own (the sweep's own local Ray is interrupted in
    the loopback test)."""
    spec_path = write_spec(
        tmp_path / "resume.toml",
        'task = "arm-grid"\nseeds = [0, 1, 2, 3]\nexperiments = 2\nepisodes = 60\n'
        '[fixed]\nplanning_steps = 150\n[space]\nplanning = ["full", "soft"]\n',
    )  # fmt: skip
    data = tmp_path / "data"
    address = local_ray.get_runtime_context().gcs_address
    proc = subprocess.Popen(
        [sys.executable, "-m", "studio", "sweep", str(spec_path), "--data-dir", str(data),
         "--address", address, "--no-progress"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, **RAY_ENV},
    )  # fmt: skip
    try:
        spec = load_sweep_spec(spec_path)

        def one_done():
            for trial in spec.trials():
                with_status = trial_run_path(data, "resume", trial.key) / "status.json"
                if with_status.is_file() and '"done"' in with_status.read_text():
                    return True
            return False

        wait_for(one_done, "a finished trial", proc=proc)
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=WAIT_SECONDS)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, out
    assert "studio sweep --resume resume" in out, out

    before = {}
    for trial in spec.trials():
        path = trial_run_path(data, "resume", trial.key)
        if (path / "status.json").is_file() and '"done"' in (path / "status.json").read_text():
            before[trial.key] = (path / "steps.csv").stat().st_mtime_ns
    unfinished = {t.key for t in spec.trials()} - set(before)
    assert before and unfinished, (before, out)

    result = run_sweep(spec, data, resume=True)
    assert set(result.ran) == unfinished
    assert not result.interrupted
    assert [row["status"] for row in result.rows] == ["done"] * len(spec.trials())
    for key, mtime in before.items():  # not run again
        assert (trial_run_path(data, "resume", key) / "steps.csv").stat().st_mtime_ns == mtime
    with pytest.raises(SweepError, match="already exists"):
        run_sweep(spec, data)


def test_a_scheduler_sweep_ends_every_trial_done_or_early_stopped(
    local_ray, tmp_path: Path
) -> None:
    """ASHA stops the weak trials, and the worker of a stopped trial runs the next trial.

    Each trial takes both CPUs, so the trials run one after another in one worker: both seeds of
    full planning first, then zero planning, whose steps at the first rung are far worse, so
    ASHA stops t0002 while t0003 waits for that worker.
    """
    spec = parse_sweep_spec(
        spec_dict(
            name="asha",
            seeds=[0, 1],
            episodes=40,
            cpus_per_trial=2,
            space={"planning": ["full", "zero"]},
            scheduler={"kind": "asha", "grace_episodes": 5, "reduction_factor": 2},
            metric={"name": "mean_steps"},
        )
    )
    result = run_sweep(spec, tmp_path)
    assert not result.interrupted and not result.failed
    records = trial_records(sweep_folder(tmp_path, "asha"))
    # one of zero planning's two seeds reaches the first rung behind the others and is stopped:
    # t0002 as a rule, t0003 when the busy machine's reports come in the other order
    zero = {records[key]["status"] for key in ("t0002", "t0003")}
    assert "early-stopped" in zero and zero <= {"done", "early-stopped"}, records
    assert len({record["pid"] for record in records.values()}) == 1, records  # one worker
    for row in result.rows:
        run = RunFolder.load(trial_run_path(tmp_path, "asha", row["trial"]))
        if row["status"] == "done":
            assert row["episodes_done"] == 40 and run.status == "done"
        else:
            assert row["status"] == "early-stopped", row
            # At least the first rung. A stop that reaches learners which just ended (these
            # trials take milliseconds) finds all 40 episodes done, the run saving itself done.
            assert 5 <= row["episodes_done"] <= 40, row
            assert run.status == "stopped" or row["episodes_done"] == 40, (row, run.status)


# ----------------------------------------------------------------------------- two Ray nodes


def test_a_sweep_on_a_two_node_cluster_uses_both_nodes(tmp_path: Path) -> None:
    require(ray is not None, "ray[tune] is not installed (pip install -e '.[cluster]')")
    ray_cli = str(Path(sys.executable).with_name("ray"))
    env = {**os.environ, **RAY_ENV}
    port = _free_port()
    address = f"127.0.0.1:{port}"
    # No log monitor: it forwards the workers' output to drivers, and a sweep's driver shows none
    # (log_to_driver=False); each would poll the node's log folder ten times a second.
    common = ["--num-cpus=1", "--disable-usage-stats", "--include-log-monitor=false", "--block"]
    heads = ["--head", f"--port={port}", "--include-dashboard=false"]
    nodes: list[subprocess.Popen] = []
    try:
        # `ray start` says "Ray runtime started" once its node is registered in the cluster (it
        # waits for that itself): the event each node is waited for, with no `ray status` polls.
        for flags in (heads, [f"--address={address}"]):
            node = subprocess.Popen(
                [ray_cli, "start", *flags, *common],
                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
            )  # fmt: skip
            nodes.append(node)
            said = _lines_of(node)
            wait_for(lambda s=said: any("Ray runtime started" in x for x in s), "a node", proc=node)
        # Tune re-uses a worker whose trial ended for the next trial waiting, also one waiting
        # for the other node's worker to start. Trials of 0.02-0.3 s (40 episodes) could all run
        # in the first worker up before the other started (CI saw it once); trials of about
        # 2.5 s each give the second worker 5 s or more.
        spec = write_spec(
            tmp_path / "two.toml",
            'task = "arm-grid"\nseeds = [0, 1, 2, 3]\nexperiments = 4\nepisodes = 4000\n'
            '[fixed]\nplanning_steps = 1000\n[space]\nplanning = ["full"]\n',
        )  # fmt: skip
        data = tmp_path / "data"
        proc = subprocess.run(
            [sys.executable, "-m", "studio", "sweep", str(spec), "--data-dir", str(data),
             "--address", address, "--no-progress"],
            capture_output=True, text=True, timeout=300, env=env,
        )  # fmt: skip
        assert proc.returncode == 0, proc.stdout + proc.stderr
        records = trial_records(sweep_folder(data, "two"))
        assert len(records) == 4 and all(r["status"] == "done" for r in records.values())
        assert len({r["node"] for r in records.values()}) == 2, records
    finally:
        for node in reversed(nodes):  # a --block process stops the Ray processes it started
            node.terminate()
        for node in reversed(nodes):
            try:
                node.wait(timeout=60)
            except subprocess.TimeoutExpired:
                node.kill()
                node.wait()


def _lines_of(proc: subprocess.Popen) -> list[str]:
    """The lines ``proc`` prints, gathered by a thread as they come (its pipe never fills)."""
    lines: list[str] = []
    assert proc.stdout is not None

    def gather() -> None:
        for line in proc.stdout:
            lines.append(line)

    threading.Thread(target=gather, daemon=True).start()
    return lines


def test_the_driver_waits_for_a_stopped_trial_to_save_its_run(tmp_path: Path, monkeypatch) -> None:
    """Tune calls a trial ended as soon as its scheduler stops it; the trial's worker still runs
    to its next episode boundary to save. The sweep's last stopped trial has no next trial
    waiting on that worker, so the driver waits for the save before shutting Ray down (on a
    busy machine it was killed unsaved, and the sweep read as interrupted)."""
    from studio.learning.sweeps import _ray as _sweep_ray

    spec = parse_sweep_spec(spec_dict(name="w", seeds=[0], space={"planning": ["zero"]}))
    (trial,) = spec.trials()
    folder = sweep_folder(tmp_path, "w")
    (folder / "trials").mkdir(parents=True)
    path = trial_run_path(tmp_path, "w", trial.key)
    run = RunFolder.create(path.parent, trial_record(spec, trial), name=path.name, status="running")
    record_trial_end(folder, {"key": trial.key, "status": "early-stopped"})  # type: ignore[typeddict-item]
    looks = []
    unsaved = _sweep_ray._unsaved

    def look(data_dir, sweep, key):  # the worker reaches its episode boundary at the 3rd look
        looks.append(key)
        if len(looks) == 3:
            run.status = "stopped"
            run.save_status()
        return unsaved(data_dir, sweep, key)

    monkeypatch.setattr(_sweep_ray, "_unsaved", look)
    _await_stopped_saves(tmp_path, spec, folder, [trial.key], timeout=600.0)
    assert looks == [trial.key] * 3  # it looked until the run was saved, and then no more
    # a trial that never saves does not hold the sweep past the timeout
    monkeypatch.setattr(_sweep_ray, "_unsaved", lambda *_: looks.append("never") or True)
    _await_stopped_saves(tmp_path, spec, folder, [trial.key], timeout=0.3)
    assert "never" in looks  # it looked, and gave up
