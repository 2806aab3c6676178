"""``POST /api/runs/pair``: a run with demonstrations and its twin without them, queued together
with the same settings, seed and goal, so the page can compare the two."""

from __future__ import annotations

import json

import numpy as np

from studio.learning import RunFolder
from tests.web.conftest import TINY_RUN, wait_run
from tests.web.test_runs_create import PAGE_REACH


def config_of(client, run: dict) -> dict:
    folder = client.app.state.studio.runs.get(run["id"]).folder
    return json.loads((folder.path / "config.json").read_text())


def test_a_grid_run_and_its_twin_without_demonstrations(client):
    body = {**TINY_RUN, "name": "taught", "demonstrations": ["sample-reach-1"]}
    r = client.post("/api/runs/pair", json=body)
    assert r.status_code == 201, r.text
    taught, bare = r.json()
    assert taught["name"] == "taught" and bare["name"] == "taught · no demos"
    assert taught["config"]["demonstrations"] == ["sample-reach-1"]
    assert bare["config"]["demonstrations"] == []
    same = ("planning", "episodes", "experiments", "seed", "goal_deg", "bins", "epsilon")
    assert {k: bare["config"][k] for k in same} == {k: taught["config"][k] for k in same}
    for run in (taught, bare):
        assert wait_run(client, run["id"])["status"] == "done"
    a = RunFolder.load(client.app.state.studio.runs.get(taught["id"]).folder.path)
    b = RunFolder.load(client.app.state.studio.runs.get(bare["id"]).folder.path)
    assert a.record.arm_grid() == b.record.arm_grid()  # the same goal bin
    assert len(a.record.demonstrations) == 1 and len(b.record.demonstrations) == 0


def test_an_unnamed_runs_twin_is_named_no_demos(client):
    """Unnamed, a run is listed after its settings ("full x20"); its twin without
    demonstrations was listed the same, and the two could not be told apart."""
    body = {**TINY_RUN, "demonstrations": ["sample-reach-1"]}
    r = client.post("/api/runs/pair", json=body)
    assert r.status_code == 201, r.text
    taught, bare = r.json()
    assert bare["name"].endswith(" · no demos")
    assert (
        bare["name"] == f"{TINY_RUN.get('planning', 'full')} x{TINY_RUN['experiments']} · no demos"
    )
    assert taught["name"] != bare["name"]
    for run in (taught, bare):
        assert wait_run(client, run["id"])["status"] == "done"


def test_a_continuous_twin_keeps_the_demonstrations_goal(client):
    body = {**PAGE_REACH, "episodes": 2, "demonstrations": ["sample-reach-1"]}
    taught, bare = client.post("/api/runs/pair", json=body).json()
    for run in (taught, bare):
        wait_run(client, run["id"], timeout=300)
    goal = [config_of(client, run)["task"]["goal"] for run in (taught, bare)]
    np.testing.assert_allclose(goal[1], goal[0])
    assert bare["name"] != taught["name"] or not taught["name"]
    # the default actions follow the demonstration; the twin, without any, moves one joint
    listed = {p["name"]: p["task"] for p in client.get("/api/policies").json()}
    assert listed[taught["id"]]["actions"] == listed[bare["id"]]["actions"] == "follow"
    assert listed[taught["id"]]["paths"] == 1 and "paths" not in listed[bare["id"]]


def test_a_pair_needs_a_demonstration_and_a_bad_field_queues_neither(client):
    before = len(client.get("/api/runs").json())
    r = client.post("/api/runs/pair", json=TINY_RUN)
    assert r.status_code == 422
    assert "at least one demonstration" in r.json()["detail"]
    r = client.post(
        "/api/runs/pair", json={**TINY_RUN, "epsilon": 7, "demonstrations": ["sample-reach-1"]}
    )
    assert r.status_code == 422 and "epsilon" in r.json()["by_field"]
    assert len(client.get("/api/runs").json()) == before
