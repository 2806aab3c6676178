"""One demonstration, one replayed path: the cutter, the page's run queue and ``studio train``.

Issue 9: for the shipped ``sample-reach-2`` the page replayed 20 steps (a path flickering between
two bins) and the CLI 8, while the demonstration list said 8. All three now go through
``ArmGrid.path_from_joints``.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np

from studio.cli import main
from studio.learning import ArmGrid
from studio.samples import SAMPLES_DIR as SAMPLES
from tests.web.conftest import TINY_RUN, wait_run


def _listed(client, name: str) -> dict:
    """The demonstration list's entry for ``name``."""
    (entry,) = [d for d in client.get("/api/demonstrations").json() if d["name"] == name]
    return entry


def _page_paths(client, runs_dir: Path, demos: list[str]) -> list[list[int]]:
    """The grid paths a run started from the page stores (and replays) for ``demos``."""
    r = client.post("/api/runs", json={**TINY_RUN, "demonstrations": demos})
    assert r.status_code == 201, r.text
    run_id = r.json()["id"]
    assert wait_run(client, run_id)["status"] == "done"
    return json.loads((runs_dir / run_id / "config.json").read_text())["demonstrations"]


def _cli_paths(demo_file: Path, out: Path) -> list[list[int]]:
    """The grid paths ``studio train --demos`` stores (and replays)."""
    code = main(
        [
            "train",
            "--demos",
            str(demo_file),
            "--out",
            str(out),
            "--experiments",
            "1",
            "--episodes",
            "2",
            "--planning",
            "zero",
            "--no-progress",
        ]
    )
    assert code == 0
    return json.loads((out / "config.json").read_text())["demonstrations"]


def test_a_cut_demonstration_replays_the_same_path_in_the_page_and_the_cli(
    client, tmp_path, capsys
):
    recordings = tmp_path / "recordings"
    shutil.copy(SAMPLES / "sample-reach-2.tape.csv", recordings)
    shipped = json.loads((SAMPLES / "sample-reach-2.demo.json").read_text())
    t0, t1 = shipped["segment"]
    r = client.post(
        "/api/demonstrations",
        json={"recording": "sample-reach-2", "t0": t0, "t1": t1, "name": "reach"},
    )
    assert r.status_code in (200, 201), r.text
    listed = _listed(client, "reach")
    detail = client.get("/api/demonstrations/reach").json()

    page = _page_paths(client, tmp_path / "runs", ["reach"])
    cli = _cli_paths(recordings / "reach.demo.json", tmp_path / "cli-run")
    assert page == cli == [detail["grid_path"]]
    assert listed["steps"] == len(page[0]) - 1 == 9
    path = page[0]
    grid = ArmGrid()
    assert path[-1] == grid.goal_state and len(set(path)) == len(path)  # no flicker
    assert path == grid.path_from_joints(np.asarray(detail["q_robot"]))
    # the run's first episode replays exactly that many steps
    (run,) = client.get("/api/runs").json()
    curve = client.get(f"/api/runs/{run['id']}/curve").json()
    assert curve["max"][0] == curve["min"][0] == len(path) - 1


def test_a_reach_and_return_cut_is_accepted_and_replayed_alike(client, tmp_path, capsys):
    """The sample reach played forward then back: accepted, cut at the first goal visit."""
    from studio.capture import RecordingWriter, TapeFrame, read_recording

    sample = read_recording(SAMPLES / "sample-reach-2.tape.csv")
    shipped = json.loads((SAMPLES / "sample-reach-2.demo.json").read_text())
    rows = np.arange(len(sample.t))[sample.segment(*shipped["segment"])]
    rows = np.concatenate([rows, rows[::-1]])
    path = tmp_path / "recordings" / "there-and-back.tape.csv"
    with RecordingWriter(path, config=sample.config) as writer:
        writer.write_many(
            [
                TapeFrame(i / sample.rate_hz, i, sample.bend[row], sample.twist[row])
                for i, row in enumerate(rows)
            ]
        )
    duration = (rows.shape[0] - 1) / sample.rate_hz
    r = client.post(
        "/api/demonstrations",
        json={"recording": "there-and-back", "t0": 0.0, "t1": duration, "name": "back"},
    )
    assert r.status_code in (200, 201), r.text
    assert client.get("/api/demonstrations/back").json()["grid_path"] == shipped["grid_path"]
    page = _page_paths(client, tmp_path / "runs", ["back"])
    cli = _cli_paths(tmp_path / "recordings" / "back.demo.json", tmp_path / "cli-run")
    assert page == cli == [shipped["grid_path"]]


def test_the_shipped_sample_replays_its_listed_steps(client, tmp_path, capsys):
    recordings = tmp_path / "recordings"
    for suffix in (".tape.csv", ".demo.json"):
        shutil.copy(SAMPLES / f"sample-reach-2{suffix}", recordings)
    listed = _listed(client, "sample-reach-2")
    page = _page_paths(client, tmp_path / "runs", ["sample-reach-2"])
    cli = _cli_paths(recordings / "sample-reach-2.demo.json", tmp_path / "cli-run")
    assert page == cli
    assert len(page[0]) - 1 == listed["steps"] == 9  # the page replayed 20 before


def test_the_cli_replays_the_trajectory_not_a_stored_grid_path(client, tmp_path, capsys):
    """A demo file whose stored ``grid_path`` was edited (or written by older code) replays the
    path its joint trajectory gives on the run's grid, as the page does."""
    recordings = tmp_path / "recordings"
    shutil.copy(SAMPLES / "sample-reach-2.tape.csv", recordings / "tampered.tape.csv")
    data = json.loads((SAMPLES / "sample-reach-2.demo.json").read_text())
    true_path = data["grid_path"]
    data["recording"] = "tampered.tape.csv"
    data["name"] = "tampered"
    data["grid_path"] = [true_path[0], *true_path[-1:]]  # a 1-step "path" no grid allows
    (recordings / "tampered.demo.json").write_text(json.dumps(data))
    page = _page_paths(client, tmp_path / "runs", ["tampered"])
    cli = _cli_paths(recordings / "tampered.demo.json", tmp_path / "cli-run")
    grid = ArmGrid()
    assert page == cli == [grid.path_from_joints(np.asarray(data["trajectory"]["q_robot"]))]
    assert cli == [true_path]


def test_the_cli_refuses_a_demonstration_that_misses_the_goal(tmp_path, capsys):
    data = json.loads((SAMPLES / "sample-reach-2.demo.json").read_text())
    q = np.asarray(data["trajectory"]["q_robot"])
    data["trajectory"]["q_robot"] = q[: len(q) // 4].tolist()  # stops well before the goal
    data["trajectory"]["t"] = data["trajectory"]["t"][: len(q) // 4]
    short = tmp_path / "short.demo.json"
    short.write_text(json.dumps(data))
    code = main(
        ["train", "--demos", str(short), "--out", str(tmp_path / "cli-run"), "--no-progress"]
    )
    assert code != 0
    err = capsys.readouterr().err
    assert "not in this run's goal bins (5, 6, 2)" in err and "Traceback" not in err
    assert not (tmp_path / "cli-run").exists()  # nothing half-made
