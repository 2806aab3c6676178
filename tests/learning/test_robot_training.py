"""Training on the chosen robot: the compiled forward kinematics of every offered arm, a short
run on the Panda that learns, policies that name their robot, and files from before robots."""

from __future__ import annotations

import json
import math
import zipfile

import gymnasium
import numpy as np
import pytest

from studio.cli import main
from studio.kinematics import load_robot, robot_names, robot_spec
from studio.learning import (
    ArmGrid,
    ArmReach,
    DynaQConfig,
    LearningError,
    RunFolder,
    RunRecord,
    check_policy_robot,
    default_goal,
    load_any_policy,
    run_experiments,
)
from studio.learning.linear._linear import greedy_rollout, greedy_success
from studio.learning.linear._policy import save_tile_policy
from studio.learning.tabular._policy import save_policy
from studio.learning.tasks._reach import reach_step


@pytest.mark.parametrize("robot", robot_names())
def test_the_compiled_forward_kinematics_equals_pinocchios(robot):
    """For every offered robot, at random poses, the numba twin the learner steps puts the tool
    where Pinocchio does; joints beyond the learned ones are held at the goal's."""
    arm = load_robot(robot, geometry=False)
    rng = np.random.default_rng([7, len(robot)])
    most = min(6, arm.nq)
    for joints in sorted({3, most}):
        for _ in range(25):
            q = rng.uniform(arm.lower, arm.upper)
            task = ArmReach(joints=joints, goal=tuple(q), robot=robot)
            oMtool = arm.forward(q)
            assert np.allclose(task.tool_pose(q[:joints]), oMtool, atol=1e-12, rtol=0.0)
            assert np.allclose(task.full_q(q[:joints]), q)


def test_a_robots_task_takes_its_limits_and_joints():
    panda = load_robot("panda", geometry=False)
    task = ArmReach(robot="panda")
    assert task.joints == 6 and len(task.goal) == panda.nq == 7  # the 7th joint is held
    assert np.array_equal(task.lower, panda.lower[:6]) and np.array_equal(
        task.upper, panda.upper[:6]
    )
    assert np.allclose(task.goal, default_goal("panda"))
    env = gymnasium.make("TeachStudio/ArmReach-v0", robot="ur5")
    assert np.array_equal(env.observation_space.high, load_robot("ur5").upper[:6])
    assert ArmReach(robot="so100", joints=5).joints == 5  # all its five
    with pytest.raises(LearningError, match="give 3 to 5"):
        ArmReach(robot="so100", joints=6)
    with pytest.raises(LearningError, match="Unknown robot 'nosuch'") as err:
        ArmReach(robot="nosuch")
    assert err.value.by_field.keys() == {"robot"}
    # a joint never leaves the robot's own limits
    q = task.upper.copy()
    reach_step(task.params, q, 0)
    assert q[0] == task.upper[0]


def test_the_default_goals_lie_inside_the_limits_and_the_ur_arms_aim_at_their_ready_pose():
    for robot in robot_names():
        arm = load_robot(robot, geometry=False)
        goal = default_goal(robot)
        assert goal.shape == (arm.nq,) and np.all(goal >= arm.lower) and np.all(goal <= arm.upper)
    assert np.allclose(np.degrees(default_goal("ur5")), [0, -90, 90, -90, -90, 0])
    assert np.allclose(np.degrees(default_goal("puma560")), [0, 45, -90, 0, 0, 0])


def test_the_default_tiles_keep_joints_1_to_3_at_ten_degrees():
    assert ArmReach().features().tiles == 32  # the Puma560's, as measured
    assert ArmReach(robot="ur5").features().tiles == 72  # +-360 degrees: 720 / 72 = 10
    assert ArmReach(robot="ur5").features(tiles=8).tiles == 8


