"""Text that is not text: an unpaired UTF-16 surrogate (``"caf\\udce9"``, a Latin-1 byte a
shell passed, or a lone ``\\ud800`` escape a script sent).

Such a name once answered 500 for every ``GET /api/runs`` (or ``/api/recordings``) across
restarts, and ``POST /api/runs`` answered 500 while it created and trained the run. Now the API
refuses it in one sentence before doing anything, and a file stored before that is listed with
the character replaced, never hiding the others.
"""

from __future__ import annotations

import json

from tests.web.conftest import TINY_RUN, wait_run
from tests.web.test_recordings import write_recording

JSON = {"content-type": "application/json"}


def _post(client, path: str, body: dict, method: str = "post"):
    return getattr(client, method)(path, content=json.dumps(body), headers=JSON)


def test_a_run_named_with_a_lone_surrogate_is_refused_before_it_is_made(client):
    answer = _post(client, "/api/runs", {**TINY_RUN, "name": "caf\udce9"})
    assert answer.status_code == 422
    assert answer.json()["detail"].startswith("name holds an unpaired UTF-16 surrogate")
    assert client.get("/api/runs").json() == []  # nothing created, nothing trained


def test_notes_and_tags_with_a_lone_surrogate_answer_422_and_keep_the_old_ones(client):
    run = client.post("/api/runs", json={**TINY_RUN, "name": "ok"}).json()
    wait_run(client, run["id"])
    assert client.put(f"/api/runs/{run['id']}/notes", json={"notes": "fine"}).status_code == 200
    notes = _post(client, f"/api/runs/{run['id']}/notes", {"notes": "x\ud800"}, "put")
    tags = _post(client, f"/api/runs/{run['id']}/notes", {"tags": ["a", "\udfff"]}, "put")
    assert notes.status_code == tags.status_code == 422
    assert tags.json()["detail"].startswith("tags.1 holds an unpaired UTF-16 surrogate")
    assert client.get(f"/api/runs/{run['id']}/notes").json()["notes"] == "fine"


def test_an_emoji_escaped_as_a_surrogate_pair_is_text(client):
    answer = _post(client, "/api/runs", {**TINY_RUN, "name": "reach \U0001f600"})
    assert answer.status_code == 201 and answer.json()["name"] == "reach \U0001f600"


def test_a_run_stored_with_a_lone_surrogate_is_listed_with_the_others(open_client, tmp_path):
    client = open_client()
    ids = [client.post("/api/runs", json={**TINY_RUN, "name": n}).json()["id"] for n in "ab"]
    for run_id in ids:
        wait_run(client, run_id)
    config = next((tmp_path / "runs").glob(f"{ids[0]}*/config.json"))
    stored = json.loads(config.read_text())
    stored["name"] = "caf\udce9"  # as `studio train --name $'caf\xe9'` once stored it
    config.write_text(json.dumps(stored))
    restarted = open_client()
    answer = restarted.get("/api/runs")
    assert answer.status_code == 200
    names = {run["id"]: run["name"] for run in answer.json()}
    assert names == {ids[0]: "caf\ufffd", ids[1]: "b"}


def test_a_recording_stored_with_a_lone_surrogate_is_listed_with_the_others(tmp_path, client):
    folder = tmp_path / "recordings"
    folder.mkdir(exist_ok=True)
    write_recording(folder / "good.tape.csv")
    bad = write_recording(folder / "bad.tape.csv")
    text = bad.read_text()
    bad.write_text(text.replace('"operator": "ada"', '"operator": "Jos\\udce9"', 1))
    answer = client.get("/api/recordings")
    assert answer.status_code == 200
    operators = {r["name"]: r["operator"] for r in answer.json() if r["name"] in ("good", "bad")}
    assert operators == {"good": "ada", "bad": "Jos\ufffd"}
