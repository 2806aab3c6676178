"""The baselines beside Dyna-Q (issue 40): the teacher (the demonstrations followed, no
learning) and behaviour cloning are learners like the others, a run picks one by name, and the
switches that make the table's rows (the demonstrations' potential, the task's shaping) are
plain settings."""

from __future__ import annotations

import json

import numpy as np
import pytest

from studio.cli import main
from studio.learning import (
    ArmReach,
    ConfigError,
    Evaluation,
    LearningError,
    RunRecord,
    RunRequest,
    Start,
    evaluate_policy,
    learner,
    learner_of,
    load_any_policy,
    policy_summary,
    resolve_run,
)
from studio.learning._registry import run_learner
from studio.learning.baselines import CloningPolicyFile, TeacherPolicyFile, fit_cloning
from studio.learning.baselines._cloning import cloning_rollout
from studio.learning.linear._teacher import teacher_walk
from studio.learning.tasks._demo_shaping import demo_potential

COMMON = ["--task", "arm-reach", "--episodes", "6", "--experiments", "2", "--no-progress"]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("baselines")
    for kind in ("teacher", "cloning"):
        argv = ["train", *COMMON, "--demos", "sample-reach-1", "--learner", kind]
        assert main([*argv, "--out", str(root / kind)]) == 0
    return root


def test_a_run_trained_by_the_teacher_or_by_cloning_is_a_policy_of_its_kind(runs):
    teacher = load_any_policy(runs / "teacher" / "policy.policy.npz")
    cloning = load_any_policy(runs / "cloning" / "policy.policy.npz")
    assert isinstance(teacher, TeacherPolicyFile) and isinstance(cloning, CloningPolicyFile)
    assert learner_of(teacher) is learner("teacher")
    assert learner_of(cloning) is learner("cloning")
    for kind in ("teacher", "cloning"):
        config = json.loads((runs / kind / "config.json").read_text())
        assert config["learner"] == kind
        record = RunRecord.from_dict(config)
        assert record.learner == kind and record.trained_by() is learner(kind)
        # listed like any policy: what it acts on and which learner made it
        facts = policy_summary(load_any_policy(runs / kind / "policy.policy.npz"))
        assert facts["task"]["kind"] == "arm-reach" and facts["task"]["learner"] == kind
        assert facts["planning"] == "none" and facts["episodes"] == 6


def test_the_teacher_follows_the_demonstrations_and_cloning_rejoins_them(runs):
    teacher = load_any_policy(runs / "teacher" / "policy.policy.npz")
    cloning = load_any_policy(runs / "cloning" / "policy.policy.npz")
    task = teacher.task
    starts = np.random.default_rng(4).uniform(task.lower, task.upper, (12, task.joints))
    judged = learner_of(teacher).evaluate(teacher, starts)
    walks = [teacher_walk(task, s, 5_000) for s in starts]
    assert judged.success == 1.0  # following reaches the goal from anywhere
    assert judged.mean_steps == pytest.approx(np.mean([len(p) - 1 for p, _ in walks]))
    # cloning from the demonstration's own start walks it to the goal; from elsewhere it
    # heads for the nearest sample's demonstrated next state, so it rejoins the demonstration
    # and walks it to its end (copying the sample's move instead, parallel to it, fell short
    # from every one of these starts)
    first = np.asarray(load_any_policy(runs / "cloning" / "policy.policy.npz").cloning.states[0])
    path, reached = cloning_rollout(cloning.task, cloning.cloning, first, 5_000)
    assert reached and len(path) > 10
    assert learner_of(cloning).evaluate(cloning, starts).success == 1.0
    out = learner_of(cloning).roll_out(cloning, Start(seed=3), 50.0)
    assert out.q.shape[1] == 6 and out.times[0] == 0.0


def test_the_curve_of_a_baseline_counts_the_cap_where_it_fails(runs):
    steps = np.loadtxt(runs / "cloning" / "steps.csv", delimiter=",", skiprows=1)
    assert steps.size and np.all(steps[..., 1:] >= 1)


def test_a_baseline_is_refused_where_it_cannot_learn():
    with pytest.raises(ConfigError, match="learner is 'teacher'"):
        resolve_run(RunRequest(learner="teacher", experiments=1, episodes=2))  # the grid
    with pytest.raises(ConfigError, match="learns from demonstrations"):
        resolve_run(RunRequest(task="arm-reach", learner="cloning", experiments=1, episodes=2))
    with pytest.raises(LearningError, match="give one of dyna-q, teacher, cloning"):
        run_learner("nope", ArmReach())
    assert run_learner("dyna-q", ArmReach()) is learner("arm-reach")


