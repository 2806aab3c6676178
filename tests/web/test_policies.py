"""Policy uploads (size, content, names) and watching a policy on the robot."""

from __future__ import annotations

import io

import numpy as np
import pytest

from studio.learning import ArmGrid, DynaQConfig, load_policy
from studio.learning.tabular._policy import save_policy
from tests.web.conftest import TINY_RUN, wait_run


def policy_bytes(tmp_path, bins: int = 5) -> bytes:
    """A valid policy file whose greedy action from every state moves toward the goal."""
    grid = ArmGrid(bins=bins)
    q = np.zeros((grid.n_states, grid.n_actions))
    deltas = grid.action_deltas()
    goal = np.asarray(grid.goal)
    for s in range(grid.n_states):
        toward = np.sign(goal - np.asarray(grid.bins_of(s)))
        q[s, int(np.flatnonzero((deltas == toward).all(axis=1))[0])] = 1.0
    path = tmp_path / "made.policy.npz"
    save_policy(path, grid, q, DynaQConfig(planning="full"), np.array([10.0, 5.0]))
    return path.read_bytes()


def upload(client, name: str, content: bytes):
    return client.post("/api/policies", files={"file": (name, content, "application/octet-stream")})


def test_upload_list_watch_download_and_delete_a_policy(client, tmp_path):
    r = upload(client, "reach.policy.npz", policy_bytes(tmp_path))
    assert r.status_code == 201, r.text
    policy = r.json()
    assert policy["name"] == "reach" and policy["source"] == "upload"
    assert policy["planning"] == "full" and policy["grid"]["bins"] == 5
    assert policy["episodes"] == 2 and policy["size_bytes"] > 0
    assert [p["name"] for p in client.get("/api/policies").json()] == ["reach"]
    assert (tmp_path / "policies" / "reach.policy.npz").is_file()

    r = client.post("/api/watch", json={"policy": "reach", "start": "random", "seed": 3})
    assert r.status_code == 200, r.text
    watch = r.json()
    assert watch["reached_goal"] is True
    grid = ArmGrid(bins=5)
    assert watch["states"][-1] == grid.goal_state
    q = np.asarray(watch["q_robot"])
    assert q.shape == (len(watch["times"]), 6)
    assert np.allclose(q[-1, :3], grid.angles_of(grid.goal_state))
    again = client.post("/api/watch", json={"policy": "reach", "seed": 3}).json()
    assert again["states"] == watch["states"]  # the same seed starts at the same state

    csv = client.get("/api/watch/trajectory.csv")
    assert csv.status_code == 200
    rows = np.loadtxt(io.StringIO(csv.text), delimiter=",", skiprows=1)
    assert csv.text.startswith("time,q1,q2,q3,q4,q5,q6")
    assert np.allclose(rows[:, 1:], q, atol=1e-5)

    r = client.get("/api/policies/reach/file")
    path = tmp_path / "back.policy.npz"
    path.write_bytes(r.content)
    assert load_policy(path).grid.bins == 5

    assert client.post("/api/watch/stop").status_code == 204
    assert client.delete("/api/policies/reach").status_code == 204
    assert client.get("/api/policies").json() == []
    assert client.delete("/api/policies/reach").status_code == 404


def test_uploads_never_overwrite(client, tmp_path):
    content = policy_bytes(tmp_path)
    names = [upload(client, "same.policy.npz", content).json()["name"] for _ in range(3)]
    assert names == ["same", "same-2", "same-3"]
    odd = upload(client, "my policy (v2)!.policy.npz", content).json()["name"]
    assert odd == "my-policy-v2"


@pytest.mark.parametrize("name", ["../evil.policy.npz", "a/b.policy.npz", "..\\x.policy.npz"])
def test_upload_names_with_separators_are_refused(client, tmp_path, name):
    r = upload(client, name, policy_bytes(tmp_path))
    assert r.status_code == 422 and "path separator" in r.json()["detail"]
    assert not list((tmp_path / "policies").iterdir())
    assert not (tmp_path / "evil.policy.npz").exists()


@pytest.mark.parametrize(
    "content",
    [b"hello, not a policy", b"PK\x03\x04broken zip", np.zeros(3).tobytes()],
)
def test_uploads_that_are_not_policies_are_refused(client, tmp_path, content):
    r = upload(client, "fake.policy.npz", content)
    assert r.status_code == 422
    assert "fake.policy.npz" in r.json()["detail"] and ".upload-" not in r.json()["detail"]
    assert not list((tmp_path / "policies").iterdir())  # the temporary file is gone too


def test_an_empty_upload_is_refused(client):
    r = upload(client, "empty.policy.npz", b"")
    assert r.status_code == 422 and "empty" in r.json()["detail"]


def test_oversized_uploads_get_413(open_client, tmp_path):
    client = open_client(upload_limit_bytes=1000)
    r = upload(client, "big.policy.npz", policy_bytes(tmp_path, bins=11))
    assert r.status_code == 413 and "limit" in r.json()["detail"]
    assert not list((tmp_path / "policies").iterdir())


