"""Runs on the chosen robot through the API: ``RunCreate.robot`` (default: the robot chosen in
the page), 422 for an unknown robot, and Watch refusing a policy of a robot not chosen."""

from __future__ import annotations

from tests.web.conftest import wait_run

REACH = {
    "task": "arm-reach",
    "planning": "zero",
    "episodes": 2,
    "experiments": 1,
    "joints": 3,
    "goal_deg": [0, -45, 0],
}


def test_an_unknown_robot_is_refused_by_field(client):
    r = client.post("/api/runs", json={**REACH, "robot": "nosuch"})
    assert r.status_code == 422
    body = r.json()
    assert "Unknown robot 'nosuch'" in body["by_field"]["robot"]
    assert client.get("/api/runs").json() == []


def test_a_run_trains_the_robot_chosen_in_the_page_unless_it_names_one(client):
    r = client.post("/api/runs", json=REACH)
    assert r.status_code == 201, r.text
    assert wait_run(client, r.json()["id"])["config"]["robot"] == "puma560"  # the default
    assert client.put("/api/robot", json={"name": "panda"}).status_code == 200
    r = client.post("/api/runs", json=REACH)
    assert r.status_code == 201, r.text
    run = wait_run(client, r.json()["id"])
    assert run["status"] == "done" and run["config"]["robot"] == "panda"
    record = client.app.state.studio.runs.get(run["id"]).folder.record
    assert record.robot == "panda" and len(record.arm_reach().goal) == 7
    grid_body = {k: v for k, v in REACH.items() if k != "joints"}
    r = client.post("/api/runs", json={**grid_body, "task": "arm-grid", "robot": "ur5"})
    assert r.status_code == 201, r.text
    grid = wait_run(client, r.json()["id"])
    assert grid["status"] == "done" and grid["config"]["robot"] == "ur5"


def test_watch_plays_a_policy_on_its_own_robot_only(client):
    assert client.put("/api/robot", json={"name": "panda"}).status_code == 200
    run = wait_run(client, client.post("/api/runs", json=REACH).json()["id"])
    assert client.put("/api/robot", json={"name": "puma560"}).status_code == 200
    r = client.post("/api/watch", json={"run": run["id"], "seed": 1})
    assert r.status_code == 409
    detail = r.json()["detail"]
    assert "Franka Emika Panda" in detail and "Puma560" in detail and "pick the panda" in detail
    assert client.put("/api/robot", json={"name": "panda"}).status_code == 200
    r = client.post("/api/watch", json={"run": run["id"], "seed": 1})
    assert r.status_code == 200, r.text
    q = r.json()["q_robot"]
    assert len(q[0]) == 7  # the Panda's joints, the seventh held at the goal's
