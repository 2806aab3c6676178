"""Demonstrations through the API: list, detail, use in a run, delete, refusals."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from studio.capture import Demonstration
from studio.learning import ArmGrid
from tests.web.conftest import TINY_RUN, wait_run


def save_demo(folder: Path, name: str, start_bins=(0, 0, 0), goal=None) -> Demonstration:
    """A demonstration file whose robot path walks the grid from ``start_bins`` to the goal."""
    grid = ArmGrid() if goal is None else ArmGrid(goal=goal)
    bins = np.array(start_bins)
    states = [grid.state_of(bins)]
    while tuple(bins) != grid.goal:
        bins = bins + np.sign(np.asarray(grid.goal) - bins)
        states.append(grid.state_of(bins))
    q = np.zeros((len(states), 6))
    q[:, :3] = [grid.angles_of(s) for s in states]
    demo = Demonstration(
        recording=folder / "take.tape.csv",
        t0=1.0,
        t1=1.0 + 0.5 * len(states),
        times=1.0 + 0.5 * np.arange(len(states)),
        q_robot=q,
        grid_path=states,
        grid=grid.to_dict(),
        goal=grid.goal,
        name=name,
    )
    folder.mkdir(parents=True, exist_ok=True)
    demo.save(folder / f"{name}.demo.json")
    return demo


def mine(listed: list[dict]) -> list[dict]:
    """The user's own demonstrations of a listing (every data folder also lists the samples)."""
    return [d for d in listed if not d["sample"]]


def test_list_and_detail(client, tmp_path):
    demo = save_demo(tmp_path / "recordings", "reach-1")
    listed = client.get("/api/demonstrations").json()
    assert [d["name"] for d in listed if not d["sample"]] == ["reach-1"]
    one = listed[-1]
    assert one["sample"] is False and one["error"] is None
    assert one["recording"] == "take" and one["t0"] == 1.0
    assert one["steps"] == len(demo.grid_path) - 1
    assert one["reaches_goal"] is True
    grid = ArmGrid()
    assert np.allclose(one["goal"], np.degrees(grid.angles_of(grid.goal_state)))
    detail = client.get("/api/demonstrations/reach-1").json()
    assert detail["grid_path"] == demo.grid_path
    assert np.allclose(detail["q_robot"], demo.q_robot, atol=1e-6)
    assert len(detail["times"]) == len(detail["q_robot"])
    assert client.post("/api/demonstrations/reach-1/preview").status_code == 202


def test_a_goal_set_from_the_end_is_not_the_default_goal(client, tmp_path):
    save_demo(tmp_path / "recordings", "elsewhere", goal=(1, 1, 1))
    (one,) = mine(client.get("/api/demonstrations").json())
    assert one["reaches_goal"] is False


def test_supervised_run_replays_demonstrations(client, tmp_path):
    save_demo(tmp_path / "recordings", "reach-1", (0, 0, 0))
    save_demo(tmp_path / "recordings", "reach-2", (10, 10, 10))
    run = client.post(
        "/api/runs", json={**TINY_RUN, "demonstrations": ["reach-1", "reach-2"]}
    ).json()
    done = wait_run(client, run["id"])
    assert done["status"] == "done", done
    curve = client.get(f"/api/runs/{run['id']}/curve").json()
    # the first two episodes replay the demonstrations: exactly their lengths
    assert curve["min"][:2] == curve["max"][:2] == [6.0, 8.0]


def test_a_demonstration_off_the_run_goal_is_refused(client, tmp_path):
    save_demo(tmp_path / "recordings", "elsewhere", goal=(1, 1, 1))
    r = client.post("/api/runs", json={**TINY_RUN, "demonstrations": ["elsewhere"]})
    assert r.status_code == 422 and "not in the goal bin" in r.json()["detail"]
    r = client.post(
        "/api/runs", json={**TINY_RUN, "episodes": 1, "demonstrations": ["elsewhere", "elsewhere"]}
    )
    assert r.status_code == 422


def test_delete_in_use_is_409_then_204(client, tmp_path):
    save_demo(tmp_path / "recordings", "reach-1")
    blocker = client.post(
        "/api/runs", json={"planning": "full", "experiments": 1, "episodes": 100_000}
    ).json()
    user = client.post("/api/runs", json={**TINY_RUN, "demonstrations": ["reach-1"]}).json()
    r = client.delete("/api/demonstrations/reach-1")
    assert r.status_code == 409 and user["id"] in r.json()["detail"]
    client.post(f"/api/runs/{user['id']}/stop")
    client.post(f"/api/runs/{blocker['id']}/stop")
    wait_run(client, blocker["id"])
    assert client.delete("/api/demonstrations/reach-1").status_code == 204
    assert not (tmp_path / "recordings" / "reach-1.demo.json").exists()
    assert client.get("/api/demonstrations/reach-1").status_code == 404


