from __future__ import annotations

import dataclasses
import hashlib
import threading

import numpy as np
import pytest

from studio.learning import (
    ArmGrid,
    ConfigError,
    DynaQConfig,
    LearningError,
    LiveProgress,
    TabularMDP,
    check_budget,
    generate_demonstrations,
    run_experiments,
)

from .conftest import GOAL_REWARD, corridor


def test_corridor_q_after_one_episode_matches_hand_computation(one_way_corridor) -> None:
    # One action, so the episode is 0 -> 1 -> 2 -> 3 whatever the seed. With Q = 0 at the start,
    # Eq. 1 gives Q(0) = Q(1) = alpha * -1 and Q(2) = alpha * 10 (terminal state worth 0).
    alpha, gamma = 0.5, 0.9
    result = run_experiments(
        one_way_corridor,
        DynaQConfig(alpha=alpha, gamma=gamma, epsilon=0.0, planning="zero"),
        1,
        1,
        seed=3,
    )
    np.testing.assert_array_equal(result.steps, [[3]])
    np.testing.assert_array_equal(result.updates, [[3]])
    np.testing.assert_allclose(result.q[0, :, 0], [-0.5, -0.5, 5.0, 0.0], rtol=0, atol=1e-15)
    # Second episode by hand: Q(0) = -0.5 + 0.5 (-1 + 0.9 * -0.5 + 0.5) = -0.975, and so on.
    result = run_experiments(
        one_way_corridor,
        DynaQConfig(alpha=alpha, gamma=gamma, epsilon=0.0, planning="zero"),
        1,
        2,
        seed=3,
    )
    q1 = -0.5 + 0.5 * (-1 + 0.9 * -0.5 + 0.5)
    q2 = -0.5 + 0.5 * (-1 + 0.9 * 5.0 + 0.5)
    q3 = 5.0 + 0.5 * (GOAL_REWARD - 5.0)
    np.testing.assert_allclose(result.q[0, :, 0], [q1, q2, q3, 0.0], rtol=0, atol=1e-15)


@pytest.mark.parametrize(
    ("planning", "n"), [("zero", 7), ("full", 7), ("soft", 7), ("full", 0), ("soft", 3)]
)
def test_planning_update_counts(two_way_corridor, planning: str, n: int) -> None:
    result = run_experiments(
        two_way_corridor, DynaQConfig(planning=planning, planning_steps=n), 3, 12, seed=1
    )
    episode = np.arange(12)
    per_step = {
        "zero": np.zeros(12, np.int64),
        "full": np.full(12, n),
        "soft": np.maximum(n - episode, 0),
    }[planning]
    assert np.all(result.steps > 0)
    np.testing.assert_array_equal(result.updates, result.steps * (1 + per_step))


@pytest.mark.parametrize(
    ("planning", "n", "episodes"),
    [("zero", 5, 3), ("full", 7, 3), ("full", 0, 2), ("soft", 6, 9), ("prioritized", 4, 3)],
)
def test_planning_updates_really_applied(planning: str, n: int, episodes: int) -> None:
    # One state, one action, straight into the terminal state: the model holds a single pair, so
    # every update, real or planned, is Eq. 1 on it, q <- q + alpha (r - q). Q after the run
    # therefore counts the updates actually applied, not just the ones reported.
    alpha, reward = 0.5, 1.0
    mdp = TabularMDP(
        np.array([[1], [1]]), np.array([[reward], [0.0]]), np.array([False, True]), [0]
    )
    config = DynaQConfig(planning=planning, planning_steps=n, alpha=alpha, priority_threshold=0.0)
    result = run_experiments(mdp, config, 1, episodes, seed=0)
    per_episode = {
        "zero": [0] * episodes,
        "full": [n] * episodes,
        "soft": [max(n - k, 0) for k in range(episodes)],
        "prioritized": [n] * episodes,  # the pair keeps a remaining error above threshold 0
    }[planning]
    q = 0.0
    for planned in per_episode:
        for _ in range(1 + planned):
            q = q + alpha * (reward + config.gamma * 0.0 - q)
    assert result.q[0, 0, 0] == q
    np.testing.assert_array_equal(result.updates[0], [1 + p for p in per_episode])


