"""Obstacles (issue 40): boxes in the robot's base frame that no move of a task may touch,
checked along the whole move, stored with a run and counted by ``studio evaluate``."""

from __future__ import annotations

import json

import numpy as np
import pytest

from studio.cli import build_parser, main
from studio.kinematics import Obstacle, ObstacleGuard, load_robot
from studio.learning import (
    ArmGrid,
    ConfigError,
    RunFolder,
    RunRequest,
    load_any_policy,
    policy_obstacles,
    resolve_run,
)

REACH = np.radians([0.0, 45.0, -90.0, 0.0, 0.0, 0.0])
"""The Puma560's default goal pose: the tool forward and up, clear of the table."""


def _swing(degrees: float) -> np.ndarray:
    """The goal pose turned by joint 1 to ``degrees``."""
    q = REACH.copy()
    q[0] = np.radians(degrees)
    return q


@pytest.fixture(scope="module")
def arm():
    return load_robot("puma560")


@pytest.fixture(scope="module")
def in_the_way(arm):
    """A 2 cm box where the tool passes when joint 1 swings from -60 to +60 degrees."""
    return Obstacle(tuple(arm.forward(REACH)[:3, 3]), (0.02, 0.02, 0.02))


def test_a_move_through_a_box_is_refused_though_both_ends_are_clear(arm, in_the_way):
    guard = ObstacleGuard(arm, [in_the_way])
    start, end = _swing(-60), _swing(60)
    assert not guard.contacts(start) and not guard.contacts(end)
    assert not arm.contacts(start) and not arm.contacts(end)  # nothing else in the way
    assert guard.move_collides(start, end)
    assert guard.move_collides(end, start)
    # a box 10 cm above the tool's arc lets the same swing through
    above = Obstacle((*in_the_way.centre[:2], in_the_way.centre[2] + 0.25), in_the_way.size)
    assert not ObstacleGuard(arm, [above]).move_collides(start, end)


def test_a_grid_move_through_a_box_leaves_the_arm_where_it_is(arm):
    grid = ArmGrid(bins=5)
    s = grid.state_of((1, 2, 2))
    t = grid.state_of((2, 2, 2))
    a = grid.mdp().action_between(s, t)
    q_s, q_t = grid.poses()[s], grid.poses()[t]
    middle = 0.5 * (q_s + q_t)
    box = Obstacle(tuple(arm.forward(middle)[:3, 3]), (0.01, 0.01, 0.01))
    guard = ObstacleGuard(arm, [box])
    assert not guard.contacts(q_s) and not guard.contacts(q_t)  # both ends clear of it
    blocked = ArmGrid(bins=5, obstacles=(box,)).mdp()
    assert grid.mdp().next_state[s, a] == t
    assert blocked.next_state[s, a] == s  # refused along the move: the arm stays
    assert blocked.reward[s, a] == -1.0
    assert blocked.intended[s, a] == t  # a demonstration may still try it
    assert blocked.action_between(s, t) == a


def test_a_goal_inside_a_box_is_refused_in_one_sentence(arm):
    goal = ArmGrid(bins=5)
    q_goal = goal.poses()[goal.goal_state]
    box = Obstacle(tuple(arm.forward(q_goal)[:3, 3]), (0.1, 0.1, 0.1))
    with pytest.raises(ConfigError) as err:
        ArmGrid(bins=5, obstacles=(box,))
    assert list(err.value.by_field) == ["obstacles"] and "at the goal" in str(err.value)