def test_studio_train_refuses_a_baseline_of_the_grid_in_one_sentence(capsys, tmp_path):
    argv = ["train", "--learner", "teacher", "--episodes", "2", "--out", str(tmp_path / "r")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "learner is 'teacher'" in err and err.count("\n") == 1


def test_evaluate_gives_the_learners_one_evaluation(runs):
    out = evaluate_policy(
        load_any_policy(runs / "teacher" / "policy.policy.npz"), 5, 0, lambda r, q: False
    )
    assert isinstance(out.policy, Evaluation) and out.policy.starts == 5
    assert set(out.policy.as_json()) == {"success", "collisions", "mean_steps", "mean_seconds"}


def test_cloning_learns_each_demonstrated_move():
    task = ArmReach(joints=3)
    path = np.linspace([0.3, 0.2, -0.5], task.goal[:3], 40)
    cloning = fit_cloning(task, [path])
    assert cloning.states.shape == cloning.moves.shape
    np.testing.assert_allclose(cloning.states[0] + cloning.moves[0], cloning.states[1])
    assert not cloning.moves[-1].any()  # the demonstration's end: no move
    with pytest.raises(LearningError, match="at least one"):
        fit_cloning(task, [])


def test_cloning_heads_for_the_demonstrated_next_state_so_it_rejoins_the_demonstration():
    """Off the demonstration the cloned action closes the gap to it: copying the nearest
    sample's move instead went parallel to the demonstration and never reached the goal."""
    task = ArmReach(joints=3)
    path = np.linspace([0.3, 0.2, -0.5], task.goal[:3], 40)
    cloning = fit_cloning(task, [path])
    start = cloning.states[0] + np.array([0.0, 0.15, 0.0])  # off the path, beside its start
    walk, reached = cloning_rollout(task, cloning, start, 5_000)
    first = walk[1] - walk[0]
    nearest = int(np.argmin(np.linalg.norm(cloning.states - start, axis=1)))
    toward = cloning.states[nearest + 1] - start  # that sample's demonstrated next state
    assert np.abs(first).max() == pytest.approx(task.step)  # one step, every joint at once
    np.testing.assert_allclose(first, toward * task.step / np.abs(toward).max())
    assert reached
    copied = start + np.cumsum(np.repeat(cloning.moves[nearest : nearest + 1], 5, axis=0), axis=0)
    assert np.linalg.norm(copied[-1] - cloning.states[nearest + 5]) > 0.1  # the move stayed off


def test_the_demonstrations_potential_is_a_setting_of_its_own():
    """Without it the weight was what DEMO_SHAPING left beside the task's shaping, with no way
    to switch it off under the paper's reward, nor on under the default shaping."""
    paths = [np.linspace([0.3, 0.2, -0.5], ArmReach(joints=3).goal[:3], 40)]

    def weight(**settings) -> float:
        task = ArmReach(joints=3, actions="single", **settings)
        start, actions = task.demonstration_actions(paths[0])
        pot = demo_potential(task, [start], [actions], 3)
        return float(pot.weight) if pot.points.shape[0] else 0.0

    assert weight(shaping=0.0) == 5.0 and weight() == 0.0  # the rule as it was
    assert weight(shaping=0.0, demo_potential=0.0) == 0.0
    assert weight(demo_potential=2.5) == 2.5
    task = ArmReach(shaping=0.0, demo_potential=3.0)
    assert ArmReach.from_dict(task.to_dict()) == task
    assert "demo_potential" not in ArmReach().to_dict()  # files of the default stay as they were
    with pytest.raises(ConfigError, match="demo_potential is -1"):
        ArmReach(demo_potential=-1.0)


def test_studio_train_sets_the_rewards_the_table_compares(tmp_path):
    argv = ["train", *COMMON, "--shaping", "0", "--demo-potential", "0", "--actions", "single"]
    assert main([*argv, "--demos", "sample-reach-1", "--out", str(tmp_path / "r")]) == 0
    record = RunRecord.from_dict(json.loads((tmp_path / "r" / "config.json").read_text()))
    task = record.arm_reach()
    assert (task.shaping, task.demo_potential, task.actions) == (0.0, 0.0, "single")
    assert record.learner == ""  # Dyna-Q, the task's own