def test_a_short_run_on_the_panda_learns_to_put_its_tool_on_the_goal():
    """Tiny budget: the greedy policy reaches the goal from far more starts than a random walk,
    and where it says it reached, Pinocchio's tool pose is within the tolerances of the goal's:
    a wrong compiled FK would train toward the wrong place."""
    task = ArmReach(joints=3, robot="panda")
    config = DynaQConfig(planning="zero", max_steps_per_episode=1000)
    make = lambda: gymnasium.make("TeachStudio/ArmReach-v0", joints=3, robot="panda")  # noqa: E731
    result = run_experiments(make, config, 1, 150, 3, [], task.features())
    rng = np.random.default_rng(11)
    starts = np.array([task.random_start(rng) for _ in range(60)])
    learned = greedy_success(task, result.coder, result.weights[0], starts, 1000).mean()
    random_walks = 0
    for start in starts[:20]:
        q = start.copy()
        for _ in range(1000):
            if reach_step(task.params, q, int(rng.integers(task.n_actions)))[1]:
                random_walks += 1
                break
    assert learned >= 0.5 and learned >= random_walks / 20 + 0.4  # (measured: 0.60 and 0.0)
    panda = load_robot("panda", geometry=False)
    oMgoal = panda.forward(np.asarray(task.goal))
    reached = 0
    for start in starts[:10]:
        path, ok = greedy_rollout(task, result.coder, result.weights[0], start, 1000)
        if not ok:
            continue
        reached += 1
        oMtool = panda.forward(task.full_q(path[-1]))
        assert np.linalg.norm(oMtool[:3, 3] - oMgoal[:3, 3]) <= task.position_tolerance
        cos = (np.trace(oMgoal[:3, :3].T @ oMtool[:3, :3]) - 1) / 2
        assert math.degrees(math.acos(min(1.0, cos))) <= task.angle_tolerance_deg
    assert reached >= 4


def test_the_grid_of_another_robot_bins_its_own_limits():
    paper = ArmGrid()
    assert (paper.robot, paper.low_deg, paper.high_deg, paper.goal) == (
        "puma560",
        -180.0,
        180.0,
        (5, 6, 2),
    )
    grid = ArmGrid(robot="panda")
    panda = load_robot("panda", geometry=False)
    centres = np.array([grid.angles_of(s) for s in range(grid.n_states)])
    assert np.all(centres >= panda.lower[:3]) and np.all(centres <= panda.upper[:3])
    assert np.allclose(grid.low_deg, np.degrees(panda.lower[:3]))
    assert grid.goal == tuple(int(b) for b in grid.bins_of_angles(default_goal("panda")[:3]))
    assert ArmGrid(**grid.to_dict()) == grid
    with pytest.raises(LearningError, match="give 1 to 5"):
        ArmGrid(robot="so100", joints=6)


def _tile_policy(tmp_path, robot: str):
    task = ArmReach(joints=3, robot=robot)
    make = lambda: gymnasium.make("TeachStudio/ArmReach-v0", joints=3, robot=robot)  # noqa: E731
    result = run_experiments(
        make, DynaQConfig(planning="zero", max_steps_per_episode=50), 1, 2, 0, [], task.features()
    )
    path = tmp_path / f"{robot}.policy.npz"
    save_tile_policy(path, result)
    return path


def _rewrite_header(path, change) -> None:
    """The policy archive with its JSON header changed by ``change`` (an older writer's file)."""
    with zipfile.ZipFile(path) as z:
        members = {n: z.read(n) for n in z.namelist()}
    arrays = {}
    import io

    for name, data in members.items():
        arrays[name.removesuffix(".npy")] = np.load(io.BytesIO(data), allow_pickle=False)
    header = json.loads(str(arrays["header"]))
    change(header)
    arrays["header"] = np.array(json.dumps(header))
    with path.open("wb") as stream:
        np.savez_compressed(stream, **arrays)


def test_a_policy_names_its_robot_and_refuses_another_in_one_sentence(tmp_path):
    path = _tile_policy(tmp_path, "panda")
    policy = load_any_policy(path)
    assert policy.robot == "panda"
    assert json.loads(str(np.load(path)["header"]))["task"]["robot"] == "panda"
    check_policy_robot(policy.robot, "panda")  # its own robot: fine
    with pytest.raises(LearningError) as err:
        check_policy_robot(policy.robot, "ur5")
    sentence = str(err.value)
    assert robot_spec("panda").title in sentence and robot_spec("ur5").title in sentence
    assert sentence.endswith(".") and sentence.count(". ") == 0
    grid = ArmGrid(robot="ur5")
    tabular = tmp_path / "grid.policy.npz"
    save_policy(tabular, grid, np.zeros((grid.n_states, grid.n_actions)), DynaQConfig())
    assert load_any_policy(tabular).robot == "ur5"