def test_oversized_upload_is_counted_while_received(open_client, tmp_path):
    # a body just under the announced-size guard but over the limit once the file is read
    client = open_client(upload_limit_bytes=50_000)
    r = upload(client, "big.policy.npz", b"x" * 60_000)
    assert r.status_code == 413
    assert not list((tmp_path / "policies").iterdir())


def test_watch_a_run_and_its_policy_in_the_list(client):
    run = client.post("/api/runs", json=TINY_RUN).json()
    wait_run(client, run["id"])
    listed = client.get("/api/policies").json()
    assert [(p["name"], p["source"], p["run"]) for p in listed] == [(run["id"], "run", run["id"])]
    watch = client.post("/api/watch", json={"run": run["id"], "start": "current"})
    assert watch.status_code == 200
    # with no live source the robot is at zero: the rollout starts in the bin of zero
    grid = ArmGrid()
    assert watch.json()["states"][0] == grid.state_of_angles(np.zeros(3))
    by_name = client.post("/api/watch", json={"policy": run["id"]})
    assert by_name.status_code == 200
    r = client.delete(f"/api/policies/{run['id']}")
    assert r.status_code == 409 and "delete the run" in r.json()["detail"]
    # an upload cannot take a run's name
    assert (
        upload(
            client, f"{run['id']}.policy.npz", client.get(f"/api/runs/{run['id']}/policy").content
        ).json()["name"]
        == f"{run['id']}-2"
    )


@pytest.mark.parametrize(
    ("body", "status", "words"),
    [
        ({}, 422, "exactly one"),
        ({"run": "a", "policy": "b"}, 422, "exactly one"),
        ({"policy": "missing"}, 404, "no policy"),
        ({"run": "20990101-000000-zero-abcd"}, 404, "no run"),
        ({"policy": "../x"}, 422, "separator"),
        ({"policy": "p", "start": "sideways"}, 422, "start"),
        ({"policy": "p", "seed": -1}, 422, "seed"),
    ],
)
def test_bad_watch_requests(client, body, status, words):
    r = client.post("/api/watch", json=body)
    assert r.status_code == status and words in r.json()["detail"]


def test_trajectory_before_any_watch_is_409(client):
    r = client.get("/api/watch/trajectory.csv")
    assert r.status_code == 409 and "watch a policy first" in r.json()["detail"]


def test_policy_names_are_checked(client):
    assert client.delete("/api/policies/a..b").status_code == 422
    assert client.get("/api/policies/.hidden/file").status_code == 422


def test_an_announced_oversized_body_is_refused_before_it_is_read(open_client, tmp_path):
    client = open_client(upload_limit_bytes=1000)
    r = upload(client, "huge.policy.npz", b"\0" * 200_000)
    assert r.status_code == 413 and "over the limit of" in r.json()["detail"]
    assert not list((tmp_path / "policies").iterdir())


def deep_policy_bytes(depth: int = 50_000) -> bytes:
    """A policy archive whose JSON header nests ``depth`` lists deep (issue 13)."""
    out = io.BytesIO()
    np.savez(out, header=np.array("[" * depth + "]" * depth), q=np.zeros((2, 2)))
    return out.getvalue()


def test_a_deeply_nested_policy_upload_is_422(client, tmp_path):
    r = upload(client, "deep.policy.npz", deep_policy_bytes())
    assert r.status_code == 422 and "deep.policy.npz" in r.json()["detail"]
    assert not list((tmp_path / "policies").iterdir())


def test_damaged_policies_are_listed_with_the_reason_and_hide_nothing(client, tmp_path):
    assert upload(client, "good.policy.npz", policy_bytes(tmp_path)).status_code == 201
    folder = tmp_path / "policies"
    (folder / "deep.policy.npz").write_bytes(deep_policy_bytes())
    (folder / "junk.policy.npz").write_bytes(b"PK\x03\x04 not a zip")
    r = client.get("/api/policies")
    assert r.status_code == 200
    listed = {p["name"]: p for p in r.json()}
    assert set(listed) == {"good", "deep", "junk"}
    assert listed["good"]["error"] is None and listed["good"]["episodes"] == 2
    for name in ("deep", "junk"):
        assert listed[name]["error"] and listed[name]["episodes"] == 0, name
        assert listed[name]["size_bytes"] == (folder / f"{name}.policy.npz").stat().st_size
    r = client.post("/api/watch", json={"policy": "junk"})
    assert r.status_code == 422
    assert client.delete("/api/policies/junk").status_code == 204


TINY_REACH_RUN = {
    "task": "arm-reach",
    "joints": 3,
    "planning": "zero",
    "experiments": 1,
    "episodes": 4,
    "seed": 1,
}
"""A continuous-joint (tile-coded) run that trains in a few seconds once its kernels are compiled."""


