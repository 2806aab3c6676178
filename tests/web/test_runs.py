"""Training runs through the API: validation, the queue, stop, downloads, persistence."""

from __future__ import annotations

import io
import json
import os
import threading
import time

import numpy as np
import pytest

from studio.learning import load_policy
from studio.learning.runs._curves import CURVE_COLUMNS, TIME_COLUMNS
from tests.conftest import hold_preparation
from tests.web.conftest import TINY_RUN, wait_for, wait_run

BAD_RUNS = [
    ({"bins": 0}, "bins"),
    ({"bins": 1}, "bins"),
    ({"episodes": -5}, "episodes"),
    ({"episodes": 0}, "episodes"),
    ({"episodes": 1_000_000_000}, "episodes"),
    ({"experiments": 0}, "experiments"),
    ({"experiments": 1000, "episodes": 100_000}, "experiments x episodes"),
    ({"epsilon": 2}, "epsilon"),
    ({"epsilon": -0.1}, "epsilon"),
    ({"alpha": 0}, "alpha"),
    ({"gamma": 1.5}, "gamma"),
    ({"planning_steps": -1}, "planning_steps"),
    ({"planning": "psychic"}, "planning"),
    ({"goal_deg": [170, 0, 0]}, "goal_deg joint 1"),
    ({"goal_deg": [0, 0, -150]}, "goal_deg joint 3"),
    ({"goal_deg": [150, 0, 0]}, "bin centred at 163.6"),  # inside the limit, its bin is not
    ({"goal_deg": [0, 0]}, "goal_deg"),
    ({"goal_deg": [0, "up", 0]}, "goal_deg"),
    ({"seed": -1}, "seed"),
    ({"episodes": "many"}, "episodes"),
    ({"demonstrations": ["no-such-demo"]}, "no-such-demo"),
    ({"demonstrations": ["../etc"]}, "separator"),
    ({"turbo": True}, "turbo"),
]


@pytest.mark.parametrize(("body", "names"), BAD_RUNS)
def test_bad_run_settings_get_one_sentence(client, body, names):
    r = client.post("/api/runs", json={**TINY_RUN, **body})
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    assert isinstance(detail, str) and names in detail
    assert detail.rstrip().endswith(".") and "\n" not in detail
    assert client.get("/api/runs").json() == []  # nothing was queued


def test_a_tiny_run_trains_and_yields_a_loadable_policy(client, tmp_path):
    r = client.post("/api/runs", json={**TINY_RUN, "name": "my first run"})
    assert r.status_code == 201
    run = r.json()
    assert run["status"] in ("queued", "running") and run["name"] == "my first run"
    done = wait_run(client, run["id"])
    assert done["status"] == "done", done
    assert done["episodes_done"] == done["episodes_total"] == 8
    assert done["has_policy"] and done["cpu_seconds"] >= 0

    curve = client.get(f"/api/runs/{run['id']}/curve").json()
    assert curve["episodes"] == [1, 2, 3, 4]
    assert curve["count"] == [2, 2, 2, 2]
    for k in range(4):
        assert curve["min"][k] <= curve["mean"][k] <= curve["max"][k]
        assert curve["std"][k] >= 0

    r = client.get(f"/api/runs/{run['id']}/policy")
    assert r.status_code == 200
    path = tmp_path / "download.policy.npz"
    path.write_bytes(r.content)
    policy = load_policy(path)
    assert policy.config.planning == "zero"
    assert policy.grid.bins == 11 and policy.experiments == 2
    assert np.allclose(policy.mean_steps, curve["mean"])

    csv = client.get(f"/api/runs/{run['id']}/curve.csv")
    assert csv.headers["content-type"].startswith("text/csv")
    rows = csv.text.strip().splitlines()
    assert rows[0] == ",".join(CURVE_COLUMNS + TIME_COLUMNS) and len(rows) == 5
    assert float(rows[1].split(",")[1]) == pytest.approx(curve["mean"][0])

    png = client.get(f"/api/runs/{run['id']}/plot.png?log=true")
    assert png.status_code == 200 and png.content[:8] == b"\x89PNG\r\n\x1a\n"
    svg = client.get(f"/api/runs/{run['id']}/plot.svg")
    assert svg.status_code == 200 and b"<svg" in svg.content[:1000]
    assert client.get(f"/api/runs/{run['id']}/plot.gif").status_code == 404

    on_disk = tmp_path / "runs" / run["id"]
    assert {"config.json", "status.json", "steps.csv", "curves.csv", "policy.policy.npz"} <= {
        p.name for p in on_disk.iterdir()
    }
    record = json.loads((on_disk / "config.json").read_text())
    assert record["request"]["name"] == "my first run" and record["origin"] == "page"
    assert done["origin"] == "page" and done["config"]["name"] == "my first run"


