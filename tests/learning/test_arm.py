from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from studio.learning import MAX_TABLE_ENTRIES, ArmGrid, DynaQConfig, LearningError, run_experiments
from studio.learning.tasks._arm import erase_loops

grids = st.builds(
    ArmGrid,
    joints=st.integers(1, 4),
    bins=st.integers(2, 7),
    low_deg=st.sampled_from([-180.0, -90.0, 0.0]),
    high_deg=st.sampled_from([120.0, 180.0]),
)


def test_paper_grid() -> None:
    grid = ArmGrid()
    mdp = grid.mdp()
    assert (grid.n_states, grid.n_actions) == (1331, 27)
    assert grid.goal == (5, 6, 2)
    assert mdp.terminal.sum() == 1 and mdp.terminal[grid.goal_state]
    assert grid.goal_state not in mdp.start_states and mdp.start_states.size == 1330
    into_goal = mdp.next_state == grid.goal_state
    np.testing.assert_array_equal(mdp.reward[into_goal], 100.0)
    np.testing.assert_array_equal(mdp.reward[~into_goal], -1.0)
    # out-of-range moves leave that joint in place: from the corner (0, 0, 0) the all -1 action stays
    corner = grid.state_of((0, 0, 0))
    assert mdp.next_state[corner, 0] == corner
    assert grid.bins_of(int(mdp.next_state[corner, 26])) == (1, 1, 1)
    assert mdp.next_state[corner, grid.stay_action] == corner
    np.testing.assert_allclose(
        np.degrees(grid.angles_of(grid.goal_state)), [0, 360 / 11, -360 / 11 * 3]
    )


@settings(max_examples=40, deadline=None)
@given(grid=grids, data=st.data())
def test_state_bins_angles_round_trip(grid: ArmGrid, data: st.DataObject) -> None:
    state = data.draw(st.integers(0, grid.n_states - 1))
    bins = grid.bins_of(state)
    assert grid.state_of(bins) == state
    assert grid.state_of_angles(grid.angles_of(state)) == state
    # anywhere inside a bin maps to that bin
    offset = data.draw(st.floats(-0.49, 0.49)) * grid.bin_width
    assert grid.state_of_angles(grid.angles_of(state) + offset) == state


def _one_action_apart(grid: ArmGrid, path: list[int]) -> bool:
    mdp = grid.mdp()
    return all(
        s != s_next and mdp.action_between(s, s_next) >= 0
        for s, s_next in zip(path[:-1], path[1:], strict=True)
    )


@settings(max_examples=40, deadline=None)
@given(grid=grids, data=st.data())
def test_path_from_joints_is_a_valid_grid_path(grid: ArmGrid, data: st.DataObject) -> None:
    low, high = np.radians(grid.low_deg) - 0.3, np.radians(grid.high_deg) + 0.3
    n = data.draw(st.integers(1, 8))
    q = np.array(
        data.draw(
            st.lists(
                st.lists(st.floats(low, high), min_size=grid.joints, max_size=grid.joints),
                min_size=n,
                max_size=n,
            )
        )
    )
    trace = grid.trace_joints(q, stop_at_goal=False)
    path = trace.states
    assert grid.path_from_joints(q, stop_at_goal=False) == path
    assert path[0] == grid.state_of_angles(q[0]) and path[-1] == grid.state_of_angles(q[-1])
    assert _one_action_apart(grid, path)  # pauses removed, one action per step
    assert len(set(path)) == len(path)  # loops erased
    # each state belongs to a sample, in order, and a sample's own bin is reached by that sample
    assert len(trace.samples) == len(path) and trace.samples == sorted(trace.samples)
    for state, sample in zip(path, trace.samples, strict=True):
        if state == grid.state_of_angles(q[sample]):
            continue
        assert sample > 0  # a state filled in between sample - 1 and sample
    assert trace.reaches_goal == (grid.goal_state in _raw_walk(grid, q))
    cut = grid.path_from_joints(q)  # stop_at_goal is the default: what demonstrations replay
    if trace.reaches_goal:
        assert cut[-1] == grid.goal_state and cut.count(grid.goal_state) == 1
        assert cut[0] == path[0] and _one_action_apart(grid, cut)
    else:
        assert cut == path


def _raw_walk(grid: ArmGrid, q: np.ndarray) -> list[int]:
    """Every state the diagonal-then-straight walk between the samples passes (a reference)."""
    bins = [tuple(int(b) for b in grid.bins_of_angles(row[: grid.joints])) for row in q]
    walk = [bins[0]]
    for target in bins[1:]:
        current = walk[-1]
        while current != target:
            current = tuple(c + int(np.sign(t - c)) for c, t in zip(current, target, strict=True))
            walk.append(current)
    return [grid.state_of(b) for b in walk]


@settings(max_examples=60, deadline=None)
@given(grid=grids, data=st.data())
def test_a_jump_over_the_goal_between_two_samples_is_cut_there(
    grid: ArmGrid, data: st.DataObject
) -> None:
    """Issue 13 item 9: no sample lies in the goal bin, but the arm passed through it."""
    start = np.array([data.draw(st.integers(0, grid.bins - 1)) for _ in range(grid.joints)])
    end = np.array([data.draw(st.integers(0, grid.bins - 1)) for _ in range(grid.joints)])
    steps = int(np.max(np.abs(end - start)))
    assume(steps >= 2)
    k = data.draw(st.integers(1, steps - 1))  # a state strictly between the two samples
    goal = start + np.sign(end - start) * np.minimum(k, np.abs(end - start))
    grid = ArmGrid(grid.joints, grid.bins, grid.low_deg, grid.high_deg, tuple(int(b) for b in goal))
    centres = np.array([grid.angles_of(grid.state_of(b)) for b in (start, end)])
    rest = data.draw(st.integers(0, 3))  # the samples after the jump: the arm comes back to rest
    q = np.vstack([centres, np.repeat(centres[:1], rest, axis=0)])
    trace = grid.trace_joints(q)
    assert trace.reaches_goal
    assert trace.states[-1] == grid.goal_state and trace.states[0] == grid.state_of(start)
    assert len(trace.states) == k + 1 and _one_action_apart(grid, trace.states)
    assert trace.samples[-1] == 1  # reached by the second sample
    assert grid.path_from_joints(q) == trace.states


