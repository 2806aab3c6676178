"""The continuous arm task: its kinematics twin, its dynamics, demonstrations, and a six-joint run."""

from __future__ import annotations

import math
import time

import gymnasium
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.cli import main
from studio.kinematics import Puma560, load_robot
from studio.learning import (
    TILE_ROLLOUT_SECONDS_PER_STEP,
    ArmReach,
    DemonstrationMotion,
    DynaQConfig,
    LearningError,
    LiveProgress,
    RunFolder,
    RunRecord,
    TilePolicyFile,
    load_any_policy,
    run_experiments,
)
from studio.learning.linear._linear import greedy_success
from studio.learning.linear._policy import save_tile_policy
from studio.learning.tasks._gym import ARM_REACH_ID
from studio.learning.tasks._reach import reach_step

ROBOT = Puma560()


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0.0, 1.0), min_size=6, max_size=6), st.integers(3, 6))
def test_tool_pose_twin_equals_puma560_forward(u, joints):
    arm = load_robot("puma560", geometry=False)  # the task's goals lie within the usable limits
    q = arm.lower + np.array(u) * (arm.upper - arm.lower)
    task = ArmReach(joints=joints, goal=tuple(q))  # joints beyond `joints` held at the goal's
    assert np.allclose(task.tool_pose(q[:joints]), ROBOT.forward(q), atol=1e-12)


def test_success_is_judged_on_the_tool_pose():
    task = ArmReach(joints=6, position_tolerance=0.02, angle_tolerance_deg=10.0)
    goal = np.array(task.goal)
    assert task.success(goal)
    # joint 6 turns the tool about its own axis: the position stays, the angle grows by the turn
    for turn_deg, expected in ((9.0, True), (11.0, False)):
        q = goal.copy()
        q[5] += math.radians(turn_deg)
        assert task.success(q) is expected
    # joint 1 swings the tool sideways: about 2 cm per 2 degrees at this pose
    reach = np.hypot(*ROBOT.forward(goal)[:2, 3])
    q = goal.copy()
    q[0] += 0.025 / reach
    assert not task.success(q)


def test_one_joint_moves_per_action_by_one_step_within_limits():
    task = ArmReach(joints=6, step_deg=2.0, actions="single")
    assert task.n_actions == 12
    rng = np.random.default_rng(0)
    for _ in range(200):
        q = task.random_start(rng)
        a = int(rng.integers(task.n_actions))
        moved = q.copy()
        reward, done = reach_step(task.params, moved, a)
        j, sign = a // 2, 1.0 if a % 2 == 0 else -1.0
        others = np.delete(np.arange(6), j)
        assert np.array_equal(moved[others], q[others])
        inside = task.lower[j] <= q[j] + sign * task.step <= task.upper[j]
        assert moved[j] == (q[j] + sign * task.step if inside else q[j])
        assert done == task.success(moved)
    # at the upper limit, moving up leaves the joint where it is
    q = task.upper - 1e-6
    before = q.copy()
    reach_step(task.params, q, 0)
    assert q[0] == before[0]


def test_random_starts_cover_the_limits_and_never_start_at_the_goal():
    task = ArmReach(joints=6)
    starts = np.array([task.random_start(np.random.default_rng(s)) for s in range(300)])
    assert np.all(starts >= task.lower) and np.all(starts <= task.upper)
    spread = (starts.max(axis=0) - starts.min(axis=0)) / (task.upper - task.lower)
    assert np.all(spread > 0.8)
    assert not any(task.success(q) for q in starts)