def test_the_goal_is_the_bin_containing_goal_deg(client, tmp_path):
    run = client.post("/api/runs", json={**TINY_RUN, "bins": 5, "goal_deg": [10, -20, 30]}).json()
    wait_run(client, run["id"])
    policy = load_policy(tmp_path / "runs" / run["id"] / "policy.policy.npz")
    assert policy.grid.bins == 5
    assert policy.grid.goal == tuple(policy.grid.bins_of_angles(np.radians([10, -20, 30])))


def hold_before_training(client) -> tuple[threading.Event, threading.Event]:
    """Make the run worker wait, each time it has marked a run running, until ``go`` is set;
    ``held`` is set once it waits. Deterministic windows instead of sleeps."""
    held, go = threading.Event(), threading.Event()

    def hook(run) -> None:
        held.set()
        assert go.wait(30), "the test never released the run worker"

    client.app.state.studio.runs.before_train = hook
    return held, go


def test_runs_queue_and_stop_queued_and_running(client):
    held, go = hold_before_training(client)
    long = {"planning": "full", "experiments": 1, "episodes": 100_000, "seed": 0}
    first = client.post("/api/runs", json=long).json()
    second = client.post("/api/runs", json={**TINY_RUN}).json()
    assert held.wait(30)
    assert client.get(f"/api/runs/{first['id']}").json()["status"] == "running"
    assert client.get(f"/api/runs/{second['id']}").json()["status"] == "queued"
    r = client.delete(f"/api/runs/{first['id']}")
    assert r.status_code == 409 and "stop it first" in r.json()["detail"]
    go.set()

    stopped = client.post(f"/api/runs/{second['id']}/stop").json()
    assert stopped["status"] == "stopped" and stopped["episodes_done"] == 0

    for _ in range(200):  # wait until the first run has finished an episode
        if client.get(f"/api/runs/{first['id']}").json()["episodes_done"] > 0:
            break
        client.app.state.studio.runs.wait_idle(0.05)
    running = client.get(f"/api/runs/{first['id']}").json()
    assert running["status"] == "running"
    r = client.delete(f"/api/runs/{first['id']}")
    assert r.status_code == 409 and "stop it first" in r.json()["detail"]

    client.post(f"/api/runs/{first['id']}/stop")
    done = wait_run(client, first["id"])
    assert done["status"] == "stopped"
    assert 0 < done["episodes_done"] < 100_000
    assert done["has_policy"]
    curve = client.get(f"/api/runs/{first['id']}/curve").json()
    assert len(curve["episodes"]) == done["episodes_done"]
    # the queued run stopped before it started never trained
    assert client.get(f"/api/runs/{second['id']}").json()["episodes_done"] == 0


