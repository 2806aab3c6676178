"""The factored action value: multi-joint moves share what each joint's move has learned."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

import studio.learning.linear._linear as linear
from studio.learning import ArmReach, DynaQConfig, TileCoding, run_experiments
from studio.learning.linear._factored import (
    action_components,
    expand,
    factored_values,
    reward_split,
    row_joints,
    slot_joints,
    split_reward,
)
from studio.learning.linear._linear import greedy_rollout, greedy_success
from studio.learning.tasks._demo_shaping import demo_potential, no_potential, potential
from studio.learning.tasks._follow import with_cost_group
from studio.learning.tasks._gym import ARM_REACH_ID
from studio.learning.tasks._reach import reach_potential, reach_step


def brute_force(task, coder, w, obs):
    """Q(s, a) = sum over joints j of joint j's term: its own tiles' weights in the column of
    what action a does to joint j."""
    feats = coder.active(obs)
    per_joint = np.repeat(np.arange(task.joints), coder.coding.tilings)
    q = np.zeros(task.n_actions)
    for a, move in enumerate(task.directions):
        for i, f in enumerate(feats):
            j = per_joint[i]
            q[a] += w[f, 3 * j + int(move[j]) + 1]
    return q


@pytest.mark.parametrize("actions", ["pairs", "all"])
def test_the_factored_value_is_the_sum_of_per_joint_terms(actions):
    task = ArmReach(joints=4, actions=actions)
    coder = task.features().bind(task.lower, task.upper)
    rng = np.random.default_rng(0)
    w = rng.normal(size=(coder.size, 3 * task.joints))
    comp = action_components(task.directions)
    slots = slot_joints(coder, task.joints)
    for _ in range(5):
        obs = task.random_start(rng)
        expected = brute_force(task, coder, w, obs)
        out = np.empty(task.n_actions)
        factored_values(w, comp, slots, np.empty(3 * task.joints), coder.active(obs), out)
        assert np.allclose(out, expected)
        # the expanded table every reader of policy files uses gives the same values
        table = expand(w, comp, row_joints(coder))
        assert np.allclose(table[coder.active(obs)].sum(axis=0), expected)


def test_features_over_several_joints_or_hashed_are_not_factored():
    task = ArmReach(joints=3)
    bind = lambda coding: coding.bind(task.lower, task.upper)  # noqa: E731
    assert slot_joints(bind(TileCoding(2, 4, groups=((0, 1), (2,)))), 3) is None
    assert slot_joints(bind(TileCoding(2, 4, size=16, groups=((0,), (1,), (2,)))), 3) is None
    coder = bind(TileCoding(2, 4, groups=((1,), (0,), (2,))))
    assert slot_joints(coder, 3).tolist() == [1, 1, 0, 0, 2, 2]
    # each row belongs to the joint whose tiles it is
    obs = task.random_start(np.random.default_rng(5))
    assert row_joints(coder)[coder.active(obs)].tolist() == [1, 1, 0, 0, 2, 2]


def test_the_reward_split_sums_to_the_reward_and_gives_each_joint_its_own_progress():
    task = ArmReach(joints=3, actions="pairs", shaping=5.0)
    rng = np.random.default_rng(1)
    empty = no_potential(3)
    for _ in range(20):
        q = task.random_start(rng)
        nxt = q.copy()
        a = int(rng.integers(task.n_actions))
        reward, done = reach_step(task.params, nxt, a)
        out = np.empty(3)
        split_reward(reward_split(task, goal_share=1.0), empty, q, nxt, reward, done, out)
        assert out.sum() == pytest.approx(reward)
        goal = np.array(task.goal[:3])
        progress = (np.abs(q - goal) - np.abs(nxt - goal)) / task.step
        rest = (reward - 5.0 * progress.sum()) / 3
        assert np.allclose(out, 5.0 * progress + rest)
    assert reach_potential(task.params, goal) == 0.0


def test_the_split_covers_the_demonstrations_potential_too():
    task = ArmReach(joints=3, actions="pairs", shaping=0.0)
    goal = np.array(task.goal[:3])
    start, actions = task.demonstration_actions(
        np.linspace(goal + np.radians([20.0, -20.0, 10.0]), goal, 30)
    )
    pot = demo_potential(task, [start], [actions], 3)
    rng = np.random.default_rng(2)
    for _ in range(20):
        q = task.random_start(rng)
        nxt = q.copy()
        reward, _ = reach_step(task.params, nxt, int(rng.integers(task.n_actions)))
        shaped = reward + potential(pot, nxt) - potential(pot, q)
        out = np.empty(3)
        split_reward(reward_split(task, goal_share=1.0), pot, q, nxt, shaped, False, out)
        assert out.sum() == pytest.approx(shaped)


def test_the_goals_reward_beyond_a_step_is_left_out_of_the_terms_by_default():
    """Whether the tool is at its goal is not a sum over joints (at the default goal joints 4
    and 6 turn about one axis, so many joint-6 angles reach it): shared among the terms, the
    goal's +100 taught joint 6 to stop far from its goal angle (package README)."""
    task = ArmReach(joints=3, actions="pairs", shaping=5.0)
    goal = np.array(task.goal[:3])
    before = goal + np.array([task.step, 0.0, 0.0])
    after = goal.copy()
    out = np.empty(3)
    reward = 100.0 + 5.0
    split_reward(reward_split(task), no_potential(3), before, after, reward, True, out)
    assert out.sum() == pytest.approx(reward - 101.0)
    assert out[0] == pytest.approx(5.0 - 1.0 / 3) and out[1] == pytest.approx(-1.0 / 3)


