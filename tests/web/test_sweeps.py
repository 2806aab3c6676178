"""``/api/sweeps``: a sweep's summary, CSV and figure; its trials are ordinary runs in ``/api/runs``.

The sweep folder is made here without Ray, trial by trial through the same pieces ``run_sweep``
uses (the trial's run record, ``RunFolder``, the summary writer); ``tests/learning/test_sweep.py``
covers the sweep on Ray itself.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest

from studio.learning.runs._folder import RunFolder
from studio.learning.sweeps._folder import prepare_folder as _prepare
from studio.learning.sweeps._folder import set_status as _set_status
from studio.learning.sweeps._folder import trial_run_path
from studio.learning.sweeps._spec import parse_sweep_spec, trial_record
from studio.learning.sweeps._summary import write_summary

SPEC = {
    "name": "tiny",
    "task": "arm-grid",
    "seeds": [0, 1],
    "experiments": 2,
    "episodes": 12,
    "fixed": {"planning_steps": 5},
    "space": {"planning": ["zero", "full"]},
}


def make_sweep(data_dir: Path, spec_data: dict = SPEC, trials: int | None = None) -> list[str]:
    """Train a sweep's trials (all, or the first ``trials``) into ``data_dir``; their keys."""
    spec = parse_sweep_spec(spec_data)
    _prepare(data_dir, spec, resume=False)
    keys = []
    for trial in spec.trials()[:trials]:
        path = trial_run_path(data_dir, spec.name, trial.key)
        run = RunFolder.create(path.parent, trial_record(spec, trial), name=path.name)
        run.train(workers=1)
        keys.append(trial.key)
    write_summary(data_dir, spec)
    _set_status(data_dir / "sweeps" / spec.name, "done" if trials is None else "interrupted")
    return keys


def test_a_sweep_is_listed_with_its_summary_and_its_runs(client, tmp_path: Path) -> None:
    keys = make_sweep(tmp_path)
    sweeps = client.get("/api/sweeps").json()
    assert [s["id"] for s in sweeps] == ["tiny"]
    sweep = client.get("/api/sweeps/tiny").json()
    assert sweep == sweeps[0]
    assert sweep["status"] == "done" and sweep["trials"] == sweep["finished"] == 4
    assert sweep["swept"] == ["planning"] and sweep["metric"] == "episodes_to_converge"
    assert [row["trial"] for row in sweep["rows"]] == keys
    assert {row["planning"] for row in sweep["rows"]} == {"zero", "full"}
    assert sweep["columns"][:4] == ["trial", "seed", "planning", "status"]
    runs = {r["id"]: r for r in client.get("/api/runs").json()}
    assert set(sweep["runs"]) == {f"tiny~tiny-{key}" for key in keys}
    for run_id in sweep["runs"]:  # every trial is an ordinary run of the page
        run = runs[run_id]
        assert run["group"] == "tiny" and run["origin"] == "sweep" and run["has_policy"]
        curve = client.get(f"/api/runs/{run_id}/curve").json()
        assert curve["episodes"] == list(range(1, 13))


def test_a_trials_policy_can_be_watched_and_exported(client, tmp_path: Path) -> None:
    make_sweep(tmp_path)
    run_id = client.get("/api/sweeps/tiny").json()["runs"][0]
    policy = client.get(f"/api/runs/{run_id}/policy")
    assert policy.status_code == 200 and policy.content[:2] == b"PK"  # an npz is a zip
    watched = client.post("/api/watch", json={"run": run_id, "seed": 0})
    assert watched.status_code == 200, watched.text
    assert watched.json()["states"]
    trajectory = client.get("/api/watch/trajectory.csv")
    assert trajectory.status_code == 200 and trajectory.text.startswith("time,q1")


def test_the_summary_csv_and_figure_download(client, tmp_path: Path) -> None:
    make_sweep(tmp_path)
    answer = client.get("/api/sweeps/tiny/sweep.csv")
    assert answer.status_code == 200 and answer.headers["content-type"].startswith("text/csv")
    assert answer.text == (tmp_path / "sweeps" / "tiny" / "sweep.csv").read_text()
    rows = list(csv.DictReader(io.StringIO(answer.text)))
    assert len(rows) == 4 and all(row["status"] == "done" for row in rows)
    png = client.get("/api/sweeps/tiny/figure.png")
    assert png.status_code == 200 and png.content[:8] == b"\x89PNG\r\n\x1a\n"
    svg = client.get("/api/sweeps/tiny/figure.svg")
    assert svg.status_code == 200 and b"<svg" in svg.content[:500]
    assert client.get("/api/sweeps/tiny/figure.gif").status_code == 422


def test_an_interrupted_sweep_shows_what_finished(client, tmp_path: Path) -> None:
    make_sweep(tmp_path, trials=2)
    sweep = client.get("/api/sweeps/tiny").json()
    assert sweep["status"] == "interrupted" and (sweep["trials"], sweep["finished"]) == (4, 2)
    assert [row["status"] for row in sweep["rows"]] == ["done", "done", "not run", "not run"]
    assert len(sweep["runs"]) == 2


@pytest.mark.parametrize("sweep_id", ["nope", "-x", "a b"])
def test_an_unknown_sweep_is_404_in_one_sentence(client, sweep_id: str) -> None:
    answer = client.get(f"/api/sweeps/{sweep_id}")
    assert answer.status_code == 404
    detail = answer.json()["detail"]
    assert "\n" not in detail and detail.endswith(".")


def test_no_sweeps_is_an_empty_list(client) -> None:
    assert client.get("/api/sweeps").json() == []