def test_a_continuous_run_policy_is_listed_uploaded_watched_and_downloaded(client, tmp_path):
    from studio.learning import TILE_ROLLOUT_SECONDS_PER_STEP, TilePolicyFile, load_any_policy

    run = client.post("/api/runs", json={**TINY_REACH_RUN, "name": "reach"}).json()
    assert wait_run(client, run["id"], timeout=180)["status"] == "done"
    listed = client.get("/api/policies").json()
    assert len(listed) == 1
    entry = listed[0]
    assert entry["error"] is None, entry["error"]
    assert (entry["name"], entry["source"], entry["run"]) == (run["id"], "run", run["id"])
    assert entry["task"]["kind"] == "arm-reach" and entry["task"]["joints"] == 3
    assert entry["task"]["tile_coding"]["tiles"] == run["config"]["tiles"]
    assert entry["joints"] == 3 and entry["grid"] == {}
    assert entry["goal_deg"] == pytest.approx(run["config"]["goal_deg"])
    assert (entry["planning"], entry["episodes"], entry["experiments"]) == ("zero", 4, 1)

    # the page's "Policy .npz" of the run, uploaded back: accepted and listed the same way
    content = client.get(f"/api/runs/{run['id']}/policy").content
    r = upload(client, f"{run['id']}.policy.npz", content)
    assert r.status_code == 201, r.text
    uploaded = r.json()
    assert uploaded["name"] == f"{run['id']}-2" and uploaded["error"] is None
    assert uploaded["task"] == entry["task"] and uploaded["episodes"] == 4
    back = tmp_path / "back.policy.npz"
    back.write_bytes(client.get(f"/api/policies/{uploaded['name']}/file").content)
    assert isinstance(load_any_policy(back), TilePolicyFile)

    # watched by run, by the run's name in the policy list, and as the upload: one rollout
    answers = [
        client.post("/api/watch", json={**target, "seed": 5})
        for target in ({"run": run["id"]}, {"policy": run["id"]}, {"policy": uploaded["name"]})
    ]
    assert [a.status_code for a in answers] == [200, 200, 200], [a.text for a in answers]
    watches = [a.json() for a in answers]
    first = watches[0]
    assert first["states"] == [] and first["seed"] == 5
    # the step count is the rollout's: one joint step per TILE_ROLLOUT_SECONDS_PER_STEP
    assert first["steps"] == round(first["times"][-1] / TILE_ROLLOUT_SECONDS_PER_STEP) > 0
    for other in watches[1:]:
        assert (other["steps"], other["reached_goal"]) == (first["steps"], first["reached_goal"])
        assert other["q_robot"] == first["q_robot"]


def test_the_rollout_csv_is_the_chosen_policys_under_its_name(client, tmp_path):
    content = policy_bytes(tmp_path)
    for name in ("near", "far"):
        assert upload(client, f"{name}.policy.npz", content).status_code == 201
    r = client.get("/api/watch/trajectory.csv", params={"policy": "near"})
    assert r.status_code == 409
    assert r.json()["detail"] == (
        "Policy near has not been watched yet; watch it first, then download its rollout."
    )
    near = client.post("/api/watch", json={"policy": "near", "seed": 1}).json()
    far = client.post("/api/watch", json={"policy": "far", "seed": 2}).json()
    assert near["q_robot"] != far["q_robot"]
    for name, watched in (("near", near), ("far", far)):
        r = client.get("/api/watch/trajectory.csv", params={"policy": name})
        assert r.status_code == 200
        assert f'filename="{name}.rollout.csv"' in r.headers["content-disposition"]
        rows = np.loadtxt(io.StringIO(r.text), delimiter=",", skiprows=1)
        assert np.allclose(rows[:, 1:], watched["q_robot"], atol=1e-5)
    last = client.get("/api/watch/trajectory.csv")  # no policy named: the last one watched
    assert 'filename="far.rollout.csv"' in last.headers["content-disposition"]
    assert client.get("/api/watch/trajectory.csv", params={"policy": "gone"}).status_code == 404
    # a deleted policy's rollout goes with it, even when the name is taken again
    assert client.delete("/api/policies/near").status_code == 204
    assert upload(client, "near.policy.npz", content).json()["name"] == "near"
    assert client.get("/api/watch/trajectory.csv", params={"policy": "near"}).status_code == 409


def test_a_random_start_reports_its_seed_so_it_can_be_watched_again(client, tmp_path):
    assert upload(client, "reach.policy.npz", policy_bytes(tmp_path)).status_code == 201
    first = client.post("/api/watch", json={"policy": "reach"}).json()
    assert isinstance(first["seed"], int) and first["steps"] == len(first["states"]) - 1
    again = client.post("/api/watch", json={"policy": "reach", "seed": first["seed"]}).json()
    assert again["states"] == first["states"]
    current = client.post("/api/watch", json={"policy": "reach", "start": "current"}).json()
    assert current["seed"] is None