def test_old_policies_and_run_configs_without_a_robot_are_the_puma560s(tmp_path):
    path = _tile_policy(tmp_path, "puma560")
    _rewrite_header(path, lambda h: h["task"].pop("robot"))
    assert "robot" not in json.loads(str(np.load(path)["header"]))["task"]
    assert load_any_policy(path).robot == "puma560"
    tabular = tmp_path / "grid.policy.npz"
    grid = ArmGrid()
    save_policy(tabular, grid, np.zeros((grid.n_states, grid.n_actions)), DynaQConfig())
    _rewrite_header(tabular, lambda h: h["grid"].pop("robot"))
    assert load_any_policy(tabular).robot == "puma560"
    for task in (
        {
            "kind": "arm-grid",
            "joints": 3,
            "bins": 11,
            "low_deg": -180,
            "high_deg": 180,
            "goal": [5, 6, 2],
        },
        {
            "kind": "arm-reach",
            **ArmReach().to_dict(),
            "tile_coding": ArmReach().features().to_dict(),
        },
    ):
        task.pop("robot", None)
        data = {
            "format": "teach-studio-run",
            "version": 1,
            "task": task,
            "config": DynaQConfig().to_dict(),
            "experiments": 1,
            "episodes": 1,
            "seed": 0,
            "demonstrations": [],
            "name": "",
            "origin": "cli",
            "group": None,
            "created": "2026-11-01T10:00:00+00:00",
        }
        assert RunRecord.from_dict(data).robot == "puma560"