def test_a_stop_right_after_a_run_is_marked_running_is_never_lost(client):
    """Issue 13 item 14: the Stop arrives after the worker marked the run running and before
    training started; the run must end stopped, having trained nothing."""
    stopped: list[dict] = []

    def stop_now(run) -> None:
        stopped.append(client.app.state.studio.runs.stop(run.id).model().model_dump())

    client.app.state.studio.runs.before_train = stop_now
    run = client.post("/api/runs", json={**TINY_RUN, "episodes": 2000}).json()
    done = wait_run(client, run["id"])
    assert stopped and stopped[0]["status"] == "running"
    assert done["status"] == "stopped" and done["episodes_done"] == 0
    assert done["error"] == "Stopped before it started." and not done["has_policy"]


def test_a_run_in_another_process_cannot_be_stopped_or_deleted_here(client, tmp_path):
    from studio.learning import ArmGrid, DynaQConfig, RunFolder, RunRecord

    record = RunRecord.for_arm_grid(ArmGrid(), DynaQConfig(), 1, 5, origin="cli")
    folder = RunFolder.create(tmp_path / "runs", record, name="elsewhere", status="running")
    folder.pid = os.getppid()  # a live process that is not this one
    folder.save_status()
    assert client.get("/api/runs/elsewhere").json()["status"] == "running"
    for r in (client.post("/api/runs/elsewhere/stop"), client.delete("/api/runs/elsewhere")):
        assert r.status_code == 409 and "another process" in r.json()["detail"]
    assert folder.path.is_dir()


def test_delete_run_removes_it_and_its_policy(client, tmp_path):
    run = client.post("/api/runs", json=TINY_RUN).json()
    wait_run(client, run["id"])
    assert any(p["run"] == run["id"] for p in client.get("/api/policies").json())
    assert client.delete(f"/api/runs/{run['id']}").status_code == 204
    assert not (tmp_path / "runs" / run["id"]).exists()
    assert client.get(f"/api/runs/{run['id']}").status_code == 404
    assert client.get(f"/api/runs/{run['id']}/policy").status_code == 404
    assert all(p["run"] != run["id"] for p in client.get("/api/policies").json())


@pytest.mark.parametrize("path", ["", "/curve", "/curve.csv", "/plot.png", "/policy"])
def test_unknown_runs_are_404_and_bad_ids_422(client, path):
    r = client.get(f"/api/runs/20990101-000000-zero-abcd{path}")
    assert r.status_code == 404 and "no run" in r.json()["detail"]
    r = client.get(f"/api/runs/a..b{path}")
    assert r.status_code == 422 and "not valid" in r.json()["detail"]
    assert client.post("/api/runs/nope/stop").status_code == 404
    assert client.delete("/api/runs/nope").status_code == 404


def test_policy_download_before_there_is_one_is_409(client):
    long = {"planning": "full", "experiments": 1, "episodes": 100_000}
    run = client.post("/api/runs", json=long).json()
    queued = client.post("/api/runs", json=TINY_RUN).json()
    r = client.get(f"/api/runs/{queued['id']}/policy")
    assert r.status_code == 409 and "no policy yet" in r.json()["detail"]
    client.post(f"/api/runs/{run['id']}/stop")
    client.post(f"/api/runs/{queued['id']}/stop")
    wait_run(client, run["id"])


