"""The shipped samples in every data folder: listed read-only, trainable, copyable (issue 10)."""

from __future__ import annotations

import numpy as np

from studio.capture import load_demonstration, read_recording
from studio.samples import SAMPLES_DIR
from tests.web.conftest import TINY_RUN, wait_run

RECORDINGS = sorted(p.name.removesuffix(".tape.csv") for p in SAMPLES_DIR.glob("*.tape.csv"))
DEMONSTRATIONS = sorted(p.name.removesuffix(".demo.json") for p in SAMPLES_DIR.glob("*.demo.json"))


def test_the_package_ships_samples():
    assert RECORDINGS and DEMONSTRATIONS
    assert all(name.startswith("sample-") for name in RECORDINGS + DEMONSTRATIONS)


def test_a_fresh_data_folder_lists_the_samples_read_only(client, tmp_path):
    assert not list((tmp_path / "recordings").iterdir())  # nothing copied into the folder
    recordings = client.get("/api/recordings").json()
    assert [r["name"] for r in recordings] == RECORDINGS
    for r in recordings:
        on_disk = read_recording(SAMPLES_DIR / f"{r['name']}.tape.csv")
        assert r["sample"] is True and r["error"] is None and r["frames"] == len(on_disk)
    demos = client.get("/api/demonstrations").json()
    assert [d["name"] for d in demos] == DEMONSTRATIONS
    assert all(d["sample"] and d["error"] is None and d["reaches_goal"] for d in demos)
    name = RECORDINGS[0]
    down = client.get(f"/api/recordings/{name}/file")
    assert down.content == (SAMPLES_DIR / f"{name}.tape.csv").read_bytes()


def test_a_run_replaying_a_sample_demonstration_trains(client):
    name = DEMONSTRATIONS[0]
    demo = load_demonstration(SAMPLES_DIR / f"{name}.demo.json")
    r = client.post("/api/runs", json={**TINY_RUN, "demonstrations": [name]})
    assert r.status_code in (200, 201), r.text
    done = wait_run(client, r.json()["id"])
    assert done["status"] == "done", done
    curve = client.get(f"/api/runs/{done['id']}/curve").json()
    # episode 1 of every experiment replays the sample: exactly its grid steps
    assert curve["min"][0] == curve["max"][0] == len(demo.grid_path) - 1


def test_a_sample_can_be_played_and_cut(client):
    name = RECORDINGS[0]
    r = client.put("/api/source", json={"kind": "recording", "recording": name})
    assert r.status_code == 200 and r.json()["recording"] == name
    demo = load_demonstration(SAMPLES_DIR / f"{name}.demo.json")
    r = client.post("/api/demonstrations", json={"recording": name, "t0": demo.t0, "t1": demo.t1})
    assert r.status_code == 201, r.text
    cut = r.json()
    assert not cut["name"].startswith("sample-") and cut["sample"] is False
    assert cut["recording"] == name and cut["steps"] == len(demo.grid_path) - 1


def test_samples_refuse_changes_in_one_sentence(client, tmp_path):
    rec, demo = RECORDINGS[0], DEMONSTRATIONS[0]
    for r in (
        client.delete(f"/api/recordings/{rec}"),
        client.patch(f"/api/recordings/{rec}", json={"notes": "mine now"}),
        client.patch(f"/api/recordings/{rec}", json={"name": "renamed"}),
        client.delete(f"/api/demonstrations/{demo}"),
    ):
        assert r.status_code == 409 and "shipped sample" in r.json()["detail"], r.text
        assert r.json()["detail"].count(". ") == 0  # one sentence
    assert (SAMPLES_DIR / f"{rec}.tape.csv").is_file()
    assert (SAMPLES_DIR / f"{demo}.demo.json").is_file()


def test_copy_a_sample_to_my_recordings(client, tmp_path):
    name = RECORDINGS[0]
    r = client.post(f"/api/recordings/{name}/copy")
    assert r.status_code == 201, r.text
    copy = r.json()
    assert copy["name"] == name.removeprefix("sample-") and copy["sample"] is False
    path = tmp_path / "recordings" / f"{copy['name']}.tape.csv"
    original = read_recording(SAMPLES_DIR / f"{name}.tape.csv")
    mine = read_recording(path)
    assert mine.meta["name"] == copy["name"]  # the header names the copy
    assert np.array_equal(mine.bend, original.bend) and np.array_equal(mine.t, original.t)
    assert client.post(f"/api/recordings/{name}/copy").json()["name"] == f"{copy['name']}-2"
    r = client.post(f"/api/recordings/{name}/copy", json={"name": copy["name"]})
    assert r.status_code == 409
    r = client.patch(f"/api/recordings/{copy['name']}", json={"notes": "mine now"})
    assert r.status_code == 200 and r.json()["notes"] == "mine now"
    assert client.delete(f"/api/recordings/{copy['name']}").status_code == 204