def test_demonstrations_are_replayed_exactly() -> None:
    grid = ArmGrid(joints=2, bins=5)
    mdp = grid.mdp()
    demos = generate_demonstrations(grid, 3, np.random.default_rng(4))
    result = run_experiments(mdp, DynaQConfig(planning="full", planning_steps=5), 1, 3, 0, demos)
    np.testing.assert_array_equal(result.steps[0], [len(d) - 1 for d in demos])
    # Every transition pays -1 or +100, so every updated entry is non-zero; planning only replays
    # visited pairs. The non-zero entries are therefore exactly the demonstrated (state, action)s.
    demonstrated = set()
    for demo in demos:
        for s, s_next in zip(demo[:-1], demo[1:], strict=True):
            demonstrated.add((s, mdp.action_between(s, s_next)))
    touched = {(int(s), int(a)) for s, a in zip(*np.nonzero(result.q[0]), strict=True)}
    assert touched == demonstrated


def test_after_the_demonstrations_episodes_start_at_random() -> None:
    grid = ArmGrid(joints=2, bins=5)
    demos = generate_demonstrations(grid, 2, np.random.default_rng(0))
    result = run_experiments(grid.mdp(), DynaQConfig(), 4, 10, 0, demos)
    assert np.all(result.steps[:, :2] == [len(d) - 1 for d in demos])
    assert len(set(map(tuple, result.steps[:, 2:]))) > 1  # experiments differ after release


def test_invalid_demonstration_names_the_step() -> None:
    grid = ArmGrid(joints=2, bins=5)
    mdp = grid.mdp()
    good = generate_demonstrations(grid, 1, np.random.default_rng(0))[0]
    far = grid.state_of((0, 0)) if grid.bins_of(good[1]) != (0, 0) else grid.state_of((4, 4))
    broken = [good[0], good[1], far, *good[2:]]
    with pytest.raises(LearningError, match=r"Demonstration 1 breaks at step 1"):
        run_experiments(mdp, DynaQConfig(), 1, 3, 0, [good, broken])
    with pytest.raises(LearningError, match=r"Demonstration 0 ends in state .* not terminal"):
        run_experiments(mdp, DynaQConfig(), 1, 3, 0, [good[:-1]])
    with pytest.raises(LearningError, match=r"Demonstration 0 breaks at step 0: state 99"):
        run_experiments(mdp, DynaQConfig(), 1, 3, 0, [[99, *good]])


def test_same_seed_same_result_bit_for_bit_whatever_the_workers() -> None:
    mdp = ArmGrid(joints=2, bins=7).mdp()
    for planning in ("full", "prioritized"):
        config = DynaQConfig(planning=planning, planning_steps=10)
        a = run_experiments(mdp, config, 4, 15, seed=11, workers=1)
        b = run_experiments(mdp, config, 4, 15, seed=11, workers=2)
        c = run_experiments(mdp, config, 4, 15, seed=12, workers=2)
        np.testing.assert_array_equal(a.steps, b.steps)
        np.testing.assert_array_equal(a.updates, b.updates)
        assert a.q.tobytes() == b.q.tobytes()
        assert not np.array_equal(a.steps, c.steps)
        assert not np.array_equal(a.steps[0], a.steps[1])  # experiments are independent


def _greedy_steps(grid: ArmGrid, q: np.ndarray) -> np.ndarray:
    mdp = grid.mdp()
    steps = np.zeros(grid.n_states, np.int64)
    for start in range(grid.n_states):
        s, k = start, 0
        while not mdp.terminal[s] and k <= grid.n_states:
            s = mdp.next_state[s, np.argmax(q[s])]
            k += 1
        steps[start] = k
    return steps


