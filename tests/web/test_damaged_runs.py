"""One damaged run folder never hides the others: the list shows it as damaged, with the reason,
and it can be deleted.

Each damage below once answered 500 for the whole ``GET /api/runs`` (a ``RecursionError`` in
``json.loads``, a device read forever, a field of the wrong type in the run's public model) or
allocated without bound (a record claiming 10**12 episodes).
"""

from __future__ import annotations

import json
import logging
import os
import shutil
from pathlib import Path

import pytest

from tests.web.conftest import TINY_RUN, wait_run

DEEP = "[" * 50_000 + "]" * 50_000


def _damage(folder: Path, kind: str) -> None:
    """Damage a copy of a good run folder in one way."""
    config = json.loads((folder / "config.json").read_text())
    if kind == "deep-config":
        (folder / "config.json").write_text(DEEP)
    elif kind == "device-config":
        (folder / "config.json").unlink()
        os.symlink("/dev/zero", folder / "config.json")
    elif kind == "huge-budget":
        config["episodes"] = 10**12
        (folder / "config.json").write_text(json.dumps(config))
    elif kind == "wrong-types":
        config["group"] = {"not": "a name"}
        config["config"] = {"planning": ["zero"], "alpha": "fast"}
        config["request"] = None
        (folder / "config.json").write_text(json.dumps(config))
    elif kind == "deep-status":
        (folder / "status.json").write_text(DEEP)
    elif kind == "garbled-status":
        (folder / "status.json").write_text(
            json.dumps({"status": "done", "created": 5, "cpu_seconds": "x", "error": [1]})
        )
    elif kind == "device-steps":
        (folder / "steps.csv").unlink()
        os.symlink("/dev/zero", folder / "steps.csv")
    elif kind == "huge-steps":
        with (folder / "steps.csv").open("a") as f:
            f.write("1," * 1_000_000 + "\n")


DAMAGES = [
    ("deep-config", False),
    ("device-config", None),  # not a regular config.json: not a run folder at all
    ("huge-budget", False),
    ("wrong-types", False),
    # a damaged status or curve leaves a readable run (status derived, curve dropped)
    ("deep-status", True),
    ("garbled-status", True),
    ("device-steps", True),
    ("huge-steps", True),
]


@pytest.mark.parametrize(("kind", "listed"), DAMAGES)
def test_a_damaged_run_folder_never_breaks_the_list(open_client, tmp_path, caplog, kind, listed):
    client = open_client()
    good = client.post("/api/runs", json=TINY_RUN).json()["id"]
    assert wait_run(client, good)["status"] == "done"
    runs = tmp_path / "runs"
    shutil.copytree(runs / good, runs / "damaged")
    _damage(runs / "damaged", kind)

    with caplog.at_level(logging.WARNING):
        fresh = open_client()  # a restart reads every folder again
        response = fresh.get("/api/runs")
    assert response.status_code == 200, response.text
    ids = {run["id"] for run in response.json()}
    assert good in ids
    assert ("damaged" in ids) == (listed is not None)
    if listed:
        run = fresh.get("/api/runs/damaged").json()
        assert isinstance(run["cpu_seconds"], float) and not run["damaged"]
        assert fresh.get("/api/runs/damaged/curve").status_code == 200
    elif listed is False:  # listed as damaged, with the reason, and deletable
        entry = next(r for r in response.json() if r["id"] == "damaged")
        assert entry["status"] == "damaged" and entry["damaged"] is True
        assert "config.json" in entry["error"] and entry["error"].endswith(".")
        assert any("damaged" in r.getMessage() for r in caplog.records)  # and logged
        assert fresh.delete("/api/runs/damaged").status_code == 204
        assert not (runs / "damaged").exists()
        assert "damaged" not in {r["id"] for r in fresh.get("/api/runs").json()}


def test_a_run_that_cannot_be_deleted_wholly_says_so_and_stays_listed(
    client, tmp_path, monkeypatch
):
    run = client.post("/api/runs", json=TINY_RUN).json()["id"]
    assert wait_run(client, run)["status"] == "done"
    real_unlink = os.unlink

    def refuse_steps(path, *args, **kwargs):  # as a file the studio may not delete would
        if str(path).endswith("steps.csv"):
            raise PermissionError(13, "Permission denied", str(path))
        return real_unlink(path, *args, **kwargs)

    monkeypatch.setattr(os, "unlink", refuse_steps)
    response = client.delete(f"/api/runs/{run}")
    assert response.status_code == 409, response.text
    detail = response.json()["detail"]
    assert "could not be deleted" in detail and "steps.csv: Permission denied" in detail
    assert (tmp_path / "runs" / run / "steps.csv").exists()
    assert run in {r["id"] for r in client.get("/api/runs").json()}  # what is left is listed

    monkeypatch.setattr(os, "unlink", real_unlink)
    assert client.delete(f"/api/runs/{run}").status_code == 204
    assert not (tmp_path / "runs" / run).exists()


def test_a_linked_run_folder_is_listed_as_damaged_and_deleting_it_removes_the_link(
    client, tmp_path
):
    target = tmp_path / "elsewhere"
    good = client.post("/api/runs", json=TINY_RUN).json()["id"]
    assert wait_run(client, good)["status"] == "done"
    shutil.copytree(tmp_path / "runs" / good, target)
    os.symlink(target, tmp_path / "runs" / "linked")
    entry = {r["id"]: r for r in client.get("/api/runs").json()}["linked"]
    assert entry["status"] == "damaged" and "symbolic link" in entry["error"]
    assert client.get("/api/runs/linked/policy").status_code == 404
    assert client.delete("/api/runs/linked").status_code == 204
    assert not (tmp_path / "runs" / "linked").is_symlink() and (target / "config.json").exists()