def test_demonstration_walk_reaches_the_goal_and_bad_demonstrations_are_refused():
    task = ArmReach(joints=6)
    start = np.radians([60.0, -40.0, 70.0, 100.0, -50.0, 120.0])
    path = np.linspace(start, task.goal, 40)
    q0, actions = task.demonstration_actions(path)
    q = q0.copy()
    for a in actions:
        _, done = reach_step(task.params, q, int(a))
    assert done and task.success(q)
    assert len(actions) <= np.abs(start - task.goal).sum() / task.step + 6
    outside = path.copy()
    outside[10, 1] = math.radians(130.0)  # joint 2's limit is 110 degrees
    with pytest.raises(LearningError, match="leaves joint 2's limits at sample 10"):
        task.demonstration_actions(outside, 0)
    with pytest.raises(LearningError, match="never brings the tool"):
        task.demonstration_actions(path[:20])
    with pytest.raises(LearningError, match="joints is 2"):
        ArmReach(joints=2)
    with pytest.raises(LearningError, match="step_deg is 5"):
        ArmReach(step_deg=5)
    with pytest.raises(LearningError, match="outside its limits"):
        ArmReach(joints=3, goal=(0.0, 3.0, 0.0))


def test_a_six_joint_run_reaches_the_goal_and_exports_a_policy_that_rolls_out(tmp_path, capsys):
    task = ArmReach(joints=6)
    rng = np.random.default_rng(1)
    demos = [np.linspace(task.random_start(rng), task.goal, 60) for _ in range(3)]
    config = DynaQConfig(planning="zero", max_steps_per_episode=2000)
    result = run_experiments(
        lambda: gymnasium.make(ARM_REACH_ID, joints=6), config, 1, 300, 0,
        demonstrations=demos, features=task.features(),
    )  # fmt: skip
    assert result.compiled and result.task == task.with_paths(demos)  # it follows them
    assert (result.steps[0, :3] < 2000).all()  # the demonstrations reach the goal
    starts = np.array([d[0] for d in demos] + [task.random_start(rng) for _ in range(40)])
    reached = greedy_success(result.task, result.coder, result.weights[0], starts, 2000)
    assert reached.any()
    start = starts[int(np.argmax(reached))]
    policy_path = tmp_path / "reach.policy.npz"
    save_tile_policy(policy_path, result, 0)
    policy = load_any_policy(policy_path)
    assert isinstance(policy, TilePolicyFile)
    assert np.array_equal(policy.weights, result.weights[0]) and policy.task == result.task
    degrees = ",".join(f"{x:.9f}" for x in np.degrees(start))
    out = tmp_path / "reach.rollout.csv"
    assert main(["export", str(policy_path), f"--start-deg={degrees}", "--out", str(out)]) == 0
    assert "reaches the goal" in capsys.readouterr().out
    rows = np.loadtxt(out, delimiter=",", skiprows=1)
    assert rows.shape[1] == 7 and np.all(np.diff(rows[:, 0]) > 0)  # times strictly rise
    oMend, oMgoal = ROBOT.forward(rows[-1, 1:]), ROBOT.forward(np.array(task.goal))
    assert np.linalg.norm(oMend[:3, 3] - oMgoal[:3, 3]) <= task.position_tolerance
    cos = (np.trace(oMgoal[:3, :3].T @ oMend[:3, :3]) - 1) / 2
    assert math.degrees(math.acos(min(1.0, cos))) <= task.angle_tolerance_deg
    # smooth: no sample moves any joint by more than one step
    assert np.abs(np.diff(rows[:, 1:], axis=0)).max() <= task.step + 1e-12


def test_a_continuous_run_folder_trains_saves_and_reads_back(tmp_path):
    task = ArmReach(joints=4)
    demo = np.linspace(task.random_start(np.random.default_rng(0)), task.goal[:4], 30)
    config = DynaQConfig(planning="full", planning_steps=2, max_steps_per_episode=300)
    record = RunRecord.for_arm_reach(task, task.features(), config, 2, 6, 0, [demo], name="reach")
    run = RunFolder.create(tmp_path, record)
    result = run.train()
    assert run.status == "done" and run.has_policy and result.steps[:, 0].max() < 300
    again = RunFolder.load(run.path)
    assert again.record.kind == "arm-reach" and again.record.arm_reach() == task
    assert np.allclose(again.record.demonstrations[0], demo)  # the joint path, not grid states
    assert np.array_equal(again.steps(), result.steps)
    policy = load_any_policy(run.policy_path)
    assert isinstance(policy, TilePolicyFile) and policy.task == task.with_paths([demo])
    with pytest.raises(LearningError, match="leaves joint 1's limits at sample 0"):
        RunRecord.for_arm_reach(task, task.features(), config, 2, 6, 0, [demo + 3.0])
    # no recorded motion: the default pace; one the task cannot walk costs the pace, not the run
    assert policy.seconds_per_step == TILE_ROLLOUT_SECONDS_PER_STEP
    astray = DemonstrationMotion("astray", np.linspace(0.0, 1.0, 10), demo[:10].copy())
    record = RunRecord.for_arm_reach(
        task, task.features(), config, 1, 2, 0, [demo], demonstration_motions=[astray]
    )
    run = RunFolder.create(tmp_path, record, name="astray")
    run.train(workers=1)
    assert run.status == "done"
    assert load_any_policy(run.policy_path).seconds_per_step == TILE_ROLLOUT_SECONDS_PER_STEP