def make(actions, shaping=5.0, joints=3):
    return lambda: gymnasium.make(ARM_REACH_ID, joints=joints, actions=actions, shaping=shaping)


def test_a_demonstrated_update_raises_its_move_there_and_not_far_away():
    """One replayed demonstration (the paper's reward, which the demonstrations' potential
    shapes): at its start the demonstrated first move gains value, and at a pose far from it in
    every joint no value moves at all (the per-joint terms read only their own joint's tiles)."""
    task = ArmReach(joints=3, actions="pairs", shaping=0.0)
    goal = np.array(task.goal[:3])
    path = np.linspace(goal + np.radians([30.0, 30.0, 30.0]), goal, 40)
    start, actions = task.demonstration_actions(path)
    config = DynaQConfig(planning="zero", max_steps_per_episode=50)
    result = run_experiments(make("pairs", 0.0), config, 1, 1, 0, [path], task.features())
    q = result.q_values(start)
    move = task.directions[actions[0]]
    back = int(np.flatnonzero((task.directions == -move).all(axis=1))[0])
    assert q[actions[0]] > 1.0 and q[actions[0]] > q[back] + 1.0
    # every move toward the goal in the demonstrated joints gained: it shares their terms
    toward = [a for a, m in enumerate(task.directions) if (m <= 0).all()]
    assert q[toward].min() > q.max() / 3
    far = goal - np.radians([100.0, 100.0, 40.0])
    far = np.clip(far, task.lower, task.upper)
    assert np.all(np.abs(far - path).min(axis=0) >= np.radians(40.0))  # over two tiles
    assert np.all(result.q_values(far) == 0.0)


def test_the_factored_value_learns_the_pairs_where_one_column_per_action_does_not():
    task = ArmReach(joints=6, actions="pairs")
    rng = np.random.default_rng(3)
    starts = np.array([task.random_start(rng) for _ in range(100)])
    config = DynaQConfig(planning="zero", max_steps_per_episode=3000)
    factored = run_experiments(make("pairs", joints=6), config, 1, 500, 0, None, task.features())
    original = linear.value_factors
    linear.value_factors = lambda *args: None
    try:
        plain = run_experiments(make("pairs", joints=6), config, 1, 500, 0, None, task.features())
    finally:
        linear.value_factors = original
    assert factored.weights.shape == plain.weights.shape == (1, factored.coder.size, 72)
    ok = greedy_success(task, factored.coder, factored.weights[0], starts, 3000).mean()
    bad = greedy_success(task, plain.coder, plain.weights[0], starts, 3000).mean()
    assert ok >= 0.9 and ok > bad + 0.2, (ok, bad)
    assert factored.steps.sum() < 0.7 * plain.steps.sum()


