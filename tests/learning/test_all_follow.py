"""``--actions all-follow``: any joints at once, or follow the demonstrations (issue 40's learner
that beats its teacher) is an action set a run picks by name, stores, and whose greedy policy
(handing over to the follow action where its moves loop) is what ``studio evaluate`` judges."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import studio.web
from studio.cli import main
from studio.learning import RunRequest, load_any_policy, resolve_run
from studio.learning.linear._greedy import greedy_success, hand_over_action
from studio.learning.linear._teacher import follows_demonstrations
from studio.web._schemas import ReachRunCreate

ARGV = [
    "train", "--task", "arm-reach", "--actions", "all-follow", "--demos", "sample-reach-1",
    "--shaping", "0", "--demo-potential", "5", "--planning", "zero", "--episodes", "8",
    "--experiments", "1", "--no-progress",
]  # fmt: skip


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("all-follow") / "run"
    assert main([*ARGV, "--out", str(out)]) == 0
    return out


def test_the_action_set_is_picked_by_name_and_stored_with_the_run(run):
    task = json.loads((run / "config.json").read_text())["task"]
    assert task["kind"] == "arm-reach" and task["actions"] == "all-follow"
    assert task["demo_potential"] == 5.0 and task["shaping"] == 0.0
    policy = load_any_policy(run / "policy.policy.npz")
    assert policy.task.actions == "all-follow" and len(policy.task.paths) == 1
    assert policy.weights.shape[1] == policy.task.n_actions == 3**6  # 728 moves and follow
    assert follows_demonstrations(policy.task)  # so it has a teacher to stand beside
    assert hand_over_action(policy.task) == policy.task.n_actions - 1


def test_studio_evaluate_judges_the_policy_that_hands_over(run, capsys, tmp_path):
    """Weights that always move joint 1 up stall at its limit: the policy that hands over to
    the follow action there reaches the goal from every start, the same greedy moves alone from
    none, and ``studio evaluate`` judges the first."""
    trained = np.load(run / "policy.policy.npz")
    weights = np.zeros_like(trained["weights"])
    weights[:, 0] = 1.0  # joint 1 up, everywhere
    doctored = tmp_path / "up.policy.npz"
    np.savez_compressed(doctored, header=trained["header"], weights=weights)
    capsys.readouterr()
    assert main(["evaluate", str(doctored), "--starts", "6", "--seed", "3", "--json"]) == 0
    judged = json.loads(capsys.readouterr().out)
    assert set(judged) >= {"policy", "teacher"}
    policy = load_any_policy(doctored)
    task = policy.task
    seeds = np.random.default_rng(3).integers(0, 2**31 - 1, size=6)
    starts = np.array([task.random_start(np.random.default_rng(int(s))) for s in seeds])
    alone = greedy_success(task, policy.coder, policy.weights, starts, 5_000, hand_over=False)
    assert judged["policy"]["success"] == 1.0 and not alone.any()


def test_the_page_form_offers_it_and_the_api_takes_it():
    record = resolve_run(
        RunRequest(
            task="arm-reach",
            reach={"joints": 3, "actions": "all-follow"},
            experiments=1,
            episodes=2,
        )
    )
    form = record.form()
    assert form["actions"] == "all-follow"
    assert ReachRunCreate(**{**form, "name": None}).actions == "all-follow"
    assert resolve_run(RunRequest.from_form(form)).arm_reach() == record.arm_reach()
    page = (Path(studio.web.__file__).parent / "static" / "index.html").read_text()
    select = page[page.index('data-testid="train-actions"') :]
    assert '<option value="all-follow"' in select[: select.index("</select>")]