def test_studio_train_takes_a_robot_for_both_tasks(tmp_path, capsys):
    reach = tmp_path / "reach"
    args = [
        "train",
        "--task",
        "arm-reach",
        "--robot",
        "panda",
        "--joints",
        "3",
        "--planning",
        "zero",
    ]
    assert (
        main([*args, "--episodes", "3", "--experiments", "1", "--out", str(reach), "--no-progress"])
        == 0
    )
    record = RunFolder.load(reach).record
    assert record.robot == "panda" and record.arm_reach().joints == 3
    assert len(record.arm_reach().goal) == 7  # the Panda's default goal, whole
    assert load_any_policy(reach / "policy.policy.npz").robot == "panda"
    out = tmp_path / "reach.csv"
    # the export drives the policy's own robot; the Puma560 is refused for it
    assert (
        main(["export", str(reach / "policy.policy.npz"), "--robot", "puma560", "--out", str(out)])
        == 2
    )
    err = capsys.readouterr().err.strip()
    assert "Franka Emika Panda" in err and "Puma560" in err and "\n" not in err and not out.exists()
    # ...and exports it for the Panda: its joint names, every joint (the seventh held). A policy
    # of 3 episodes rarely reaches its goal: its rollout runs to the cap, 5,000 steps by default,
    # which the export then times, checks and replays in MuJoCo (minutes); 20 steps show the same.
    args = ["export", str(reach / "policy.policy.npz"), "--robot", "panda", "--unchecked"]
    args += ["--max-steps", "20"]
    assert main([*args, "--start-deg=10,-30,20", "--out", str(out)]) == 0
    header = next(x for x in out.read_text().splitlines() if not x.startswith("#")).split(",")
    assert header == ["time", *load_robot("panda").joint_names]
    grid = tmp_path / "grid"
    assert (
        main(
            [
                "train",
                "--robot",
                "ur5",
                "--planning",
                "zero",
                "--episodes",
                "2",
                "--experiments",
                "1",
                "--out",
                str(grid),
                "--no-progress",
            ]
        )
        == 0
    )
    task = RunFolder.load(grid).record.arm_grid()
    # binned over the UR5's usable limits: its hard ones less the margin every plan keeps
    ur5 = load_robot("ur5", geometry=False)
    assert task.robot == "ur5" and np.allclose(task.low_deg, np.degrees(ur5.lower[:3]))
    assert np.allclose(np.degrees(ur5.hard_lower[:3]), (-360.0, -360.0, -180.0))
    assert main(["train", "--robot", "nosuch", "--episodes", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert "Unknown robot 'nosuch'" in err and "\n" not in err


def test_a_run_on_the_panda_replays_demonstrations_retargeted_to_the_panda(tmp_path):
    """A demonstration holds the Puma560's joints; for the Panda its recording's segment is
    retargeted (the export's path), and the run's goal is where the Panda's path ends."""
    from studio.export import training_demonstration
    from studio.learning import RunRequest, resolve_run
    from studio.samples import SAMPLES_DIR

    demo_file = SAMPLES_DIR / "sample-reach-1.demo.json"
    out = tmp_path / "demo-run"
    args = ["train", "--task", "arm-reach", "--robot", "panda", "--joints", "3"]
    args += ["--demos", "sample-reach-1", "--planning", "zero", "--episodes", "2"]
    assert main([*args, "--experiments", "1", "--out", str(out), "--no-progress"]) == 0
    record = RunFolder.load(out).record
    panda = training_demonstration(demo_file, "panda", "The demonstration")
    assert panda.robot == "panda" and panda.q_robot.shape[1] == 7
    assert np.allclose(record.arm_reach().goal, panda.q_robot[-1], atol=1e-9)
    assert np.allclose(record.demonstrations[0], panda.q_robot[:, :3], atol=1e-9)
    assert record.demonstration_motions[0].q_robot.shape[1] == 7
    card = json.loads((out / "likeness.json").read_text())["cards"][0]
    assert "error" not in card and card["card"]["frechet_m"] >= 0  # scored on the Panda's FK
    puma = training_demonstration(demo_file, "puma560", "The demonstration")
    with pytest.raises(LearningError) as err:
        resolve_run(RunRequest(task="arm-reach", robot="panda", demonstrations=[puma]))
    assert str(err.value) == (
        "The demonstration holds joints of the Puma560 (the paper's robot), not of the Franka "
        "Emika Panda; retarget it to the panda from its recording, or train on the puma560."
    )


def test_a_sweep_trial_names_its_robot():
    from studio.learning.sweeps._spec import parse_sweep_spec, resolve_trial, trial_record

    assert resolve_trial("arm-reach", {"robot": "panda", "joints": 3}, 1, 2, 0).robot == "panda"
    assert resolve_trial("arm-grid", {"robot": "ur5"}, 1, 2, 0).arm_grid().robot == "ur5"
    assert resolve_trial("arm-grid", {}, 1, 2, 0).robot == "puma560"
    with pytest.raises(LearningError, match="Unknown robot"):
        resolve_trial("arm-grid", {"robot": "nosuch"}, 1, 2, 0)
    spec = parse_sweep_spec(
        {
            "name": "robots",
            "task": "arm-reach",
            "experiments": 1,
            "episodes": 2,
            "metric": {"name": "final_steps"},
            "fixed": {"joints": 3, "planning": "zero"},
            "space": {"robot": ["puma560", "panda"]},
        }
    )
    assert [trial_record(spec, t).robot for t in spec.trials()] == ["puma560", "panda"]


def test_the_grid_environment_takes_a_robot():
    from studio.learning.runs._summary import has_default_goal

    env = gymnasium.make("TeachStudio/ArmGrid-v0", robot="panda")
    assert env.unwrapped.grid == ArmGrid(robot="panda")
    assert has_default_goal(ArmGrid(robot="panda"))
    assert not has_default_goal(ArmGrid(robot="panda", goal=(5, 5, 5)))
    # a goal that would lay the arm on the table it stands on is refused, in one sentence
    with pytest.raises(LearningError, match="table it stands on"):
        ArmGrid(robot="panda", goal=(0, 0, 0))