def test_runs_survive_a_restart_and_interrupted_runs_show_stopped(open_client, tmp_path):
    first = open_client()
    done = first.post("/api/runs", json=TINY_RUN).json()
    wait_run(first, done["id"])
    curve = first.get(f"/api/runs/{done['id']}/curve").json()
    first.__exit__(None, None, None)

    # fake a crash during a second run: its folder says running, with a partial curve
    runs = tmp_path / "runs"
    crashed = runs / "20200101-000000-full-dead"
    crashed.mkdir()
    record = json.loads((runs / done["id"] / "config.json").read_text())
    record["id"] = crashed.name
    (crashed / "config.json").write_text(json.dumps(record))
    status = json.loads((runs / done["id"] / "status.json").read_text())
    (crashed / "status.json").write_text(json.dumps({**status, "status": "running"}))
    (crashed / "steps.csv").write_text("# partial\n7,5,-1,-1\n9,-1,-1,-1\n")

    second = open_client()
    listed = {r["id"]: r for r in second.get("/api/runs").json()}
    assert listed[done["id"]]["status"] == "done"
    assert second.get(f"/api/runs/{done['id']}/curve").json() == curve
    assert second.get(f"/api/runs/{done['id']}/policy").status_code == 200
    interrupted = listed[crashed.name]
    assert interrupted["status"] == "stopped"
    assert "stopped while this run was training" in interrupted["error"]
    partial = second.get(f"/api/runs/{crashed.name}/curve").json()
    assert partial["episodes"] == [1, 2] and partial["count"] == [2, 1]
    assert partial["mean"] == [8.0, 5.0]
    # only its owner writes a run's status: a studio that lists it never does
    assert json.loads((crashed / "status.json").read_text())["status"] == "running"
    marked = second.post(f"/api/runs/{crashed.name}/mark-stopped")  # the user may, by hand
    assert marked.status_code == 200 and marked.json()["status"] == "stopped"
    assert json.loads((crashed / "status.json").read_text())["status"] == "stopped"


def test_a_shutdown_mid_run_keeps_the_partial_curve(open_client):
    first = open_client()
    run = first.post(
        "/api/runs", json={"planning": "full", "experiments": 1, "episodes": 100_000}
    ).json()
    for _ in range(400):
        if first.get(f"/api/runs/{run['id']}").json()["episodes_done"] > 0:
            break
        first.app.state.studio.runs.wait_idle(0.05)
    first.__exit__(None, None, None)
    second = open_client()
    after = second.get(f"/api/runs/{run['id']}").json()
    assert after["status"] == "stopped" and after["episodes_done"] > 0
    assert "shut down" in after["error"]
    assert after["has_policy"]


def test_run_events_stream_the_curve_while_training(client):
    run = client.post(
        "/api/runs", json={"planning": "full", "experiments": 1, "episodes": 100_000}
    ).json()
    for _ in range(400):  # wait until training is under way (the kernels load first)
        if client.get(f"/api/runs/{run['id']}").json()["episodes_done"] > 0:
            break
        client.app.state.studio.runs.wait_idle(0.05)
    events = stream_run_events(client, 1.5)
    client.post(f"/api/runs/{run['id']}/stop")
    wait_run(client, run["id"])
    assert len(events) >= 7  # at least 5 per second over the 1.5 s stream
    assert all(e["run"]["id"] == run["id"] for e in events)
    assert events[0]["from"] == 0
    # replaying the partial updates rebuilds the curve the API serves at that moment
    counts = replay_counts(events)
    assert events[-1]["run"]["episodes_done"] > events[0]["run"]["episodes_done"]
    assert len(counts) <= 100_000


def replay_counts(events: list[dict]) -> list[int]:
    """A page's copy of a run's ``count`` column, rebuilt from its events (the first holds the
    whole curve, later ones the pieces that changed); each step's total is the run's progress."""
    counts: list[int] = []
    for e in events:
        if "curve" in e:
            counts = counts[: e["from"]] + e["curve"]["count"]
            assert e["curve"]["episodes"][:1] in ([], [e["from"] + 1])
        for piece in e.get("pieces", []):
            assert piece["curve"]["episodes"] == list(range(piece["from"] + 1, piece["to"] + 1))
            counts += [0] * (piece["from"] - len(counts))
            counts[piece["from"] : piece["to"]] = piece["curve"]["count"]
        assert sum(counts) == e["run"]["episodes_done"]
    return counts


def stream_run_events(client, seconds: float) -> list[dict]:
    events, event = [], None
    with client.stream("GET", f"/api/events?max_seconds={seconds}") as r:
        assert r.headers["content-type"].startswith("text/event-stream")
        for line in r.iter_lines():
            if line.startswith("event: "):
                event = line[7:]
            elif line.startswith("data: ") and event == "run":
                events.append(json.loads(line[6:]))
    return events