def test_beyond_the_paper_measures_memory_and_success(tmp_path):
    from studio.learning.paper._beyond import beyond_the_paper, memory_row

    row = memory_row(ArmReach(joints=6))
    assert row["paper_entries"] == 11**6 * 3**6  # the paper's grid at six joints
    assert row["fine_entries"] > 1e14 > 1e8 > row["tile_entries"]  # tiles: a few MB, not petabytes
    text, files, rows = beyond_the_paper(tmp_path, 0, joints=(3,), episodes=(20,), experiments=1)
    assert [f.name for f in files] == ["beyond.png", "beyond.svg"]
    assert "| 3 | 35,937 entries" in text and "greedy success" in text
    (budget,) = rows[0]["budgets"]
    assert budget["episodes"] == 20 and 0.0 <= budget["success"][0] <= 1.0


def test_six_joint_greedy_policy_reaches_the_goal_from_random_starts_without_oscillating():
    # the defaults (shaping 5, per-joint tilings) make each action's value a per-joint sum the
    # features fit; with shaping 1 (toward-goal steps paying 0) the greedy policy stepped a
    # near-goal joint back and forth: 16% success after 4,000 episodes instead of 97-100%
    task = ArmReach(joints=6)
    config = DynaQConfig(planning="zero", max_steps_per_episode=3000)
    result = run_experiments(
        lambda: gymnasium.make(ARM_REACH_ID, joints=6), config, 1, 3000, 0, features=task.features()
    )
    rng = np.random.default_rng(5)
    starts = np.array([task.random_start(rng) for _ in range(100)])
    assert greedy_success(task, result.coder, result.weights[0], starts, 3000).mean() >= 0.9


def test_first_own_success_counts_episodes_after_the_demonstrations():
    from studio.learning.paper._beyond import _first_own_success

    steps = np.array([[40, 50, 3000, 700, 9], [40, 50, 3000, 3000, 3000]])
    assert _first_own_success(steps, 2, 3000) == [[2, 700], None]
    assert _first_own_success(steps, 0, 3000) == [[1, 40], [1, 40]]


def test_a_continuous_run_checkpoints_its_policy_while_it_learns(tmp_path):
    """The weights the kernel is filling are saved with each checkpoint, so a crash (the run
    never reaching its end) still leaves a loadable policy."""
    task = ArmReach(joints=3)
    config = DynaQConfig(planning="full", planning_steps=2, max_steps_per_episode=200)
    record = RunRecord.for_arm_reach(task, task.features(), config, 1, 100_000, 0, [])
    run = RunFolder.create(tmp_path, record)
    seen: list = []
    give_up = time.monotonic() + 120  # a bound, not a wait: the event is the policy appearing

    def on_checkpoint(live: LiveProgress) -> None:
        if not seen and run.has_policy:  # the first checkpoint's policy, mid-run
            seen.append((live.completed, load_any_policy(run.policy_path)))
            live.stop()
        elif time.monotonic() > give_up:
            live.stop()

    run.train(on_checkpoint=on_checkpoint)
    assert seen, "no policy was checkpointed while the run learnt"
    done, policy = seen[0]
    assert 0 < done < 100_000
    assert isinstance(policy, TilePolicyFile) and policy.task == task
    assert np.abs(policy.weights).max() > 0  # what the kernel had learnt, not a blank table
