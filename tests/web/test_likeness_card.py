"""The likeness card of every policy watched, and in the run's files (``likeness.json``)."""

from __future__ import annotations

import json

import pytest

from studio.learning import TILE_ROLLOUT_SECONDS_PER_STEP, load_any_policy
from tests.web.conftest import TINY_RUN, wait_run
from tests.web.test_policies import policy_bytes, upload

FIGURES = {
    "ldlj",
    "sparc",
    "joint_shares",
    "together",
    "duration_s",
    "joint_travel_rad",
    "tool_path_m",
}


def both_columns(card: dict) -> None:
    assert set(card["policy"]) == FIGURES and set(card["demonstration"]) == FIGURES
    assert card["demonstration"]["duration_s"] > 0 and card["policy"]["duration_s"] > 0
    assert card["dtw_rad"] is not None and card["frechet_m"] is not None


def test_a_run_of_a_demonstration_writes_likeness_json_and_watch_shows_the_card(client, tmp_path):
    body = {**TINY_RUN, "demonstrations": ["sample-reach-1"]}
    run = client.post("/api/runs", json=body)
    assert run.status_code == 201, run.text
    assert wait_run(client, run.json()["id"])["status"] == "done"
    folder = tmp_path / "runs" / run.json()["id"]
    config = json.loads((folder / "config.json").read_text())
    assert config["demonstration_motions"][0]["name"] == "sample-reach-1"
    document = json.loads((folder / "likeness.json").read_text())
    assert document["format"] == "teach-studio-likeness"
    [entry] = document["cards"]
    assert entry["demonstration"] == "sample-reach-1"
    both_columns(entry["card"])
    watched = client.post("/api/watch", json={"run": run.json()["id"], "seed": 1}).json()
    assert watched["likeness"]["name"] == "sample-reach-1"
    both_columns(watched["likeness"])
    # the card rolls out from the demonstration's start, not the watched random start
    assert watched["likeness"] == entry["card"] | {"name": "sample-reach-1"}


def test_an_upload_has_no_card_until_a_demonstration_is_chosen(client, tmp_path):
    assert upload(client, "reach.policy.npz", policy_bytes(tmp_path, bins=11)).status_code == 201
    plain = client.post("/api/watch", json={"policy": "reach", "seed": 1}).json()
    assert (
        plain["likeness"] is None
        and "not taught from a recorded demonstration" in plain["likeness_note"]
    )
    chosen = client.post(
        "/api/watch", json={"policy": "reach", "seed": 1, "demonstration": "sample-reach-2"}
    ).json()
    assert chosen["likeness"]["name"] == "sample-reach-2"
    both_columns(chosen["likeness"])
    missing = client.post("/api/watch", json={"policy": "reach", "demonstration": "nope"})
    assert missing.status_code == 404 and "nope" in missing.json()["detail"]


def test_a_continuous_run_of_a_recorded_demonstration_moves_at_the_persons_pace(client, tmp_path):
    """The page's continuous run, taught by sample-reach-1: its policy keeps the demonstration's
    pace, so watched from the demonstration's start (the card) it takes the person's time and its
    smoothness is the person's within 20%; a plain watch steps at that pace too."""
    body = {
        "task": "arm-reach",
        "planning": "zero",
        "experiments": 1,
        "episodes": 3000,
        "seed": 0,
        "demonstrations": ["sample-reach-1"],
    }
    run = client.post("/api/runs", json=body)
    assert run.status_code == 201, run.text
    assert wait_run(client, run.json()["id"], timeout=180)["status"] == "done"
    watched = client.post("/api/watch", json={"run": run.json()["id"], "seed": 1}).json()
    card = watched["likeness"]
    both_columns(card)
    person, policy = card["demonstration"], card["policy"]
    assert policy["duration_s"] == pytest.approx(person["duration_s"], abs=0.05)
    assert abs(policy["ldlj"] / person["ldlj"] - 1) <= 0.2 and card["dtw_rad"] <= 0.05
    # a plain watch steps at the policy file's pace, the demonstration's (24 steps in 2.5 s)
    saved = tmp_path / "run.policy.npz"
    saved.write_bytes(client.get(f"/api/runs/{run.json()['id']}/policy").content)
    pace = load_any_policy(saved).seconds_per_step
    assert pace > 2 * TILE_ROLLOUT_SECONDS_PER_STEP
    assert watched["times"][-1] == pytest.approx(watched["steps"] * pace)
