"""One learner interface: each learner registered by kind, one dispatch, the same answers as the
functions of each kind it stands for."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from studio.capture import load_demonstration
from studio.learning import (
    ArmGrid,
    ArmReach,
    Learner,
    LearningError,
    LiveProgress,
    RunRequest,
    Start,
    TilePolicyFile,
    fit_dmp_policy,
    greedy_path,
    learner,
    learner_of,
    load_any_policy,
    register_learner,
    resolve_run,
    rollout,
    rollout_dmp_policy,
    rollout_tile_policy,
    save_dmp_policy,
)
from studio.learning._interface import Learner as LearnerProtocol
from studio.learning._registry import learner_for_task

STUDIO = Path(__file__).resolve().parents[2] / "studio"
SAMPLE = STUDIO / "samples" / "sample-reach-1.demo.json"
POLICY_CLASSES = {"PolicyFile", "TilePolicyFile", "DmpPolicyFile"}


def _trained(tmp_path: Path, request: RunRequest) -> object:
    """A tiny run of ``request`` trained and saved through its learner, loaded back."""
    record = resolve_run(request)
    task_learner = learner_for_task(record.task)
    live = LiveProgress(record.experiments, record.episodes)
    result = task_learner.train(record, live, workers=1)
    path = tmp_path / f"{task_learner.kind}.policy.npz"
    task_learner.save(path, record, result, notes="tiny")
    return load_any_policy(path)


@pytest.fixture(scope="module")
def policies(tmp_path_factory) -> dict[str, object]:
    """One policy of each registered kind."""
    folder = tmp_path_factory.mktemp("learners")
    demo = load_demonstration(SAMPLE)
    dmp = folder / "dmp.policy.npz"
    save_dmp_policy(dmp, fit_dmp_policy(demo.times, demo.q_robot, learned_joints=3))
    return {
        "arm-grid": _trained(
            folder,
            RunRequest(grid={"bins": 5}, config={"planning": "zero"}, experiments=2, episodes=30),
        ),
        "arm-reach": _trained(
            folder,
            RunRequest(
                task="arm-reach",
                reach={"joints": 3, "actions": "single"},
                config={"planning": "zero"},
                experiments=1,
                episodes=3,
            ),
        ),
        "dmp": load_any_policy(dmp),
    }


def test_each_kind_is_registered_and_dispatched_by_its_policy(policies):
    assert set(policies) == {"arm-grid", "arm-reach", "dmp"}
    for kind, policy in policies.items():
        assert learner_of(policy) is learner(kind)
        assert learner(kind).kind == kind
        assert isinstance(learner(kind), LearnerProtocol)
    assert learner_for_task(ArmGrid()) is learner("arm-grid")
    assert learner_for_task(ArmReach()) is learner("arm-reach")
    with pytest.raises(LearningError, match="no learner of kind 'bc'"):
        learner("bc")
    with pytest.raises(LearningError, match="is registered already"):
        register_learner(learner("dmp"))
    assert Learner is LearnerProtocol


def test_a_grid_rollout_is_the_greedy_path_rollout_gives(policies):
    policy = policies["arm-grid"]
    state = int(policy.grid.mdp().start_states[7])
    out = learner_of(policy).roll_out(policy, Start(state=state), rate_hz=20.0)
    times, q = rollout(policy, state, 20.0)
    np.testing.assert_array_equal(out.times, times)
    np.testing.assert_array_equal(out.q, q)
    assert list(out.states) == greedy_path(policy, state)
    assert out.steps == len(out.states) - 1
    assert out.reached == (out.states[-1] == policy.grid.goal_state)
    np.testing.assert_allclose(out.goal[:3], policy.grid.angles_of(policy.grid.goal_state))


def test_a_random_start_repeats_with_its_seed_and_a_pose_holds_the_other_joints(policies):
    for kind in ("arm-grid", "arm-reach"):
        policy = policies[kind]
        one, two = (learner(kind).roll_out(policy, Start(seed=5), 50.0) for _ in range(2))
        np.testing.assert_array_equal(one.q, two.q)
        assert one.seed == 5
    policy = policies["arm-grid"]
    pose = np.radians([30.0, -20.0, 10.0, 15.0, 25.0, 35.0])
    out = learner_of(policy).roll_out(policy, learner_of(policy).pose_start(policy, pose), 50.0)
    assert out.states[0] == policy.grid.state_of_angles(pose[:3])
    np.testing.assert_allclose(out.q[:, 3:], np.tile(pose[3:], (len(out.q), 1)))


def test_tile_and_primitive_rollouts_are_their_kinds_own(policies):
    tile: TilePolicyFile = policies["arm-reach"]
    start = np.radians([10.0, 20.0, -30.0])
    out = learner_of(tile).roll_out(tile, Start(q=start), 50.0, max_steps=40)
    times, q, reached = rollout_tile_policy(tile, start, 50.0, 40)
    np.testing.assert_array_equal(out.q, q)
    assert out.reached == reached and out.states == () and 0 <= out.steps <= 40
    dmp = policies["dmp"]
    out = learner_of(dmp).roll_out(dmp, Start(), 50.0)
    times, q, reached = rollout_dmp_policy(dmp, None, 50.0)
    np.testing.assert_array_equal(out.q, q)
    assert out.reached == reached and out.seed is None
    with pytest.raises(LearningError, match="grid state is no start"):
        learner_of(dmp).roll_out(dmp, Start(state=3), 50.0)


def test_evaluate_counts_the_starts_that_reach_the_goal(policies):
    policy = policies["arm-grid"]
    grid = policy.grid
    starts = np.array([grid.angles_of(int(s)) for s in grid.mdp().start_states[:40]])
    evaluation = learner_of(policy).evaluate(policy, starts)
    paths = [greedy_path(policy, int(s)) for s in grid.mdp().start_states[:40]]
    reached = [p[-1] == grid.goal_state for p in paths]
    assert evaluation.starts == 40
    assert evaluation.success == pytest.approx(np.mean(reached))
    if any(reached):
        steps = [len(p) - 1 for p, r in zip(paths, reached, strict=True) if r]
        assert evaluation.mean_steps == pytest.approx(np.mean(steps))
    dmp = policies["dmp"]
    at_start = learner_of(dmp).evaluate(dmp, dmp.demo_q[:1, :3])
    assert at_start.starts == 1 and at_start.success == 1.0


def test_every_learner_offers_every_method_of_the_interface(policies):
    methods = {
        name
        for name, value in vars(LearnerProtocol).items()
        if callable(value) and not name.startswith("_")
    }
    assert {"train", "save", "load", "roll_out", "evaluate", "likeness"} <= methods
    for kind in policies:
        missing = [m for m in methods if not callable(getattr(learner(kind), m, None))]
        assert missing == [], f"the {kind} learner lacks {missing}"


def test_no_code_outside_learning_asks_which_class_a_policy_is():
    """One dispatch: isinstance on the policy classes stays inside studio/learning."""
    found = []
    for path in STUDIO.rglob("*.py"):
        if path.is_relative_to(STUDIO / "learning"):
            continue
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "isinstance":
                named = {n.id for n in ast.walk(node.args[1]) if isinstance(n, ast.Name)} | {
                    n.attr for n in ast.walk(node.args[1]) if isinstance(n, ast.Attribute)
                }
                if named & POLICY_CLASSES:
                    found.append(f"{path.relative_to(STUDIO.parent)}:{node.lineno}")
    assert found == []


def test_a_run_learns_through_its_tasks_learner(tmp_path):
    record = resolve_run(RunRequest(grid={"bins": 5}, experiments=1, episodes=4))
    assert record.kind == "arm-grid" and learner_for_task(record.task).kind == record.kind
    live = LiveProgress(1, 4)
    result = learner(record.kind).train(record, live, workers=1)
    assert result.steps.shape == (1, 4) and (result.steps > 0).all()
