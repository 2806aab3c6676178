"""The continuous task's follow action: every joint at once, along the demonstrated paths."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium
import numpy as np
import pytest

from studio.capture import load_demonstration
from studio.cli import main
from studio.learning import (
    TILE_ROLLOUT_SECONDS_PER_STEP,
    ArmReach,
    ConfigError,
    DynaQConfig,
    LearningError,
    PolicyFileError,
    RunRequest,
    TilePolicyFile,
    load_any_policy,
    policy_likeness_card,
    policy_summary,
    resolve_run,
    run_experiments,
)
from studio.learning.linear._common_value import without_common
from studio.learning.linear._linear import _q_values, greedy_success
from studio.learning.linear._policy import (
    demonstrated_pace,
    load_tile_policy,
    rollout_tile_policy,
    save_tile_policy,
)
from studio.learning.paper._beyond import demonstration_paths
from studio.learning.tasks._gym import ARM_REACH_ID
from studio.learning.tasks._reach import reach_step

SAMPLES = Path(__file__).resolve().parents[2] / "studio" / "samples"


def line_task(joints: int = 3, points: int = 200) -> tuple[ArmReach, np.ndarray]:
    """A task whose one path runs straight, in joint space, from a start to its goal."""
    goal = np.array(ArmReach(joints=joints).goal[:joints])
    start = goal - np.radians([30.0, -20.0, 10.0, 5.0, -5.0, 5.0][:joints])
    path = start + np.linspace(0.0, 1.0, points)[:, None] * (goal - start)
    return ArmReach(joints=joints, goal=tuple(goal), actions="follow", paths=(path,)), path


def test_the_follow_action_moves_every_joint_one_step_along_the_path_and_cuts_back_to_it():
    task, path = line_task()
    follow = task.n_actions - 1
    assert task.n_actions == 2 * task.joints + 1
    assert len(ArmReach(joints=3, actions="follow", paths=np.stack([path, path])).paths) == 2
    direction = (path[-1] - path[0]) / np.abs(path[-1] - path[0]).max()
    q = path[0].copy()
    reach_step(task.params, q, follow)
    assert np.allclose(q - path[0], task.step * direction)  # one step, every joint, on the line
    off = path[40] + np.radians([3.0, 3.0, -3.0])  # beside the path: back toward it
    q = off.copy()
    reach_step(task.params, q, follow)

    def to_line(x):
        along = path[0] + np.dot(x - path[0], direction) / direction.dot(direction) * direction
        return np.linalg.norm(x - along)

    assert to_line(q) < to_line(off) and np.abs(q - off).max() == pytest.approx(task.step)
    q = path[-1].copy()  # at the path's end it stays
    reward, done = reach_step(task.params, q, follow)
    assert np.array_equal(q, path[-1]) and done


def test_a_demonstration_is_walked_with_the_follow_action_in_fewer_steps():
    task, path = line_task()
    start, actions = task.demonstration_actions(path)
    assert np.array_equal(start, path[0]) and set(actions.tolist()) == {task.n_actions - 1}
    single = ArmReach(joints=3, goal=task.goal, actions="single")
    _, staircase = single.demonstration_actions(path)
    assert len(actions) <= 0.5 * len(staircase)


def test_without_paths_follow_is_one_joint_per_action_bit_for_bit():
    features = ArmReach(joints=3).features()
    runs = [
        run_experiments(
            lambda a=actions: gymnasium.make(ARM_REACH_ID, joints=3, actions=a),
            DynaQConfig(planning="zero", max_steps_per_episode=500),
            1,
            5,
            3,
            features=features,
        )
        for actions in ("single", "follow")
    ]
    assert np.array_equal(runs[0].weights, runs[1].weights)
    assert runs[1].task.n_actions == 6 and runs[1].task.paths == ()


def test_run_experiments_gives_the_task_its_demonstrations_and_the_policy_keeps_them(tmp_path):
    task, path = line_task()
    result = run_experiments(
        lambda: gymnasium.make(ARM_REACH_ID, joints=3, goal=task.goal, actions="follow"),
        DynaQConfig(planning="zero", max_steps_per_episode=500),
        1,
        20,
        0,
        [path],
        task.features(),
    )
    assert result.task.n_actions == 7 and len(result.task.paths) == 1
    assert result.weights.shape[-1] == 7
    saved = tmp_path / "follow.policy.npz"
    save_tile_policy(saved, result)
    loaded = load_any_policy(saved)
    assert loaded.task == result.task  # the followed points come back as they were
    assert policy_summary(loaded)["task"]["paths"] == 1  # a listing counts them
    assert "paths" not in ArmReach(joints=3).to_dict()  # a task without any stores none
    env = gymnasium.make(ARM_REACH_ID, **result.task.to_dict())
    assert env.action_space.n == 7


def test_a_task_that_follows_paths_observes_its_follow_cost_and_tiles_it_on_its_own():
    task, path = line_task()
    env = gymnasium.make(ARM_REACH_ID, **task.to_dict())
    obs, _ = env.reset(seed=1)
    q = env.unwrapped.q
    followed = np.asarray(task.paths[0])
    left = np.linalg.norm(
        followed[-1] - followed, axis=1
    )  # a straight path: the chord is its length
    assert obs.shape == (4,) and np.array_equal(obs[:3], q)
    assert obs[3] == pytest.approx(
        np.min(2.0 * np.linalg.norm(followed - q, axis=1) + left), abs=0.02
    )
    assert env.observation_space.contains(obs)
    assert task.features().groups == ((0,), (1,), (2,), (3,))
    no_paths = ArmReach(joints=3, actions="follow")
    assert np.array_equal(no_paths.observe(q), q) and no_paths.features().groups[-1] == (2,)
    # run_experiments tiles the cost also for a coding made before the task had paths
    result = run_experiments(
        lambda: gymnasium.make(ARM_REACH_ID, joints=3, goal=task.goal, actions="follow"),
        DynaQConfig(planning="zero", max_steps_per_episode=200), 1, 3, 0, [path],
        no_paths.features(),
    )  # fmt: skip
    assert result.coder.coding.groups[-1] == (3,) and result.coder.spec.low.shape == (4,)
    with pytest.raises(LearningError, match="observe 4 values but the task 3"):
        greedy_success(no_paths, result.coder, result.weights[0], q[None], 10)  # not result.task


def test_a_follow_policy_from_before_the_cost_was_observed_rolls_out_on_its_joint_features(
    tmp_path,
):
    """Its features tile the joints alone: the rollout observes the joints only, as in training."""
    task, _ = line_task()
    coder = ArmReach(joints=3).features(tilings=4, tiles=6).bind(task.lower, task.upper)
    weights = np.zeros((coder.size, task.n_actions))
    weights[:, task.n_actions - 1] = 1.0  # always follow
    policy = TilePolicyFile(coder=coder, weights=weights, config=DynaQConfig(), task=task)
    start = np.asarray(task.paths[0][0]) + 0.05
    times, q, reached = rollout_tile_policy(policy, start, 50.0)
    assert reached and np.allclose(q[-1, :3], task.goal[:3], atol=task.step)


class PythonLoop(gymnasium.Wrapper):
    """Any wrapper of its own makes run_experiments step the environment from Python."""


def test_the_compiled_kernel_observes_the_follow_cost_as_the_environment_does():
    task, _ = line_task()
    config = DynaQConfig(planning="full", planning_steps=3, max_steps_per_episode=300)
    runs = [
        run_experiments(make, config, 1, 4, 2, features=task.features(), workers=1)
        for make in (
            lambda: gymnasium.make(ARM_REACH_ID, **task.to_dict()),
            lambda: PythonLoop(gymnasium.make(ARM_REACH_ID, **task.to_dict())),
        )
    ]
    assert runs[0].compiled and not runs[1].compiled
    assert np.array_equal(runs[0].steps, runs[1].steps)
    assert np.array_equal(runs[0].weights, runs[1].weights)


def test_a_policy_taught_to_follow_its_demonstration_moves_like_it():
    """One sample demonstration, 3,000 episodes, no planning: the follow policy's rollout from
    the demonstration's start lies within 0.05 rad a sample of it; one joint per action's, a
    staircase, does not."""
    demo = load_demonstration(SAMPLES / "sample-reach-3.demo.json")
    cards = {}
    goal = tuple(demo.q_robot[-1])
    for actions in ("follow", "single"):
        task = ArmReach(goal=goal, actions=actions)
        config = DynaQConfig(planning="zero", max_steps_per_episode=3000)
        result = run_experiments(
            lambda a=actions: gymnasium.make(ARM_REACH_ID, goal=goal, actions=a),
            config,
            1,
            3000,
            0,
            [demo.q_robot],
            task.features(),
            workers=1,
        )
        policy = TilePolicyFile(
            coder=result.coder, weights=result.weights[0], config=config, task=result.task
        )
        cards[actions] = policy_likeness_card(policy, demo.times, demo.q_robot)
    assert cards["follow"].dtw_rad <= 0.05 and cards["follow"].policy.together >= 0.5
    assert cards["single"].dtw_rad > 0.1 and cards["single"].policy.together == 0.0


def test_bad_paths_are_refused_in_one_sentence_and_a_run_without_demonstrations_moves_one_joint():
    _, path = line_task()
    with pytest.raises(ConfigError, match='actions="follow"'):
        ArmReach(joints=3, actions="single", paths=(path,))
    with pytest.raises(ConfigError, match=r"Path 0 has shape \(4,\)"):
        ArmReach(joints=3, actions="follow", paths=((1.0, 2.0, 3.0, 4.0),))
    with pytest.raises(ConfigError, match="Path 0 holds NaN"):
        ArmReach(joints=3, actions="follow", paths=(np.full((5, 3), np.nan),))
    nan_demo = path.copy()
    nan_demo[7, 1] = np.nan
    with pytest.raises(LearningError, match="NaN"):  # through run_experiments: one sentence
        run_experiments(
            lambda: gymnasium.make(ARM_REACH_ID, joints=3, actions="follow"),
            DynaQConfig(planning="zero"),
            1,
            2,
            0,
            [nan_demo],
            ArmReach(joints=3, actions="follow").features(),
        )
    with pytest.raises(
        LearningError, match=r"Demonstration 0 has shape \(0, 3\)"
    ):  # a zero-length cut
        run_experiments(
            lambda: gymnasium.make(ARM_REACH_ID, joints=3), DynaQConfig(planning="zero"), 1, 2, 0,
            [np.zeros((0, 3))], ArmReach(joints=3).features(),
        )  # fmt: skip
    # the default action set: without demonstrations a run moves one joint per action
    record = resolve_run(RunRequest(task="arm-reach", experiments=1))
    assert record.arm_reach().actions == "follow" and record.arm_reach().n_actions == 12


def test_following_from_anywhere_reaches_the_goal_without_going_round_in_circles():
    """Three straight demonstrations from random starts: the follow action alone brings every
    random start to the goal. (Heading for the nearest point instead, a start between two paths
    went to and fro between them for ever: 25% of these starts.)"""
    from studio.learning.paper._beyond import demonstration_paths

    task = ArmReach(joints=6)
    paths = demonstration_paths(task, 3, np.random.default_rng([1, 6]))
    follow = ArmReach(joints=6, actions="follow").with_paths(paths)
    action = follow.n_actions - 1
    rng = np.random.default_rng(7)
    for _ in range(100):
        q = follow.random_start(rng)
        for _ in range(1000):
            _, done = reach_step(follow.params, q, action)
            if done:
                break
        assert done


def test_the_value_common_to_every_action_is_folded_into_the_ordinary_table():
    """On a follow task the learner keeps a column common to every action (``_common_value``);
    the table it hands out has one column per action and the same Q."""
    w = np.random.default_rng(0).normal(size=(6, 4))  # 3 actions and the common column
    feats = np.array([0, 2, 5])
    q = np.empty(3)
    _q_values(w, feats, q)  # the learner's Q(s, a) = C(s) + A_a(s)
    table = without_common(w)
    assert table.shape == (6, 3)
    assert np.allclose(q, table[feats].sum(axis=0))
    plain = np.empty(3)
    _q_values(table, feats, plain)
    assert np.allclose(plain, q)
    task, _ = line_task()
    result = run_experiments(
        lambda: gymnasium.make(ARM_REACH_ID, **task.to_dict()),
        DynaQConfig(planning="zero", max_steps_per_episode=300),
        1, 3, 0, features=task.features(), workers=1,
    )  # fmt: skip
    assert result.weights.shape[-1] == task.n_actions


def test_demonstrations_cost_no_greedy_success_after_long_training_without_planning():
    """The control the common value keeps: six joints, the default shaping, 3 straight
    demonstrations from random starts, 4,000 episodes, no planning. Greedy success from 200
    random starts with them is at most 2 points below without (with a column per action alone,
    this seed read 0.955 against 0.995: a single joint stepped to and fro far from them)."""
    task = ArmReach(joints=6)
    demos = demonstration_paths(task, 3, np.random.default_rng([0, 6]))
    starts = np.random.default_rng([0, 6, 7]).uniform(task.lower, task.upper, (200, 6))
    success = []
    for given in (demos, []):
        result = run_experiments(
            lambda: gymnasium.make(ARM_REACH_ID, joints=6),
            DynaQConfig(planning="zero", max_steps_per_episode=3000),
            1, 4000, 0, given, task.features(), workers=1,
        )  # fmt: skip
        w = result.weights[0]
        success.append(greedy_success(result.task, result.coder, w, starts, 3000).mean())
    assert success[0] >= success[1] - 0.02, success


def test_a_policy_taught_from_a_demonstration_moves_at_its_pace(tmp_path):
    """The run's policy keeps the demonstration's pace: its moving time (sample 1 moves from
    its first sample to its last) over the steps the task takes along it, so a rollout along its
    route takes as long as the person moved."""
    demo = load_demonstration(SAMPLES / "sample-reach-1.demo.json")
    out = tmp_path / "run"
    args = ["train", "--task", "arm-reach", "--demos", "sample-reach-1", "--planning", "zero"]
    args += ["--episodes", "2", "--experiments", "1", "--out", str(out), "--no-progress"]
    assert main(args) == 0
    policy = load_tile_policy(out / "policy.policy.npz")
    _, actions = policy.task.demonstration_actions(demo.q_robot)
    duration = demo.times[-1] - demo.times[0]
    assert policy.seconds_per_step == pytest.approx(duration / len(actions))
    assert policy.seconds_per_step > 2 * TILE_ROLLOUT_SECONDS_PER_STEP  # 24 steps in 2.5 s
    # every rollout takes the policy's pace unless told otherwise
    start = demo.q_robot[0]
    own = rollout_tile_policy(policy, start, 50.0, 200)
    told = rollout_tile_policy(policy, start, 50.0, 200, seconds_per_step=policy.seconds_per_step)
    np.testing.assert_array_equal(own[0], told[0])
    quick = rollout_tile_policy(policy, start, 50.0, 200, seconds_per_step=0.04)
    assert own[0][-1] == pytest.approx(quick[0][-1] * policy.seconds_per_step / 0.04)
    # a cut that holds still for a second before and after the motion: the same pace
    hold = np.arange(1, 111) / 110.0
    padded_t = np.r_[demo.times[0] - hold[::-1], demo.times, demo.times[-1] + hold]
    padded_q = np.r_[[demo.q_robot[0]] * 110, demo.q_robot, [demo.q_robot[-1]] * 110]
    assert demonstrated_pace(policy.task, [(padded_t, padded_q)]) == pytest.approx(
        policy.seconds_per_step
    )
    # two demonstrations: their total time over their total steps; one at the goal adds nothing
    twice = [(demo.times, demo.q_robot), (demo.times * 3, demo.q_robot)]
    assert demonstrated_pace(policy.task, twice) == pytest.approx(2 * policy.seconds_per_step)
    still = np.repeat(demo.q_robot[-1:], 5, axis=0)
    assert (
        demonstrated_pace(policy.task, [(demo.times[:5], still)]) == TILE_ROLLOUT_SECONDS_PER_STEP
    )
    with pytest.raises(LearningError, match="times do not increase"):
        demonstrated_pace(policy.task, [(demo.times[::-1], demo.q_robot)])


def test_a_policy_file_without_a_pace_has_the_default_and_a_bad_pace_is_refused(tmp_path):
    task, path = line_task()
    result = run_experiments(
        lambda: gymnasium.make(ARM_REACH_ID, joints=3, goal=task.goal, actions="follow"),
        DynaQConfig(planning="zero", max_steps_per_episode=500),
        1,
        5,
        0,
        [path],
        task.features(),
    )
    saved = tmp_path / "follow.policy.npz"
    assert save_tile_policy(saved, result, seconds_per_step=0.25).seconds_per_step == 0.25
    assert load_tile_policy(saved).seconds_per_step == 0.25
    with np.load(saved) as archive:
        header, weights = json.loads(str(archive["header"])), archive["weights"]
    for pace, expected in ((None, TILE_ROLLOUT_SECONDS_PER_STEP), (0.0, None), ("fast", None)):
        if pace is None:
            header.pop("seconds_per_step")  # a file written before policies kept a pace
        else:
            header["seconds_per_step"] = pace
        np.savez(saved, header=np.array(json.dumps(header)), weights=weights)
        if expected is not None:
            assert load_tile_policy(saved).seconds_per_step == expected
            continue
        with pytest.raises(PolicyFileError) as err:
            load_tile_policy(saved)
        assert "seconds_per_step" in str(err.value) and "positive number" in str(err.value)
    with pytest.raises(LearningError, match="positive number"):
        TilePolicyFile(result.coder, result.weights[0], result.config, seconds_per_step=-1.0)


def test_at_the_demonstrations_pace_the_follow_policy_is_as_smooth_as_the_person():
    """Sample 1, 3,000 episodes, no planning: rolled out at the demonstration's pace the policy
    takes the person's time and its LDLJ is within 20% of the person's; at the fixed 0.04 s a
    step it took 1.0 s and read 24% smoother."""
    demo = load_demonstration(SAMPLES / "sample-reach-1.demo.json")
    goal = tuple(demo.q_robot[-1])
    config = DynaQConfig(planning="zero", max_steps_per_episode=3000)
    result = run_experiments(
        lambda: gymnasium.make(ARM_REACH_ID, goal=goal),
        config,
        1,
        3000,
        0,
        [demo.q_robot],
        ArmReach(goal=goal).features(),
        workers=1,
    )
    cards = {}
    for pace in (TILE_ROLLOUT_SECONDS_PER_STEP, None):
        policy = TilePolicyFile(
            coder=result.coder,
            weights=result.weights[0],
            config=config,
            task=result.task,
            seconds_per_step=pace or demonstrated_pace(result.task, [(demo.times, demo.q_robot)]),
        )
        cards[pace] = policy_likeness_card(policy, demo.times, demo.q_robot)

    def off(card) -> float:
        return abs(card.policy.ldlj / card.demonstration.ldlj - 1.0)

    paced, quick = cards[None], cards[TILE_ROLLOUT_SECONDS_PER_STEP]
    assert paced.dtw_rad <= 0.05 and off(paced) <= 0.2
    assert paced.policy.duration_s == pytest.approx(paced.demonstration.duration_s, abs=0.05)
    assert off(quick) > 0.2 and quick.policy.duration_s < 0.5 * quick.demonstration.duration_s