def test_prioritized_reaches_the_optimal_greedy_policy_of_full_with_fewer_updates() -> None:
    grid = ArmGrid(joints=2, bins=5)
    mdp = grid.mdp()
    shortest = np.array([grid.shortest_steps(s) for s in range(grid.n_states)])
    for alpha in (0.1, 1.0):
        # epsilon = 1: a random walk visits every pair, and Q-learning learns the optimum off-policy
        runs = {
            planning: run_experiments(
                mdp,
                DynaQConfig(planning=planning, planning_steps=50, epsilon=1.0, alpha=alpha),
                1,
                60,
                seed=5,
            )
            for planning in ("full", "prioritized")
        }
        for result in runs.values():
            np.testing.assert_array_equal(_greedy_steps(grid, result.q[0]), shortest)
        assert runs["prioritized"].updates.sum() < 0.6 * runs["full"].updates.sum()


def test_prioritized_sweeps_the_goal_back_to_the_start_in_one_episode() -> None:
    # A one-way corridor walked once with alpha = 1: when the last real step learns the goal's
    # reward, sweeping must queue that state's predecessor, update it, queue its predecessor, and so
    # on back to the start, all within that step's planning budget. Q then holds the corridor's
    # exact values, V(s) = -1 + gamma V(s + 1) from V(last) = 10. Q-learning alone knows only the
    # last step.
    length, gamma = 8, 0.9
    mdp = corridor(length, actions=1)
    values = [GOAL_REWARD]
    for _ in range(length - 2):
        values.insert(0, -1.0 + gamma * values[0])
    config = DynaQConfig(alpha=1.0, gamma=gamma, planning="prioritized", planning_steps=length)
    swept = run_experiments(mdp, config, 1, 1, seed=0)
    np.testing.assert_allclose(swept.q[0, :-1, 0], values, rtol=0, atol=1e-12)
    alone = run_experiments(mdp, DynaQConfig(alpha=1.0, gamma=gamma, planning="zero"), 1, 1, seed=0)
    np.testing.assert_array_equal(alone.q[0, :-1, 0], [-1.0] * (length - 2) + [GOAL_REWARD])
    # Cut one step short of the goal, the sweeps carry falling values back just as well: the k
    # states walked are worth -(1 + gamma + ... ) up to the cut, where nothing is known yet.
    k = length - 2
    short = run_experiments(mdp, dataclasses.replace(config, max_steps_per_episode=k), 1, 1, seed=0)
    expected = [-sum(gamma**i for i in range(k - s)) for s in range(k)] + [0.0, 0.0]
    np.testing.assert_allclose(short.q[0, :, 0], expected, rtol=0, atol=1e-12)


def test_prioritized_without_planning_is_q_learning() -> None:
    mdp = ArmGrid(joints=2, bins=5).mdp()
    zero = run_experiments(mdp, DynaQConfig(planning="zero"), 2, 10, seed=2)
    swept = run_experiments(
        mdp, DynaQConfig(planning="prioritized", planning_steps=0), 2, 10, seed=2
    )
    assert zero.q.tobytes() == swept.q.tobytes()


def test_live_progress_is_filled_and_stop_is_obeyed() -> None:
    mdp = corridor(6, actions=2)
    live = LiveProgress(2, 5)
    result = run_experiments(mdp, DynaQConfig(), 2, 5, 0, live=live)
    np.testing.assert_array_equal(live.steps, result.steps)
    assert live.completed == 10 and not result.stopped
    with pytest.raises(LearningError, match="new LiveProgress"):
        run_experiments(mdp, DynaQConfig(), 2, 5, 0, live=live)

    live = LiveProgress(2, 5)
    live.stop()
    result = run_experiments(mdp, DynaQConfig(), 2, 5, 0, live=live)
    assert result.stopped and not result.completed.any() and live.completed == 0


