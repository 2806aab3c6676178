"""One resolver from a run request to a run record, typed records, and errors keyed by field."""

from __future__ import annotations

import json

import numpy as np
import pytest

from studio.learning import (
    ArmGrid,
    ArmReach,
    ConfigError,
    DemonstrationPath,
    DynaQConfig,
    RunFolder,
    RunRecord,
    RunRequest,
    TileCoding,
    resolve_run,
)


@pytest.mark.parametrize(
    ("build", "field"),
    [
        (lambda: ArmReach(joints=9), "joints"),
        (lambda: ArmReach(step_deg=500.0), "step_deg"),
        (lambda: ArmReach(goal=(9.0, 9.0, 9.0)), "goal"),
        (lambda: TileCoding(tiles=0), "tiles"),
        (lambda: TileCoding(tilings=0), "tilings"),
    ],
)
def test_the_continuous_tasks_errors_carry_their_field(build, field):
    with pytest.raises(ConfigError) as err:
        build()
    assert list(err.value.by_field) == [field]
    assert str(err.value).startswith(field) or field == "goal"


def test_every_bad_setting_of_a_request_is_reported_at_once_keyed_by_the_persons_field():
    with pytest.raises(ConfigError) as err:
        resolve_run(
            RunRequest(
                task="arm-reach",
                config={"alpha": 2.0},
                reach={"step_deg": 500.0},
                goal_deg=(170.0, 0.0, 0.0),
                seed=-1,
            )
        )
    assert {"alpha", "step_deg", "goal_deg", "seed"} <= set(err.value.by_field)
    with pytest.raises(ConfigError) as err:
        resolve_run(RunRequest(grid={"bins": 1}, experiments=0))
    assert {"bins", "experiments"} <= set(err.value.by_field)
    with pytest.raises(ConfigError) as err:
        resolve_run(RunRequest(generated=-2, episodes=0))
    assert {"episodes", "demonstrations"} <= set(err.value.by_field)
    with pytest.raises(ConfigError) as err:
        resolve_run(RunRequest(task="arm-elsewhere"))
    assert list(err.value.by_field) == ["task"]


@pytest.mark.parametrize(
    "request_",
    [
        RunRequest(config={"planning": "zero"}, goal_deg=(0.0, 45.0, -90.0), experiments=3),
        RunRequest(grid={"bins": 7}, episodes=12, seed=5, generated=2, name="g"),
        RunRequest(task="arm-reach", reach={"joints": 4, "tiles": 6}, goal_deg=(10.0, 40.0, -80.0)),
    ],
)
def test_a_records_form_resolves_back_to_the_same_record(request_):
    """The page shows a run by RunRecord.form(); resolving that form again gives the same run
    (so the page, the CLI and a sweep that ask alike get the same record)."""
    record = resolve_run(request_)
    again = resolve_run(RunRequest.from_form(record.form(), origin=record.origin))
    same = ("task", "coding", "config", "experiments", "episodes", "seed", "name", "goal_deg")
    assert all(getattr(again, k) == getattr(record, k) for k in same)
    assert isinstance(record.config, DynaQConfig)
    assert isinstance(record.task, ArmReach if request_.task == "arm-reach" else ArmGrid)


def test_generated_demonstrations_draw_from_the_runs_seed():
    one = resolve_run(RunRequest(generated=3, seed=7))
    two = resolve_run(RunRequest(generated=3, seed=7))
    assert len(one.demonstrations) == 3 and one.demonstrations == two.demonstrations
    assert all(path[-1] == ArmGrid().goal_state for path in one.demonstrations)


def test_a_recorded_demonstration_off_the_goal_names_itself():
    q = np.zeros((5, 6))
    with pytest.raises(ConfigError) as err:
        resolve_run(RunRequest(demonstrations=[DemonstrationPath("Demonstration 'x'", q, "x")]))
    assert list(err.value.by_field) == ["demonstrations"]
    assert str(err.value).startswith("Demonstration 'x' ends at joints (0, 0, 0) degrees")


def test_a_page_config_json_of_the_previous_layout_loads_typed(tmp_path):
    """config.json as the studio wrote it before records were typed: the page's whole form as
    ``request``, beside the record's own fields."""
    request = {
        "name": "mine",
        "planning": "zero",
        "planning_steps": 100,
        "epsilon": 0.1,
        "alpha": 0.1,
        "gamma": 0.95,
        "episodes": 4,
        "experiments": 2,
        "bins": 11,
        "task": "arm-grid",
        "joints": 3,
        "step_deg": 5.0,
        "tilings": 8,
        "tiles": 8,
        "goal_deg": [1.0, 44.0, -91.0],
        "demonstrations": ["reach-1"],
        "seed": 1,
    }
    data = {
        "format": "teach-studio-run",
        "version": 1,
        "task": {"kind": "arm-grid", **ArmGrid().to_dict()},
        "config": DynaQConfig(planning="zero").to_dict(),
        "experiments": 2,
        "episodes": 4,
        "seed": 1,
        "demonstrations": [],
        "name": "mine",
        "origin": "page",
        "group": None,
        "created": "2026-11-01T10:00:00+00:00",
        "request": request,
    }
    (tmp_path / "config.json").write_text(json.dumps(data))
    record = RunFolder.load(tmp_path).record
    assert record.config == DynaQConfig(planning="zero") and record.task == ArmGrid()
    assert record.goal_deg == (1.0, 44.0, -91.0) and record.demonstration_names == ("reach-1",)
    written = record.to_dict()
    assert set(written) == set(data)  # the same layout
    assert {k: v for k, v in written.items() if k != "request"} == {
        k: v for k, v in data.items() if k != "request"
    }
    grid_form = {
        k: v for k, v in request.items() if k not in ("joints", "step_deg", "tilings", "tiles")
    }
    assert written["request"] == {**grid_form, "robot": "puma560"}  # the form names its robot
    assert RunRecord.from_dict(written) == record
