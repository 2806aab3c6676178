"""``RunCreate`` is a union by task: each task's fields, the page's bodies accepted as before."""

from __future__ import annotations

import pytest
from pydantic import TypeAdapter, ValidationError

from studio.web._app import validation_sentence
from studio.web._schemas import GridRunCreate, ReachRunCreate, RunCreate
from tests.web.conftest import TINY_RUN, wait_run

RUN_CREATE = TypeAdapter(RunCreate)

# the bodies app.js's readTrainForm() sends: every field, bins with both tasks
PAGE_GRID = {
    "planning": "zero",
    "planning_steps": 5,
    "epsilon": 0.1,
    "alpha": 0.1,
    "gamma": 0.95,
    "episodes": 4,
    "experiments": 2,
    "bins": 11,
    "task": "arm-grid",
    "seed": 1,
    "goal_deg": [0, 45, -90],
    "demonstrations": [],
}
PAGE_REACH = {
    **PAGE_GRID,
    "task": "arm-reach",
    "joints": 3,
    "step_deg": 2,
    "tilings": 4,
    "tiles": 6,
}


def test_the_union_picks_the_task_and_takes_the_pages_bodies():
    assert isinstance(RUN_CREATE.validate_python(PAGE_GRID), GridRunCreate)
    assert isinstance(RUN_CREATE.validate_python(TINY_RUN), GridRunCreate)  # no task: the grid
    reach = RUN_CREATE.validate_python(PAGE_REACH)
    assert isinstance(reach, ReachRunCreate) and reach.tiles == 6
    with pytest.raises(ValidationError):  # the grid has no continuous-task fields
        RUN_CREATE.validate_python({**PAGE_GRID, "tiles": 6})


@pytest.mark.parametrize(
    ("body", "sentence"),
    [
        ({**PAGE_REACH, "tiles": "x"}, "tiles is 'x': "),
        ({**PAGE_GRID, "turbo": 1}, "turbo is not a known field"),
        ({**PAGE_GRID, "task": "fly"}, "task is 'fly': "),
    ],
)
def test_a_schema_error_names_the_field_not_the_union_member(body, sentence):
    with pytest.raises(ValidationError) as err:
        RUN_CREATE.validate_python(body)
    assert validation_sentence(err.value.errors()).startswith(sentence)


def test_a_continuous_run_from_the_pages_body_trains_and_shows_its_form(client):
    r = client.post("/api/runs", json={**PAGE_REACH, "joints": 3, "episodes": 2, "experiments": 1})
    assert r.status_code == 201, r.text
    run = wait_run(client, r.json()["id"])
    assert run["status"] == "done"
    config = run["config"]
    assert (config["task"], config["tiles"], config["tilings"]) == ("arm-reach", 6, 4)
    assert "bins" not in config or config["bins"] is None
    r = client.post("/api/runs", json={**PAGE_GRID, "tiles": 6})
    assert r.status_code == 422 and r.json()["detail"].startswith("tiles is not a known field")
