"""The page's run form chooses the continuous task's action set through the one resolver."""

from __future__ import annotations

from tests.web.conftest import wait_run
from tests.web.test_runs_create import PAGE_REACH


def test_the_page_offers_the_action_set_and_a_run_keeps_it(client):
    # the form starts with one joint per action, so a run taught by a sample learns visibly
    assert client.get("/api/config").json()["training"]["actions"] == "single"
    body = {**PAGE_REACH, "actions": "pairs", "episodes": 2, "experiments": 1}
    r = client.post("/api/runs", json=body)
    assert r.status_code == 201, r.text
    run = wait_run(client, r.json()["id"])
    assert run["status"] == "done" and run["config"]["actions"] == "pairs"
    r = client.post("/api/runs", json={**body, "actions": "diagonal"})
    assert r.status_code == 422
    assert r.json()["detail"].startswith("actions is 'diagonal'; give 'single', 'pairs', 'all'")


def test_a_follow_run_follows_its_demonstrations_and_one_without_any_moves_one_joint(client):
    body = {**PAGE_REACH, "actions": "follow", "episodes": 3, "experiments": 1}
    r = client.post("/api/runs", json={**body, "demonstrations": ["sample-reach-1"]})
    assert r.status_code == 201, r.text
    run = wait_run(client, r.json()["id"])
    assert run["status"] == "done" and run["config"]["actions"] == "follow"
    listed = next(p for p in client.get("/api/policies").json() if p["name"] == run["id"])
    assert listed["task"]["actions"] == "follow" and listed["task"]["paths"] == 1
    watched = client.post("/api/watch", json={"run": run["id"]})
    assert watched.status_code == 200, watched.text
    assert watched.json()["likeness"]["name"] == "sample-reach-1"  # scored against what it follows
    r = client.post("/api/runs", json=body)  # without any: one joint per action
    assert r.status_code == 201, r.text
    alone = wait_run(client, r.json()["id"])
    listed = next(p for p in client.get("/api/policies").json() if p["name"] == alone["id"])
    assert alone["status"] == "done" and "paths" not in listed["task"]


def test_the_page_launches_a_baseline_that_compare_runs_tells_apart(client):
    """A run trained by the teacher (the demonstrations followed, no learning; issue 40) from the
    API: its settings say so, its policy is listed and watched like any other."""
    body = {**PAGE_REACH, "episodes": 3, "experiments": 1, "learner": "teacher"}
    r = client.post("/api/runs", json={**body, "demonstrations": ["sample-reach-1"]})
    assert r.status_code == 201, r.text
    run = wait_run(client, r.json()["id"])
    assert run["status"] == "done" and run["config"]["learner"] == "teacher"
    listed = next(p for p in client.get("/api/policies").json() if p["name"] == run["id"])
    assert listed["task"]["learner"] == "teacher" and listed["planning"] == "none"
    assert client.post("/api/watch", json={"run": run["id"]}).status_code == 200
    r = client.post("/api/runs", json=body)  # nothing to follow: one sentence on the field
    assert r.status_code == 422 and "learns from demonstrations" in r.json()["detail"]
