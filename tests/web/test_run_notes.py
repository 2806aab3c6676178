"""Run tags and notes through the API (``<run>/notes.json``), and several runs in one curves CSV."""

from __future__ import annotations

import csv
import io
import json
import os

import pytest

from studio.learning import curves_csv
from studio.learning.runs._curves import CURVE_COLUMNS, TIME_COLUMNS
from studio.learning.runs._notes import MAX_NOTES_CHARS, MAX_TAG_CHARS, MAX_TAGS, NOTES_FILE
from tests.web.conftest import TINY_RUN, wait_run

EVIL = "http://evil.example"


@pytest.fixture
def two_runs(client):
    ids = []
    for name in ("alpha", "beta"):
        run = client.post("/api/runs", json={**TINY_RUN, "name": name}).json()
        ids.append(wait_run(client, run["id"])["id"])
    return ids


def test_tags_and_notes_land_beside_config_json_and_survive_a_reload(client, tmp_path, two_runs):
    a, b = two_runs
    folder = tmp_path / "runs" / a
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    r = client.put(
        f"/api/runs/{a}/notes", json={"tags": [" baseline ", "grid", "baseline"], "notes": "first"}
    )
    assert r.status_code == 200, r.text
    assert r.json()["tags"] == ["baseline", "grid"] and r.json()["updated"]
    stored = json.loads((folder / NOTES_FILE).read_text())
    assert stored["format"] == "teach-studio-run-notes"
    assert stored["tags"] == ["baseline", "grid"] and stored["notes"] == "first"
    # nothing the learner wrote changed
    assert {p: (folder / p).read_bytes() for p in before} == before
    assert client.get(f"/api/runs/{a}/notes").json()["notes"] == "first"
    assert client.get(f"/api/runs/{b}/notes").json() == {
        "tags": [],
        "notes": "",
        "updated": None,
        "error": None,
    }
    listed = client.get("/api/run-notes").json()
    assert list(listed) == [a] and listed[a]["tags"] == ["baseline", "grid"]
    # the run list still loads the run as before
    assert client.get(f"/api/runs/{a}").json()["status"] == "done"


@pytest.mark.parametrize(
    ("body", "words"),
    [
        ({"tags": ["x" * (MAX_TAG_CHARS + 1)]}, "shorten it"),
        ({"tags": [f"t{i}" for i in range(MAX_TAGS + 1)]}, f"more than the {MAX_TAGS}"),
        ({"tags": ["a,b"]}, "comma"),
        ({"tags": ["  "]}, "empty"),
        ({"notes": "n" * (MAX_NOTES_CHARS + 1)}, "shorten them"),
        ({"notes": "bell\x07"}, "control character"),
        ({"tags": "baseline"}, "tags"),
        ({"colour": "red"}, "colour"),
    ],
)
def test_bad_tags_or_notes_get_one_sentence_and_store_nothing(
    client, tmp_path, two_runs, body, words
):
    a = two_runs[0]
    r = client.put(f"/api/runs/{a}/notes", json=body)
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    assert words in detail and detail.count(". ") == 0 and "Traceback" not in detail
    assert not (tmp_path / "runs" / a / NOTES_FILE).exists()


def test_unknown_runs_and_folders_being_written_are_refused(client, tmp_path, two_runs):
    r = client.put("/api/runs/no-such-run/notes", json={"tags": ["x"]})
    assert r.status_code == 404 and "no run" in r.json()["detail"]
    folder = tmp_path / "runs" / two_runs[1]
    os.rename(folder / "config.json", folder / "config.json.moving")  # as a delete in progress
    r = client.put(f"/api/runs/{two_runs[1]}/notes", json={"tags": ["x"]})
    assert r.status_code == 409 and "being written or deleted" in r.json()["detail"]
    assert not (folder / NOTES_FILE).exists()


def test_a_damaged_notes_file_is_reported_and_replaced_by_a_save(client, tmp_path, two_runs):
    a = two_runs[0]
    (tmp_path / "runs" / a / NOTES_FILE).write_text("{not json")
    got = client.get(f"/api/runs/{a}/notes").json()
    assert got["tags"] == [] and "not valid JSON" in got["error"]
    assert client.put(f"/api/runs/{a}/notes", json={"tags": ["ok"]}).status_code == 200
    assert client.get(f"/api/runs/{a}/notes").json()["tags"] == ["ok"]


def test_notes_from_another_site_are_refused(client, tmp_path, two_runs):
    a = two_runs[0]
    r = client.put(f"/api/runs/{a}/notes", json={"tags": ["x"]}, headers={"Origin": EVIL})
    assert r.status_code == 403 and "another site" in r.json()["detail"]
    assert not (tmp_path / "runs" / a / NOTES_FILE).exists()


def test_several_runs_export_in_one_csv_in_the_one_layout(client, two_runs):
    a, b = two_runs
    r = client.get("/api/run-curves.csv", params=[("run", b), ("run", a)])
    assert r.status_code == 200 and "attachment" in r.headers["content-disposition"]
    rows = list(csv.reader(io.StringIO(r.text)))
    assert rows[0] == ["configuration", *CURVE_COLUMNS, *TIME_COLUMNS]
    assert [row[0] for row in rows[1:]] == ["beta"] * 4 + ["alpha"] * 4
    # each run's rows are exactly its own curves.csv, with the run's name in front
    own = client.get(f"/api/runs/{a}/curve.csv").text.splitlines()[1:]
    assert [",".join(row[1:]) for row in rows[5:]] == own
    assert curves_csv(client.get(f"/api/runs/{a}/curve").json(), "alpha").splitlines()[1:] == [
        ",".join(row) for row in rows[5:]
    ]
    assert client.get("/api/run-curves.csv").status_code == 422
    assert client.get("/api/run-curves.csv", params={"run": "nope"}).status_code == 404


def test_notes_saved_while_the_run_is_deleted_leave_nothing_behind(tmp_path, monkeypatch):
    from studio.learning import RunBusyError, write_run_notes
    from studio.learning.runs import _notes as _run_notes

    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "config.json").write_text("{}")
    real = _run_notes.atomic_write_text

    def write_then_delete(path, text):  # the delete removes config.json while notes are written
        out = real(path, text)
        (folder / "config.json").unlink()
        return out

    monkeypatch.setattr(_run_notes, "atomic_write_text", write_then_delete)
    with pytest.raises(RunBusyError, match="deleted while its notes were saved"):
        write_run_notes(folder, ["x"], "")
    assert list(folder.iterdir()) == []
