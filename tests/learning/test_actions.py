"""The continuous task's action sets: one joint per action, the pairs, or any joints at once."""

from __future__ import annotations

import json
import math

import gymnasium
import numpy as np
import pytest

from studio.cli import main
from studio.learning import (
    ACTION_SETS,
    REACH_DEFAULTS,
    ArmReach,
    ConfigError,
    DynaQConfig,
    RunRecord,
    RunRequest,
    load_any_policy,
    resolve_run,
    run_experiments,
)
from studio.learning.linear._policy import save_tile_policy
from studio.learning.tasks._gym import ARM_REACH_ID
from studio.learning.tasks._reach import action_directions, reach_step
from studio.web._schemas import ReachRunCreate


@pytest.mark.parametrize("joints", [3, 4, 5, 6])
def test_each_action_set_has_its_size_and_begins_with_the_one_before(joints):
    # "follow" without demonstrated paths to follow moves one joint per action
    sizes = {
        "single": 2 * joints,
        "pairs": 2 * joints**2,
        "all": 3**joints - 1,
        "follow": 2 * joints,
        "all-follow": 3**joints - 1,
    }
    tables = {name: action_directions(joints, name) for name in ACTION_SETS}
    for name, table in tables.items():
        assert ArmReach(joints=joints, actions=name).n_actions == sizes[name] == table.shape[0]
        assert len({tuple(row) for row in table}) == table.shape[0]  # no move twice
        assert np.abs(table).sum(axis=1).min() == 1  # no "stay"
    assert np.array_equal(tables["pairs"][: 2 * joints], tables["single"])
    assert np.array_equal(tables["all"][: 2 * joints**2], tables["pairs"])
    assert np.array_equal(tables["follow"], tables["single"])
    assert np.array_equal(tables["all-follow"], tables["all"])
    assert np.abs(tables["pairs"]).sum(axis=1).max() == 2
    single = tables["single"]  # action 2j moves joint j up, 2j + 1 down, as before
    for j in range(joints):
        assert single[2 * j, j] == 1 and single[2 * j + 1, j] == -1


def test_the_default_moves_one_joint_per_action_and_follows_demonstrations_when_given():
    assert ArmReach().actions == "follow" == REACH_DEFAULTS["actions"]
    assert ArmReach(joints=6).n_actions == 12  # without demonstrations: one joint per action
    goal = np.asarray(ArmReach(joints=6).goal)
    path = np.linspace(goal - 0.3, goal, 20)
    assert ArmReach(joints=6).with_paths([path]).n_actions == 13


def test_a_diagonal_move_changes_two_joints_in_one_step():
    task = ArmReach(joints=3, actions="pairs")
    table = task.directions
    up_up = int(np.flatnonzero((table == (1, 1, 0)).all(axis=1))[0])
    q = 0.5 * (task.lower + task.upper)
    before = q.copy()
    reach_step(task.params, q, up_up)
    assert np.allclose(q - before, [task.step, task.step, 0.0])
    # a joint at its limit stays there; the action's other joint still moves
    q = before.copy()
    q[0] = task.upper[0]
    reach_step(task.params, q, up_up)
    assert q[0] == task.upper[0] and math.isclose(q[1], before[1] + task.step)


def test_the_gym_env_offers_every_move_of_its_set():
    env = gymnasium.make(ARM_REACH_ID, joints=3, actions="all")
    assert env.action_space.n == 26
    q0, _ = env.reset(seed=0, options={"q": [0.0, 0.5, -1.0]})
    index = int(np.flatnonzero((env.unwrapped.task.directions == (1, -1, 1)).all(axis=1))[0])
    q1, *_ = env.step(index)
    assert np.allclose(q1 - q0, np.radians(2.0) * np.array([1, -1, 1]))


def test_a_demonstration_walks_diagonally_when_the_task_can():
    single = ArmReach(joints=3, actions="single")
    pairs = ArmReach(joints=3, actions="pairs")
    everything = ArmReach(joints=3, actions="all")
    goal = np.array(single.goal[:3])
    path = np.linspace(goal + np.radians([30.0, -30.0, 30.0]), goal, 40)
    lengths = {}
    for task in (single, pairs, everything):
        start, actions = task.demonstration_actions(path)
        q = start.copy()
        done = False
        for a in actions:
            _, done = reach_step(task.params, q, int(a))
        assert done and np.allclose(start, path[0])
        lengths[task.actions] = len(actions)
    assert lengths["all"] < lengths["pairs"] < lengths["single"]
    assert 2.5 * lengths["all"] < lengths["single"]  # all three joints at once: a third


def test_the_action_set_round_trips_through_config_json_the_form_and_policy_files(tmp_path):
    record = resolve_run(
        RunRequest(
            task="arm-reach", reach={"joints": 3, "actions": "pairs"}, experiments=1, episodes=3
        )
    )
    assert record.arm_reach().actions == "pairs"
    stored = json.loads(json.dumps(record.to_dict()))
    assert stored["task"]["actions"] == "pairs"
    assert RunRecord.from_dict(stored) == record
    form = record.form()
    assert form["actions"] == "pairs"
    assert resolve_run(RunRequest.from_form(form)).arm_reach() == record.arm_reach()
    assert ReachRunCreate(**{**form, "name": None}).actions == "pairs"
    # a task stored before the field existed moves one joint per action
    old = {k: v for k, v in record.arm_reach().to_dict().items() if k != "actions"}
    assert ArmReach.from_dict(old).actions == "single"

    task = record.arm_reach()
    make = lambda: gymnasium.make(ARM_REACH_ID, joints=3, actions="pairs")  # noqa: E731
    result = run_experiments(make, DynaQConfig(planning="zero"), 1, 2, 0, features=task.features())
    path = tmp_path / "pairs.policy.npz"
    save_tile_policy(path, result)
    policy = load_any_policy(path)
    assert policy.task == task and policy.n_actions == 18


def test_a_bad_action_set_is_refused_in_one_sentence(capsys):
    with pytest.raises(ConfigError) as err:
        ArmReach(actions="diagonal")
    assert set(err.value.by_field) == {"actions"}
    sentence = err.value.by_field["actions"]
    assert sentence.startswith("actions is 'diagonal'; give 'single', 'pairs', 'all'")
    assert sentence.count(". ") == 0 and sentence.endswith(".")
    with pytest.raises(ConfigError) as err:
        resolve_run(RunRequest(task="arm-reach", reach={"actions": 3}))
    assert "actions is 3" in err.value.by_field["actions"]
    assert main(["train", "--actions", "pairs", "--episodes", "2", "--no-progress"]) == 2
    out = capsys.readouterr().err
    assert "--actions sets the continuous task; add --task arm-reach" in out
    assert "Traceback" not in out and out.count("\n") == 1


def test_a_sweep_trial_takes_the_action_set():
    from studio.learning.sweeps._spec import resolve_trial

    record = resolve_trial("arm-reach", {"joints": 3, "actions": "all"}, 1, 2, 0)
    assert record.arm_reach().n_actions == 26
