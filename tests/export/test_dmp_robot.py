"""A movement primitive fitted in the chosen robot's joint space: to a demonstration retargeted
onto that robot (the path a training run replays), saved naming its robot, rolled out, scored on
the likeness card with that robot's tool, exported for it and refused for another."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from studio.cli import main
from studio.export import ExportError, check_policy_robot, training_demonstration
from studio.kinematics import load_robot
from studio.learning import (
    DmpPolicyFile,
    LearningError,
    PolicyFileError,
    dtw_distance,
    fit_dmp_policy,
    likeness_card,
    load_any_policy,
    load_dmp_policy,
    policy_summary,
    rollout_dmp_policy,
    save_dmp_policy,
)
from studio.learning.likeness._likeness import robot_tool_positions
from studio.samples import SAMPLES_DIR
from tests.export.test_roundtrip import read_csv

DEMO = SAMPLES_DIR / "sample-reach-2.demo.json"


@pytest.fixture(scope="module")
def panda_demo():
    return training_demonstration(DEMO, "panda", "The demonstration sample-reach-2")


@pytest.fixture
def panda_policy(tmp_path: Path, panda_demo) -> tuple[Path, DmpPolicyFile]:
    policy = fit_dmp_policy(panda_demo.times, panda_demo.q_robot, robot="panda")
    path = tmp_path / "reach.panda.policy.npz"
    save_dmp_policy(path, policy)
    return path, policy


def test_a_primitive_fitted_to_the_retargeted_demonstration_drives_the_panda(
    panda_policy, panda_demo
) -> None:
    path, policy = panda_policy
    panda = load_robot("panda", geometry=False)
    assert policy.robot == "panda" and policy.primitive.joints == panda.nq == 7
    assert policy.learned_joints == 7  # all of its joints by default
    np.testing.assert_allclose(policy.goal, panda_demo.q_robot[-1])
    times, q, reached = rollout_dmp_policy(policy)
    assert reached and q.shape[1] == 7
    assert np.all(q >= panda.lower - 0.02) and np.all(q <= panda.upper + 0.02)
    # the file names its robot, and reads back as the Panda's
    with np.load(path, allow_pickle=False) as archive:
        header = json.loads(str(archive["header"]))
    assert header["robot"] == "panda" and header["primitive"]["joints"] == 7
    again = load_any_policy(path)
    assert isinstance(again, DmpPolicyFile) and again.robot == "panda"
    np.testing.assert_array_equal(again.primitive.weights, policy.primitive.weights)
    assert policy_summary(again)["task"] == {"kind": "dmp", "basis": 50, "robot": "panda"}
    # its card is scored on the Panda's tool, as the other policies' are
    card = header["likeness"]

    def panda_tool(x: np.ndarray) -> np.ndarray:
        return robot_tool_positions("panda", x)

    expected = likeness_card(
        times, q, policy.demo_times, policy.demo_q, panda_tool, joints=7
    ).to_dict()
    assert card["frechet_m"] == pytest.approx(expected["frechet_m"], rel=1e-6)
    assert card["dtw_rad"] == pytest.approx(expected["dtw_rad"], rel=1e-6)
    # it follows its demonstration: far nearer than a straight line between its ends
    demo_q = policy.demo_q
    line = np.linspace(demo_q[0], demo_q[-1], len(demo_q))
    assert card["dtw_rad"] < 0.2 * dtw_distance(line, demo_q)


def test_a_panda_primitive_exports_for_the_panda_and_is_refused_for_the_puma(
    panda_policy, tmp_path: Path, capsys
) -> None:
    path, policy = panda_policy
    with pytest.raises(ExportError, match="Franka Emika Panda.*not the Puma560"):
        check_policy_robot(path, policy.robot, "puma560")
    out = tmp_path / "dmp.csv"
    assert (
        main(["export", str(path), "--robot", "panda", "--format", "csv", "--out", str(out)]) == 0
    )
    said = capsys.readouterr().out
    assert said.startswith("the movement primitive") and "Franka Emika Panda" in said
    assert "likeness to its demonstration" in said
    header, rows = read_csv(out)
    assert header == ["time", *load_robot("panda").joint_names]
    assert np.allclose(rows[0, 1:], policy.demo_q[0], atol=1e-6)
    # scored against a named demonstration too: retargeted onto the Panda first
    assert (
        main(["export", str(path), "--robot", "panda", "--demo", str(DEMO), "--out", str(out)]) == 0
    )
    assert "likeness to sample-reach-2" in capsys.readouterr().out
    # without --robot the Puma560 is asked for: one sentence naming both
    assert main(["export", str(path), "--format", "csv", "--out", str(out)]) != 0
    err = capsys.readouterr().err
    assert "Franka Emika Panda" in err and "--robot panda" in err


def test_a_primitive_is_refused_angles_of_another_robot_and_a_file_naming_no_offered_robot(
    panda_policy, tmp_path: Path
) -> None:
    path, policy = panda_policy
    with pytest.raises(LearningError, match=r"\(N, 7\) Franka Emika Panda angles"):
        fit_dmp_policy(policy.demo_times, policy.demo_q[:, :6], robot="panda")
    with pytest.raises(LearningError, match="r2d2"):
        fit_dmp_policy(policy.demo_times, policy.demo_q, robot="r2d2")
    with np.load(path, allow_pickle=False) as archive:
        members = {k: archive[k] for k in archive.files}
    header = json.loads(str(members["header"]))
    for robot, why in (
        ("r2d2", "does not offer"),
        ("puma560", "moves 7 joints where the Puma560.* has 6"),
    ):
        bad = tmp_path / f"{robot}.policy.npz"
        members["header"] = np.array(json.dumps({**header, "robot": robot}))
        np.savez(bad, **members)
        with pytest.raises(PolicyFileError, match=why):
            load_dmp_policy(bad)


def test_a_primitive_rolls_out_within_its_robots_limits(panda_policy) -> None:
    """The Panda's sample demonstration runs along joint 4's upper limit (-4 degrees); the
    primitive, which knows no limits, must not carry the rollout past it."""
    _, policy = panda_policy
    panda = load_robot("panda", geometry=False)
    _, q, _ = rollout_dmp_policy(policy)
    assert np.all(q >= panda.lower) and np.all(q <= panda.upper)