@pytest.mark.parametrize(
    ("value", "says"),
    [
        ("1,2,3", "not six numbers"),
        ("0.5,0,1,0.1,0.1", "not six numbers"),
        ("0.5,0,1,nan,0.1,0.1", "NaN"),
        ("0.5,0,1,0.1,0,0.1", "above zero"),
        ("0.5,0,1,0.1,-0.2,0.1", "above zero"),
        ("a,b,c,d,e,f", "not six numbers"),
    ],
)
def test_a_malformed_obstacle_is_one_sentence_and_exit_2(value, says, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["train", f"--obstacle={value}"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert says in err and err.count("\n") == 1


def test_obstacles_repeat_and_a_negative_centre_parses():
    parser, _ = build_parser(["train"])
    args = parser.parse_args(
        ["train", "--obstacle", "-0.3,0.2,0.9,0.1,0.1,0.1", "--obstacle", "0.5,-0.2,1,0.2,0.2,0.2"]
    )
    assert args.obstacle == [
        Obstacle((-0.3, 0.2, 0.9), (0.1, 0.1, 0.1)),
        Obstacle((0.5, -0.2, 1.0), (0.2, 0.2, 0.2)),
    ]
    args = parser.parse_args(["train", "--demos", "sample-reach-1", "--demos", "sample-reach-2"])
    assert [str(d) for d in args.demos] == ["sample-reach-1", "sample-reach-2"]


def test_a_run_stores_its_obstacles_and_its_policy_keeps_them(tmp_path, in_the_way):
    far = Obstacle((-0.6, 0.4, 0.3), (0.2, 0.1, 0.3))
    request = RunRequest(
        grid={"bins": 5}, obstacles=[far.to_dict()], experiments=1, episodes=3, origin="cli"
    )
    record = resolve_run(request)
    assert record.arm_grid().obstacles == (far,)
    folder = RunFolder.create(tmp_path, record)
    stored = json.loads((folder.path / "config.json").read_text())
    assert stored["task"]["obstacles"] == [far.to_dict()]
    assert RunFolder.load(folder.path).record.arm_grid().obstacles == (far,)
    folder.train()
    assert policy_obstacles(load_any_policy(folder.path / "policy.policy.npz")) == (far,)


def test_several_demonstrations_and_an_obstacle_from_the_command_line(tmp_path):
    out = tmp_path / "runs/taught"
    argv = ["train", "--demos", "sample-reach-1", "--demos", "sample-reach-3", "--bins", "11"]
    box = "-0.6,0.4,0.3,0.2,0.1,0.3"
    argv += ["--obstacle", box, "--episodes", "3", "--experiments", "1", "--no-progress"]
    assert main([*argv, "--out", str(out)]) == 0
    stored = json.loads((out / "config.json").read_text())
    assert len(stored["demonstrations"]) == 2
    assert stored["task"]["obstacles"] == [Obstacle.parse(box).to_dict()]


def test_evaluate_counts_a_rollout_through_a_box_as_a_collision(arm, in_the_way):
    from studio.commands.evaluate import _collides_with

    swing = np.array([_swing(d) for d in np.linspace(-60, 60, 7)])
    clear = swing[[0, -1]]  # its ends only: nothing between them is skipped by the check
    assert not _collides_with(())("puma560", swing)
    assert _collides_with((in_the_way,))("puma560", swing)
    assert _collides_with((in_the_way,))("puma560", clear)


def test_the_continuous_task_takes_a_box_and_a_rollout_into_it_is_a_collision(tmp_path, in_the_way):
    """The continuous task takes boxes as the grid does, from the request (the page, the API)
    and from the command line: its run and its policy keep them (none is dropped), and
    ``studio evaluate`` counts a rollout of that policy's task through the box as a collision."""
    from studio.commands.evaluate import _collides_with

    away = "120,45,-90"  # the goal turned away from the box in the tool's way at joint 1 = 0
    request = RunRequest(
        task="arm-reach",
        obstacles=[in_the_way.to_dict()],
        goal_deg=[float(v) for v in away.split(",")],
        experiments=1,
        episodes=1,
    )
    assert resolve_run(request).arm_reach().obstacles == (in_the_way,)
    box = ",".join(f"{v!r}" for v in (*in_the_way.centre, *in_the_way.size))
    out = tmp_path / "run"
    argv = ["train", "--task", "arm-reach", f"--obstacle={box}", f"--goal-deg={away}"]
    argv += ["--episodes", "1", "--experiments", "1", "--no-progress", f"--out={out}"]
    assert main(argv) == 0
    stored = json.loads((out / "config.json").read_text())
    assert stored["task"]["obstacles"] == [in_the_way.to_dict()]
    assert stored["task"]["tile_coding"]["groups"][-2:] == [[0, 1], [0, 2]]  # joint 1 with 2, 3
    kept = policy_obstacles(load_any_policy(out / "policy.policy.npz"))
    assert kept == (in_the_way,)
    swing = np.array([_swing(d) for d in (-60.0, 60.0)])  # both ends clear, the box between
    assert not _collides_with(())("puma560", swing)
    assert _collides_with(kept)("puma560", swing)


# ------------------------------------------------------------------ the continuous task

AWAY = tuple(float(v) for v in _swing(120.0))
"""A goal far from the box in the tool's way at joint 1 = 0."""


@pytest.fixture(scope="module")
def boxed_reach(in_the_way):
    from studio.learning import ArmReach

    return ArmReach(obstacles=(in_the_way,), goal=AWAY)


def test_the_continuous_task_refuses_a_move_through_a_box_along_it(boxed_reach):
    from studio.learning.tasks._obstacles import move_blocked

    start, end = (np.ascontiguousarray(_swing(d)) for d in (-60, 60))
    p = boxed_reach.params
    assert not move_blocked(p, start, start) and not move_blocked(p, end, end)
    assert move_blocked(p, start, end)  # neither end touches it; the swing between does


def test_the_continuous_check_holds_every_pose_and_move_coal_finds_touching(
    boxed_reach, arm, in_the_way
):
    """The compiled check (spheres holding the links) never lets through what coal's exact
    geometry finds touching the box: random poses and random single steps."""
    from studio.learning.tasks._obstacles import move_blocked
    from studio.learning.tasks._reach import reach_step

    guard = ObstacleGuard(arm, [in_the_way])
    rng = np.random.default_rng(4)
    p, touching, stayed = boxed_reach.params, 0, 0
    for _ in range(400):
        q = rng.uniform(boxed_reach.lower, boxed_reach.upper)
        if guard.contacts(boxed_reach.full_q(q)):
            touching += 1
            assert move_blocked(p, q, q)
        moved = q.copy()
        reward, _ = reach_step(p, moved, int(rng.integers(boxed_reach.n_actions)))
        if np.array_equal(moved, q):
            stayed += 1
            continue
        assert not guard.move_collides(boxed_reach.full_q(q), boxed_reach.full_q(moved))
    assert stayed > 0


def test_a_step_into_a_box_leaves_the_arm_where_it_is_and_costs_the_step(in_the_way):
    from studio.learning import ArmReach
    from studio.learning.tasks._obstacles import move_blocked
    from studio.learning.tasks._reach import reach_step

    task = ArmReach(obstacles=(in_the_way,), shaping=0.0, goal=AWAY)
    q = np.ascontiguousarray(_swing(-60))
    for _ in range(200):  # joint 1 up, one step at a time, until the box stops it
        before = q.copy()
        reward, done = reach_step(task.params, q, 0)
        if np.array_equal(q, before):
            break
    assert np.array_equal(q, before) and reward == -1.0 and not done
    assert move_blocked(task.params, before, before + np.eye(6)[0] * task.step)
    assert np.degrees(q[0]) < 0  # stopped before the tool's arc reaches the box


def test_a_continuous_task_keeps_its_obstacles_in_its_settings(boxed_reach, in_the_way):
    from studio.learning import ArmReach

    stored = json.loads(json.dumps(boxed_reach.to_dict()))
    assert stored["obstacles"] == [in_the_way.to_dict()]
    assert ArmReach.from_dict(stored).obstacles == (in_the_way,)
    assert "obstacles" not in ArmReach().to_dict()  # a task without boxes is stored as before


def test_an_export_is_checked_along_it_against_the_obstacles(arm, in_the_way):
    from studio.export import check_trajectory

    swing = np.array([_swing(d) for d in np.linspace(-60, 60, 5)])
    times = np.arange(len(swing), dtype=float)
    assert not [f for f in check_trajectory(arm, times, swing) if "obstacle" in f.where]
    found = [
        f
        for f in check_trajectory(arm, times, swing, obstacles=(in_the_way,))
        if "obstacle" in f.where
    ]
    assert len(found) == 1 and "touches obstacle 1" in found[0].sentence
    assert 0 < found[0].sample < len(swing)


def test_with_a_box_one_joint_per_action_also_tiles_joint_1_with_joints_2_and_3(in_the_way):
    """Where a box refuses a move depends on where the arm stands as a whole: a task with one
    joint per action and obstacles tiles joint 1 with joint 2 and with joint 3 too. The factored
    action sets keep the per-joint tiles their value is factored over; without a box nothing
    changes."""
    from studio.learning import ArmReach

    singles = tuple((j,) for j in range(6))
    for actions in ("single", "follow"):
        boxed = ArmReach(obstacles=(in_the_way,), goal=AWAY, actions=actions)
        assert boxed.features().groups == (*singles, (0, 1), (0, 2))
        assert ArmReach(goal=AWAY, actions=actions).features().groups == singles
    for actions in ("pairs", "all-follow"):
        boxed = ArmReach(obstacles=(in_the_way,), goal=AWAY, actions=actions)
        assert boxed.features().groups == singles


def _pressed_then_around(task) -> np.ndarray:
    """The greedy path of weights that prefer joint 1 up, then joint 2 up, wherever the arm is,
    from joint 1 at -60 degrees toward the box: pressing refused moves again it stays in front of
    the box; stepping around them it passes the box (returned)."""
    from studio.learning.linear._greedy import greedy_rollout

    coder = task.features().bind(*task.observation_bounds)
    weights = np.zeros((coder.size, task.n_actions))
    weights[:, 0], weights[:, 2] = 2.0, 1.0  # joint 1 up, else joint 2 up
    start = np.ascontiguousarray(_swing(-60))
    pressed, _ = greedy_rollout(task, coder, weights, start, 300, step_around=False)
    around, _ = greedy_rollout(task, coder, weights, start, 300)
    assert np.degrees(pressed[:, 0]).max() < 0 and np.array_equal(pressed[-1], pressed[-2])
    assert np.degrees(around[:, 0]).max() > 10
    return around


def test_the_greedy_policy_steps_around_a_move_a_box_refuses(in_the_way):
    """Weights that prefer joint 1 up, then joint 2 up, wherever the arm is: pressing the move
    the box refuses again, the greedy policy stays in front of the box to the cap; stepping
    around refused moves (the policy of a task with obstacles), it climbs past the box, never
    staying put nor stepping back to where it was."""
    from studio.learning import ArmReach
    from studio.learning.linear._greedy import steps_around

    task = ArmReach(obstacles=(in_the_way,), shaping=0.0, goal=AWAY)
    assert steps_around(task) and not steps_around(ArmReach(goal=AWAY))
    around = _pressed_then_around(task)
    assert not any(np.array_equal(a, b) for a, b in zip(around[1:], around[:-1], strict=True))
    assert not any(np.array_equal(a, b) for a, b in zip(around[2:], around[:-2], strict=True))


def test_a_follow_move_the_box_refuses_hands_the_motion_back(in_the_way):
    """``"all-follow"`` hands over to the follow action where its greedy moves loop. Following a
    demonstration that swings through the box, that hand-over stalls in front of it for good;
    stepping around refused moves, the follow move the box refuses hands back to the greedy moves,
    which climb past the box."""
    from studio.learning import ArmReach
    from studio.learning.linear._greedy import hand_over_action

    swing = np.array([_swing(d) for d in np.arange(-60.0, 121.0, 2.0)])  # through the box
    task = ArmReach(
        obstacles=(in_the_way,), shaping=0.0, goal=AWAY, actions="all-follow", paths=(swing,)
    )
    assert hand_over_action(task) == task.n_actions - 1
    _pressed_then_around(task)