def test_a_reach_and_return_is_cut_at_its_first_goal_visit() -> None:
    grid = ArmGrid(goal=(7, 5, 5))
    bins = [(5, 5, 5), (6, 5, 5), (6, 5, 5), (7, 5, 5), (8, 5, 5), (7, 5, 5), (6, 5, 5), (5, 5, 5)]
    q = np.array([grid.angles_of(grid.state_of(b)) for b in bins])
    path = grid.path_from_joints(q)
    assert [grid.bins_of(s) for s in path] == [(5, 5, 5), (6, 5, 5), (7, 5, 5)]
    assert grid.trace_joints(q).samples == [0, 1, 3]
    # without the cut the return erases the reach: the loop-free path is back at rest
    assert grid.path_from_joints(q, stop_at_goal=False) == [grid.state_of((5, 5, 5))]


def test_flicker_on_a_bin_boundary_is_erased_before_the_goal() -> None:
    grid = ArmGrid(goal=(7, 5, 5))
    edge = np.radians(grid.low_deg) + 6 * grid.bin_width  # between bins 5 and 6 of joint 1
    q = np.zeros((12, 3))
    q[:, 0] = edge + np.array([-1, 1] * 5 + [2 * grid.bin_width, 2 * grid.bin_width]) * 1e-3
    q[-2:, 0] = np.radians(grid.low_deg) + 7.5 * grid.bin_width
    path = grid.path_from_joints(q)
    assert [grid.bins_of(s) for s in path] == [(5, 5, 5), (6, 5, 5), (7, 5, 5)]


@given(st.lists(st.integers(0, 6), min_size=1, max_size=40))
def test_erase_loops_keeps_a_loop_free_subpath(path: list[int]) -> None:
    out = erase_loops(path)
    assert len(set(out)) == len(out)
    assert out[0] == path[0] and out[-1] == path[-1]
    steps = set(zip(path, path[1:], strict=False))
    assert all(step in steps for step in zip(out, out[1:], strict=False))


def test_path_from_joints_uses_the_first_columns_of_a_robot_path() -> None:
    grid = ArmGrid()
    q_robot = np.zeros((3, 6))
    q_robot[:, 3:] = 2.0  # wrist joints are ignored by a 3-joint grid
    q_robot[2, 0] = np.radians(100)
    path = grid.path_from_joints(q_robot)
    assert [grid.bins_of(s) for s in path] == [(5, 5, 5), (6, 5, 5), (7, 5, 5), (8, 5, 5)]
    # a motion that wobbles through the goal bin and back ends at its first arrival when asked
    grid = ArmGrid(goal=(7, 5, 5))
    assert grid.path_from_joints(q_robot, stop_at_goal=False)[-1] == grid.state_of((8, 5, 5))
    assert grid.path_from_joints(q_robot)[-1] == grid.goal_state
    assert len(grid.path_from_joints(q_robot)) == 3
    with pytest.raises(LearningError, match="joint path has shape"):
        grid.path_from_joints(np.zeros((3, 2)))
    with pytest.raises(LearningError, match="NaN"):
        grid.path_from_joints(np.full((2, 3), np.nan))


def test_six_joints_where_memory_allows_and_a_clear_refusal_beyond() -> None:
    assert ArmGrid(joints=6, bins=4).n_actions == 729
    with pytest.raises(LearningError, match=f"over the limit of {MAX_TABLE_ENTRIES:,}"):
        ArmGrid(joints=6, bins=11)
    with pytest.raises(LearningError, match="joints is 7"):
        ArmGrid(joints=7)
    with pytest.raises(LearningError, match="goal"):
        ArmGrid(goal=(11, 0, 0))
    with pytest.raises(LearningError, match="empty"):
        ArmGrid(low_deg=10, high_deg=-10)


def test_a_six_joint_grid_moves_every_joint_and_learns() -> None:
    grid = ArmGrid(joints=6, bins=3, goal=(1, 1, 1, 1, 1, 1))
    mdp = grid.mdp()
    assert mdp.next_state.shape == (3**6, 3**6)
    rng = np.random.default_rng(0)
    deltas = grid.action_deltas()
    for state, action in zip(
        rng.integers(0, grid.n_states, 50), rng.integers(0, 729, 50), strict=True
    ):
        moved = np.asarray(grid.bins_of(int(state))) + deltas[action]
        stays = (moved < 0) | (moved >= grid.bins)  # out of range: that joint stays
        moved[stays] = np.asarray(grid.bins_of(int(state)))[stays]
        assert grid.bins_of(int(mdp.next_state[state, action])) == tuple(moved)
    result = run_experiments(mdp, DynaQConfig(planning="full", planning_steps=5), 2, 3, seed=0)
    assert np.all(result.steps >= 1) and np.all(result.q[:, grid.goal_state] == 0)


def test_shortest_steps_is_the_chebyshev_distance() -> None:
    grid = ArmGrid(joints=2, bins=5, goal=(1, 3))
    assert grid.shortest_steps(grid.state_of((4, 0))) == 3
    assert grid.shortest_steps(grid.goal_state) == 0