def followed(joints=4, shaping=5.0):
    """An ``"all-follow"`` task with one demonstrated path to follow, and its bound features."""
    task = ArmReach(joints=joints, actions="all-follow", shaping=shaping)
    goal = np.array(task.goal[:joints])
    task = task.with_paths([np.linspace(goal + np.radians(20.0), goal, 30)])
    coder = with_cost_group(task.features(), joints).bind(*task.observation_bounds)
    return task, coder


def test_any_joints_or_follow_is_factored_with_a_column_of_its_own_for_the_follow_action():
    """The moves' joint terms read their joint's tiles and the follow cost's; the follow action
    reads every tile in its own column; the expanded table gives the same values."""
    task, coder = followed()
    joints = task.joints
    assert task.n_actions == 3**joints and task.actions == "all-follow"
    slots = slot_joints(coder, joints, follows=True)
    assert slots is not None and slot_joints(coder, joints) is None
    comp = action_components(task.directions)
    rng = np.random.default_rng(7)
    w = rng.normal(size=(coder.size, 3 * joints + 1))
    for _ in range(5):
        obs = task.observe(task.random_start(rng))
        feats = coder.active(obs)
        expected = np.zeros(task.n_actions)
        for a, move in enumerate(task.directions):
            for i, f in enumerate(feats):
                js = [slots[i]] if slots[i] < joints else range(joints)  # the cost: every joint
                expected[a] += sum(w[f, 3 * j + int(move[j]) + 1] for j in js)
        expected[-1] = w[feats, 3 * joints].sum()
        out = np.empty(task.n_actions)
        factored_values(w, comp, slots, np.empty(3 * joints + 1), feats, out)
        assert np.allclose(out, expected)
        table = expand(w, comp, row_joints(coder))
        assert table.shape == (coder.size, task.n_actions)
        assert np.allclose(table[feats].sum(axis=0), expected)


def test_a_run_with_any_joints_or_follow_learns_the_follow_action_too():
    task, _ = followed(joints=3, shaping=0.0)
    path = np.asarray(task.paths[0])
    config = DynaQConfig(planning="zero", max_steps_per_episode=300)
    result = run_experiments(
        make("all-follow", 0.0), config, 1, 4, 0, [path], ArmReach(joints=3).features()
    )
    assert result.task.actions == "all-follow" and result.task.paths
    assert result.weights.shape[-1] == 3**3  # 26 moves and the follow action, expanded
    q = result.q_values(result.task.observe(path[0]))
    assert q[-1] > 1.0  # the replayed demonstration pressed it, and it reached the goal


def test_the_greedy_policy_of_any_joints_or_follow_hands_over_where_its_moves_stall():
    """Weights that always move joint 1 up: at its limit the move leaves the arm where it is;
    the greedy policy hands over to the follow action and reaches the goal, where without the
    hand-over (or with another action set) it stays at the limit."""
    task, coder = followed(joints=3)
    table = np.zeros((coder.size, task.n_actions))
    table[:, 0] = 1.0  # joint 1 up, everywhere
    start = np.array(task.goal[:3])
    start[0] = task.upper[0] - 3.5 * task.step
    path, reached = greedy_rollout(task, coder, table, start, 2_000)
    assert reached and task.success(path[-1])
    assert path[3, 0] == pytest.approx(task.upper[0] - 0.5 * task.step)  # three moves up
    np.testing.assert_allclose(path[:4, 1:], np.tile(start[1:], (4, 1)))  # of joint 1 alone
    assert np.abs(path[4] - path[3]).max() > 0.5 * task.step  # then the follow action, not a stay
    assert not greedy_success(task, coder, table, start[None], 2_000, hand_over=False)[0]
