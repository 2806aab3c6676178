"""The train form is checked as it is filled in: the demonstrations picked against its goal."""

from __future__ import annotations

from tests.web.conftest import TINY_RUN


def test_a_demonstration_for_another_goal_is_named_before_start(client):
    form = {**TINY_RUN, "demonstrations": ["sample-reach-1"]}
    fine = client.post("/api/demonstrations/check", json=form)
    assert fine.status_code == 204
    other = client.post("/api/demonstrations/check", json={**form, "goal_deg": [-120, 45, -90]})
    assert other.status_code == 422  # what Start would answer
    said = other.json()["by_field"]["demonstrations"]
    assert "sample-reach-1" in said and "goal" in said
    assert client.get("/api/runs").json() == []  # a check starts nothing


def test_an_unknown_demonstration_is_one_sentence(client):
    r = client.post("/api/demonstrations/check", json={**TINY_RUN, "demonstrations": ["nope"]})
    assert r.status_code == 422 and "nope" in r.json()["detail"]