def test_stop_from_another_thread_ends_a_long_run_early() -> None:
    mdp = ArmGrid(joints=3, bins=11).mdp()
    live = LiveProgress(1, 100_000)
    box = {}
    thread = threading.Thread(
        target=lambda: box.setdefault(
            "r", run_experiments(mdp, DynaQConfig(planning="full"), 1, 100_000, 0, live=live)
        )
    )
    thread.start()
    while live.completed == 0:
        thread.join(0.001)
    live.stop()
    thread.join()
    result = box["r"]
    done = result.completed[0]
    assert result.stopped and 0 < done.sum() < 100_000
    assert np.all(done[: done.sum()]) and not np.any(done[done.sum() :])  # a prefix finished


def test_episode_cap_cuts_long_episodes() -> None:
    mdp = corridor(50, actions=2)
    result = run_experiments(mdp, DynaQConfig(epsilon=1.0, max_steps_per_episode=7), 2, 3, 0)
    np.testing.assert_array_equal(result.steps, 7)


def test_config_errors_name_field_value_and_range() -> None:
    with pytest.raises(ConfigError) as err:
        DynaQConfig(
            alpha=0.0, gamma=1.5, epsilon=float("nan"), planning="greedy", planning_steps=2.5
        )
    problems = err.value.problems
    assert len(problems) == 5
    assert problems[0] == "alpha is 0.0; give a number in (0.0, 1.0]."
    assert "gamma is 1.5" in problems[1] and "[0.0, 1.0]" in problems[1]
    assert "planning is 'greedy'" in problems[3] and "prioritized" in problems[3]
    assert "planning_steps is 2.5" in problems[4]
    with pytest.raises(ConfigError, match="Unknown config field 'beta'"):
        DynaQConfig.from_dict({"beta": 1})
    assert DynaQConfig.from_dict(DynaQConfig(planning="soft").to_dict()) == DynaQConfig(
        planning="soft"
    )


def test_budget_refuses_huge_runs_before_working() -> None:
    with pytest.raises(ConfigError, match="episodes is 1000000000; give a whole number from 1 to"):
        check_budget(20, 1_000_000_000)
    with pytest.raises(ConfigError, match="experiments x episodes"):
        check_budget(1000, 100_000)
    with pytest.raises(ConfigError, match="GB of Q tables"):
        check_budget(1000, 10, 1_000_000, 729)
    with pytest.raises(LearningError, match="seed is -1"):
        run_experiments(corridor(), DynaQConfig(), 1, 1, -1)
    check_budget(20, 100, 1331, 27)


def test_mdp_validation() -> None:
    with pytest.raises(LearningError, match="next_state holds values outside"):
        TabularMDP(np.array([[2]]), np.array([[0.0]]), np.array([False]), np.array([0]))
    with pytest.raises(LearningError, match="reward has shape"):
        TabularMDP(np.array([[0]]), np.zeros((2, 1)), np.array([False]), np.array([0]))
    with pytest.raises(LearningError, match="start_states is empty"):
        TabularMDP(np.array([[0]]), np.zeros((1, 1)), np.array([False]), np.array([], int))


_MASK = (1 << 64) - 1


