"""The registered Gymnasium environments: check_env, seeding, nothing rendered, shared dynamics."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import studio.learning  # noqa: F401  (registers the environments)
from studio.learning import ArmGrid, ArmReach, LearningError
from studio.learning.tasks._gym import ARM_GRID_ID, ARM_REACH_ID
from studio.learning.tasks._reach import reach_step


@pytest.mark.parametrize("gymnasium_first", [False, True])
def test_import_studio_learning_registers_both_environments_in_either_order(gymnasium_first):
    """``import studio.learning`` registers the environments without importing Gymnasium (the
    CLI's parsers read its defaults): they are there once Gymnasium is, whichever came first."""
    import subprocess
    import sys

    imports = ["import studio.learning", "import gymnasium.spaces"]
    code = "\n".join(
        [
            "import sys",
            *(reversed(imports) if gymnasium_first else imports[:1]),
            "print('gymnasium' in sys.modules)",
            *([] if gymnasium_first else imports[1:]),
            "import gymnasium",
            f"print([gymnasium.spec(i).id for i in {[ARM_GRID_ID, ARM_REACH_ID]!r}])",
        ]
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    loaded, ids = done.stdout.splitlines()
    assert loaded == str(gymnasium_first)
    assert ids == str([ARM_GRID_ID, ARM_REACH_ID])


@pytest.mark.filterwarnings("ignore:.*render_mode")
@pytest.mark.parametrize(
    "env_id, kwargs",
    [(ARM_GRID_ID, {}), (ARM_REACH_ID, {}), (ARM_REACH_ID, {"joints": 3, "step_deg": 1.0})],
)
def test_check_env_passes_and_nothing_renders(env_id, kwargs):
    env = gymnasium.make(env_id, **kwargs)
    check_env(env.unwrapped)
    assert env.render_mode is None and env.unwrapped.metadata["render_modes"] == []
    with pytest.raises(LearningError, match="renders nothing"):
        gymnasium.make(env_id, render_mode="human", **kwargs).unwrapped  # noqa: B018


@pytest.mark.parametrize("env_id", [ARM_GRID_ID, ARM_REACH_ID])
def test_reset_seed_repeats_the_episode(env_id):
    def episode(seed):
        env = gymnasium.make(env_id)
        obs, _ = env.reset(seed=seed)
        out = [np.asarray(obs, dtype=float).copy()]
        rng = np.random.default_rng(0)
        for _ in range(20):
            obs, *_ = env.step(int(rng.integers(env.action_space.n)))
            out.append(np.asarray(obs, dtype=float).copy())
        return np.array(out)

    assert np.array_equal(episode(3), episode(3))
    assert not np.array_equal(episode(3)[0], episode(4)[0])


def test_arm_grid_env_steps_the_learners_table():
    grid = ArmGrid()
    mdp = grid.mdp()
    env = gymnasium.make(ARM_GRID_ID).unwrapped
    state, _ = env.reset(seed=0)
    rng = np.random.default_rng(1)
    for _ in range(200):
        a = int(rng.integers(grid.n_actions))
        nxt, reward, terminated, truncated, _ = env.step(a)
        assert (nxt, reward, terminated) == (
            int(mdp.next_state[state, a]),
            float(mdp.reward[state, a]),
            bool(mdp.terminal[mdp.next_state[state, a]]),
        )
        state = nxt if not terminated else env.reset()[0]


def test_arm_reach_env_steps_the_learners_function():
    task = ArmReach(joints=4, step_deg=1.5)
    env = gymnasium.make(ARM_REACH_ID, joints=4, step_deg=1.5).unwrapped
    q, _ = env.reset(seed=2)
    assert env.observation_space.contains(q)
    mirror = q.copy()
    rng = np.random.default_rng(3)
    for _ in range(300):
        a = int(rng.integers(task.n_actions))
        q, reward, terminated, _, _ = env.step(a)
        expected_reward, expected_done = reach_step(task.params, mirror, a)
        assert np.array_equal(q, mirror) and reward == expected_reward
        assert terminated == expected_done
        assert np.all(q >= task.lower) and np.all(q <= task.upper)


def test_arm_reach_env_options_start_and_bad_start():
    env = gymnasium.make(ARM_REACH_ID, joints=3).unwrapped
    q, _ = env.reset(options={"q": [0.1, 0.2, 0.3]})
    assert np.array_equal(q, [0.1, 0.2, 0.3])
    with pytest.raises(LearningError, match="inside the limits"):
        env.reset(options={"q": [10.0, 0.0, 0.0]})


def test_arm_reach_env_takes_the_task_itself():
    """A run hands its record's task to the environment as is, not rebuilt from a dict."""
    task = ArmReach(joints=4, step_deg=1.5, actions="pairs")
    env = gymnasium.make(ARM_REACH_ID, arm_reach=task)
    assert env.unwrapped.task is task
    assert env.action_space.n == task.n_actions
    with pytest.raises(LearningError, match="give the task or its settings"):
        gymnasium.make(ARM_REACH_ID, arm_reach=task, joints=3).unwrapped  # noqa: B018