def test_run_events_send_only_what_changed_when_experiments_train_far_apart(open_client):
    # one kernel thread: experiment 1 starts at episode 1 while experiment 0 finished them all,
    # so the episodes that change lie at both ends of a 20,000-episode curve
    client = open_client(run_workers=1)
    body = {"planning": "full", "planning_steps": 500, "experiments": 3, "episodes": 20_000}
    run = client.post("/api/runs", json=body).json()
    assert wait_for(
        lambda: client.get(f"/api/runs/{run['id']}").json()["episodes_done"] > 20_000, 300
    )
    try:
        events = stream_run_events(client, 1.5)
    finally:
        client.post(f"/api/runs/{run['id']}/stop")
        wait_run(client, run["id"])
    assert len(events) >= 5 and len(events[0]["curve"]["count"]) == 20_000
    later = [e for e in events[1:] if e["run"]["status"] == "running"]
    sent = [sum(p["to"] - p["from"] for p in e["pieces"]) for e in later]
    # each event sends the episodes finished since the last one, never the tail from experiment
    # 1's episode to the curve's end (about 20,000 episodes) again and again: how many finish
    # between two events depends on the machine's speed, so the bound is half the curve
    assert later and max(sent) < 10_000, sent
    assert len(replay_counts(events)) == 20_000


def test_a_client_that_disconnects_mid_run_changes_nothing(client):
    run = client.post("/api/runs", json={**TINY_RUN, "episodes": 200}).json()
    with client.stream("GET", "/api/events") as r:
        for line in r.iter_lines():
            if line.startswith("event: "):
                break  # leave after the first event
    done = wait_run(client, run["id"])
    assert done["status"] == "done" and done["episodes_done"] == 400
    assert client.get("/api/source").status_code == 200


def test_csv_of_curve_is_parseable(client):
    run = client.post("/api/runs", json=TINY_RUN).json()
    wait_run(client, run["id"])
    data = np.loadtxt(
        io.StringIO(client.get(f"/api/runs/{run['id']}/curve.csv").text), delimiter=",", skiprows=1
    )
    assert data.shape == (4, len(CURVE_COLUMNS + TIME_COLUMNS)) and list(data[:, 0]) == [1, 2, 3, 4]


def test_a_failing_run_shows_why_and_the_queue_goes_on(client, monkeypatch):
    import studio.learning.runs._train
    from studio.learning import LearningError

    real = studio.learning.runs._train.train_learner
    calls = []

    def flaky(*args, **kwargs):
        calls.append(1)
        if len(calls) == 1:
            raise LearningError("the kernel ran out of luck; try again.")
        if len(calls) == 2:
            raise RuntimeError("boom")
        return real(*args, **kwargs)

    monkeypatch.setattr(studio.learning.runs._train, "train_learner", flaky)
    first = client.post("/api/runs", json=TINY_RUN).json()
    second = client.post("/api/runs", json=TINY_RUN).json()
    third = client.post("/api/runs", json=TINY_RUN).json()
    wait_run(client, third["id"])
    one = client.get(f"/api/runs/{first['id']}").json()
    assert one["status"] == "failed" and one["error"] == "the kernel ran out of luck; try again."
    two = client.get(f"/api/runs/{second['id']}").json()
    assert two["status"] == "failed" and "RuntimeError: boom" in two["error"]
    assert client.get(f"/api/runs/{third['id']}").json()["status"] == "done"
    assert client.get(f"/api/runs/{first['id']}/policy").status_code == 409


def test_a_new_run_on_a_full_disk_answers_one_sentence_and_leaves_nothing(
    client, tmp_path, monkeypatch
):
    import errno
    from pathlib import Path

    def full(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Path, "write_text", full)
    r = client.post("/api/runs", json=TINY_RUN)
    monkeypatch.undo()
    assert r.status_code == 422
    detail = r.json()["detail"]
    assert "disk holding" in detail and "is full" in detail and "\n" not in detail
    assert list((tmp_path / "runs").iterdir()) == []
    assert client.get("/api/runs").json() == []