def _python_dyna_q(mdp, config, episodes, seed, demos):
    """The kernel's algorithm in plain Python, drawing the same random numbers in the same order."""
    from studio.learning._learner import experiment_seed

    state = int(experiment_seed(seed, 0))

    def draw() -> int:
        nonlocal state
        state = (state + 0x9E3779B97F4A7C15) & _MASK
        z = state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK
        return z ^ (z >> 31)

    def below(n: int) -> int:
        return ((draw() >> 32) * n) >> 32

    n_states, n_actions = mdp.next_state.shape
    q = [[0.0] * n_actions for _ in range(n_states)]
    visited: list[tuple[int, int]] = []
    for episode in range(episodes):
        n = {"zero": 0, "full": config.planning_steps}.get(
            config.planning, max(config.planning_steps - episode, 0)
        )
        demo = demos[episode] if episode < len(demos) else None
        s = demo[0] if demo else int(mdp.start_states[below(mdp.start_states.size)])
        steps = 0
        while not mdp.terminal[s] and steps < config.max_steps_per_episode:
            if demo:
                a = mdp.action_between(s, demo[steps + 1])
            elif (draw() >> 11) * 2.0**-53 < config.epsilon:
                a = below(n_actions)
            else:
                ties = [b for b in range(n_actions) if q[s][b] == max(q[s])]
                a = ties[below(len(ties))] if len(ties) > 1 else ties[0]
            s2, r = int(mdp.next_state[s, a]), float(mdp.reward[s, a])
            if (s, a) not in visited:
                visited.append((s, a))
            q[s][a] = q[s][a] + config.alpha * (r + config.gamma * max(q[s2]) - q[s][a])
            for _ in range(n):
                ps, pa = visited[below(len(visited))]
                ps2, pr = int(mdp.next_state[ps, pa]), float(mdp.reward[ps, pa])
                q[ps][pa] = q[ps][pa] + config.alpha * (pr + config.gamma * max(q[ps2]) - q[ps][pa])
            s = s2
            steps += 1
    return np.array(q)


@pytest.mark.parametrize("planning", ["zero", "full", "soft"])
def test_kernel_matches_a_plain_python_transcription_bit_for_bit(planning: str) -> None:
    # checks the kernel's cached maxima, tie counts and random draws against the obvious code
    grid = ArmGrid(joints=2, bins=5)
    mdp = grid.mdp()
    demos = generate_demonstrations(grid, 2, np.random.default_rng(1))
    config = DynaQConfig(planning=planning, planning_steps=6, epsilon=0.2)
    result = run_experiments(mdp, config, 1, 12, seed=7, demonstrations=demos)
    expected = _python_dyna_q(mdp, config, 12, 7, demos)
    assert result.q[0].tobytes() == expected.tobytes()


def test_config_errors_are_keyed_by_field_and_numpy_numbers_are_accepted() -> None:
    with pytest.raises(ConfigError) as err:
        DynaQConfig(alpha=2.0, planning="x")
    assert set(err.value.by_field) == {"alpha", "planning"}
    with pytest.raises(ConfigError) as err:
        check_budget(0, 1_000_000_000)
    assert set(err.value.by_field) == {"experiments", "episodes"}
    config = DynaQConfig(planning_steps=np.int64(5), alpha=np.float64(0.5))
    assert type(config.planning_steps) is int and type(config.alpha) is float  # JSON-ready


GOLDEN_CURVES = {  # recorded before the learners' shared parts moved into their own module
    "zero": ([[6, 8, 436, 100], [6, 8, 37, 446]], 1047, "bdc8c1b9106d5f76"),
    "full": ([[6, 8, 140, 327], [6, 8, 141, 50]], 4116, "fac5e9c906562e21"),
    "soft": ([[6, 8, 337, 178], [6, 8, 307, 894]], 5944, "ad8680672178c822"),
    "prioritized": ([[6, 8, 247, 49], [6, 8, 37, 102]], 2778, "c6fc06863ec3e636"),
}


@pytest.mark.parametrize("planning", GOLDEN_CURVES)
def test_fixed_seed_results_are_unchanged(planning: str) -> None:
    """A seeded run on the paper's grid gives the very curves and Q tables it always gave: a
    refactoring of the kernel that changes one draw or one rounding fails here."""
    grid = ArmGrid()
    demos = generate_demonstrations(grid, 2, np.random.default_rng([0, 1]))
    config = DynaQConfig(planning=planning, planning_steps=5)
    result = run_experiments(grid.mdp(), config, 2, 4, 7, demos)
    steps, updates, q_digest = GOLDEN_CURVES[planning]
    assert result.steps.tolist() == steps
    assert int(result.updates.sum()) == updates
    assert hashlib.sha256(result.q.tobytes()).hexdigest()[:16] == q_digest