@pytest.mark.parametrize(
    ("body", "status", "words"),
    [
        ({"recording": "nope", "t0": 0, "t1": 1}, 404, "no recording"),
        ({"recording": "../x", "t0": 0, "t1": 1}, 422, "separator"),
        ({"recording": "x", "t0": 2, "t1": 1}, 422, "t1 > t0"),
        ({"recording": "x", "t0": -1, "t1": 1}, 422, "t0"),
        ({"recording": "x", "t0": 0}, 422, "t1 is missing"),
        ({"recording": "x", "t0": 0, "t1": 1, "name": "a/b"}, 422, "separator"),
    ],
)
def test_bad_cuts(client, body, status, words):
    r = client.post("/api/demonstrations", json=body)
    assert r.status_code == status and words in r.json()["detail"], r.text


def test_bad_names_and_unknown_demonstrations(client):
    assert client.get("/api/demonstrations/a..b").status_code == 422
    assert client.delete("/api/demonstrations/.x").status_code == 422
    assert client.get("/api/demonstrations/missing").status_code == 404
    assert client.post("/api/demonstrations/missing/preview").status_code == 404
    assert client.delete("/api/demonstrations/missing").status_code == 404


def test_marking_needs_a_capture(client):
    assert client.get("/api/demonstrations/mark").json() == {
        "marking": False,
        "t0": None,
        "demonstration": None,
    }
    for action in ("start", "stop"):
        r = client.post("/api/demonstrations/mark", json={"action": action})
        assert r.status_code == 409 and "press Record" in r.json()["detail"]
    assert client.post("/api/demonstrations/mark", json={"action": "pause"}).status_code == 422


DEEP = 50_000
"""Nesting depth of the damaged JSON file (issue 13: far past Python's recursion limit)."""


def test_damaged_demonstrations_are_listed_with_the_reason_and_hide_nothing(client, tmp_path):
    folder = tmp_path / "recordings"
    save_demo(folder, "good")
    (folder / "deep.demo.json").write_text("[" * DEEP + "]" * DEEP)
    (folder / "badjson.demo.json").write_text("{not json")
    (folder / "other.demo.json").write_text('{"format": "something-else", "version": 1}')
    r = client.get("/api/demonstrations")
    assert r.status_code == 200
    listed = {d["name"]: d for d in mine(r.json())}
    assert set(listed) == {"good", "deep", "badjson", "other"}
    for name in ("deep", "badjson", "other"):
        assert listed[name]["error"] and listed[name]["steps"] == 0, name
    assert listed["good"]["error"] is None and listed["good"]["steps"] > 0
    assert client.get("/api/demonstrations/deep").status_code == 422
    r = client.post("/api/runs", json={**TINY_RUN, "demonstrations": ["badjson"]})
    assert r.status_code == 422
    assert client.delete("/api/demonstrations/deep").status_code == 204  # damaged files can go


def _recording_going_back(seconds: float) -> bytes:
    """The sample reach with frame 250's time set ``seconds`` back."""
    from studio.samples import SAMPLES_DIR

    lines = (SAMPLES_DIR / "sample-reach-1.tape.csv").read_text().split("\n")
    row = next(i for i, line in enumerate(lines) if line.startswith("0.0,0,"))
    cells = lines[row + 250].split(",")
    cells[0] = repr(float(cells[0]) - seconds)
    lines[row + 250] = ",".join(cells)
    return "\n".join(lines).encode()


@pytest.mark.parametrize(
    ("body", "words"),
    [
        ('{"recording": "sample-reach-1", "t0": 0, "t1": 1e999}', "not two finite times"),
        ('{"recording": "odd", "t0": 1.0, "t1": 3.4}', "times that do not increase"),
    ],
)
def test_a_refused_cut_writes_no_file(client, tmp_path, body, words):
    """Such a cut once answered 422 but left ``….0.00-inf.demo.json`` behind, listed as damaged
    from then on."""
    files = {"file": ("odd.tape.csv", _recording_going_back(0.5), "text/csv")}
    assert client.post("/api/recordings", files=files).status_code == 201
    before = sorted(p.name for p in (tmp_path / "recordings").iterdir())
    r = client.post(
        "/api/demonstrations", content=body, headers={"content-type": "application/json"}
    )
    assert r.status_code == 422 and words in r.json()["detail"], r.text
    assert ".tmp" not in r.json()["detail"]
    assert sorted(p.name for p in (tmp_path / "recordings").iterdir()) == before
    assert all(not d["error"] for d in client.get("/api/demonstrations").json())