def test_a_just_started_run_shows_its_own_cpu_time_not_the_servers(client):
    held, go = hold_before_training(client)
    busy = time.process_time()
    while time.process_time() - busy < 0.3:  # the server process has spent CPU before the run
        sum(range(1000))
    run = client.post("/api/runs", json={**TINY_RUN, "episodes": 500}).json()
    assert held.wait(30)
    running = client.get(f"/api/runs/{run['id']}").json()
    assert running["status"] == "running" and running["cpu_seconds"] == 0.0
    go.set()
    done = wait_run(client, run["id"])
    assert done["status"] == "done" and 0 < done["cpu_seconds"] < time.process_time()


@pytest.mark.parametrize(
    "goal", [[170.0, 0.0, 0.0], [0.0, 120.0, -150.0], [0.0, 0.0], [1, "up", 2]]
)
def test_the_simulators_reach_and_a_run_check_a_goal_with_one_function(client, goal):
    from studio.learning import ConfigError, goal_pose
    from studio.learning.tasks._goal import goal_problems

    with pytest.raises(ConfigError) as err:
        goal_pose(goal)
    assert err.value.problems == goal_problems(goal)
    r = client.post("/api/runs", json={**TINY_RUN, "goal_deg": goal})
    if r.status_code == 422 and "problems" in r.json():
        assert r.json()["problems"] == goal_problems(goal)
    else:  # a malformed list is refused by the schema first
        assert r.status_code == 422 and "goal_deg" in r.json()["detail"]


def test_a_first_run_reports_preparing_the_learner_before_its_first_episode(client, monkeypatch):
    compiling, compiled = hold_preparation(monkeypatch)
    run = client.post("/api/runs", json=TINY_RUN).json()
    assert compiling.wait(30)
    preparing = client.get(f"/api/runs/{run['id']}").json()
    assert preparing["status"] == "running" and preparing["episodes_done"] == 0
    assert preparing["note"].startswith("preparing the learner (first run on this machine, about ")
    assert client.get("/api/runs").json()[0]["note"] == preparing["note"]
    compiled.set()
    done = wait_run(client, run["id"])
    assert done["status"] == "done" and done["note"] is None


def test_a_continuous_run_counts_its_cpu_while_it_trains(open_client):
    client = open_client(run_workers=2)  # the page's studio: one kernel thread per core
    body = {**TINY_RUN, "task": "arm-reach", "joints": 3, "episodes": 100_000,
            "planning": "full", "planning_steps": 50}  # fmt: skip
    run = client.post("/api/runs", json=body).json()

    def mid_way() -> dict | None:
        now = client.get(f"/api/runs/{run['id']}").json()
        # a second of CPU: far beyond what the thread polling the run spends meanwhile
        return now if now["episodes_done"] > 0 and now["cpu_seconds"] >= 1.0 else None

    try:
        assert wait_for(mid_way, 300, step=0.2), client.get(f"/api/runs/{run['id']}").json()
        now = client.get(f"/api/runs/{run['id']}").json()
        assert now["status"] == "running" and now["episodes_done"] < 2 * 100_000
    finally:
        client.post(f"/api/runs/{run['id']}/stop")
        wait_run(client, run["id"])


def test_a_curve_encoded_in_slices_is_the_same_json():
    from studio.web.services._runs import JSON_SLICE, _json_in_slices

    rng = np.random.default_rng(0)
    n = 2 * JSON_SLICE + 7
    curve = {"episodes": list(range(1, n + 1)), "mean": rng.random(n).round(3).tolist(),
             "count": rng.integers(0, 9, n).tolist(), "empty": []}  # fmt: skip
    assert _json_in_slices(curve) == json.dumps(curve, separators=(",", ":"))
