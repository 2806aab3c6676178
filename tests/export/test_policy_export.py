"""A policy file through the new export: timed within the Puma560's limits by default, checked
at the fixed pace --seconds-per-step asks for, and the old form unchanged."""

from __future__ import annotations

import numpy as np
import pytest

from studio.cli import main
from studio.kinematics import load_robot

from .test_roundtrip import read_csv, read_mcap


@pytest.fixture(scope="module")
def policy(tmp_path_factory):
    run = tmp_path_factory.mktemp("run") / "run"
    argv = ["train", "--out", str(run), "--episodes", "30", "--experiments", "1",
            "--planning", "full", "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    return run / "policy.policy.npz"


def test_a_policy_exports_as_a_joint_trajectory_timed_within_the_limits(policy, tmp_path, capsys):
    out = tmp_path / "p.mcap"
    start = "--start-deg=0,33,-65"  # one grid step from the goal: the path stays in range
    argv = ["export", str(policy), "--format", "mcap", start, "--out", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    said = capsys.readouterr().out
    assert "timed within the limits (TOPP-RA), passed the safety checks" in said
    schema, names, times, q = read_mcap(out)
    assert schema == "trajectory_msgs/msg/JointTrajectory"
    assert names == list(load_robot("puma560").joint_names)
    assert np.allclose(np.diff(times), 1 / 50)  # --rate's default grid


def test_a_fixed_pace_is_checked_and_the_old_form_is_not(policy, tmp_path, capsys):
    out = tmp_path / "fast.csv"
    fast = ["export", str(policy), "--start-deg=-90,0,0", "--seconds-per-step", "0.2"]
    assert main([*fast, "--format", "csv", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("studio export: Refused: policy policy.policy.npz for the Puma560")
    assert "rad/s" in err and "exceeds its limit" in err and not out.exists()
    assert main([*fast, "--out", str(out)]) == 0  # the old form: its own pace, time,q1..q6
    header, rows = read_csv(out)
    assert header == ["time", "q1", "q2", "q3", "q4", "q5", "q6"] and rows.shape[1] == 7


def test_a_policy_for_another_robot_is_refused(policy, tmp_path, capsys):
    out = tmp_path / "x.csv"
    assert main(["export", str(policy), "--robot", "so100", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "was learnt on the Puma560 (the paper's robot)" in err and "\n" not in err
    assert not out.exists()


def test_a_movement_primitive_exports_timed_and_checked(tmp_path, capsys):
    from studio.capture import load_demonstration
    from studio.learning import fit_dmp_policy, save_dmp_policy
    from studio.samples import SAMPLES_DIR

    demo = load_demonstration(SAMPLES_DIR / "sample-reach-2.demo.json")
    path = tmp_path / "dmp.policy.npz"
    save_dmp_policy(path, fit_dmp_policy(demo.times, demo.q_robot, learned_joints=3))
    out = tmp_path / "dmp.csv"
    assert main(["export", str(path), "--format", "csv", "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert said.startswith("the movement primitive") and "passed the safety checks" in said
    header, rows = read_csv(out)
    assert header == ["time", *load_robot("puma560").joint_names]
    assert np.allclose(rows[0, 1:], demo.q_robot[0], atol=1e-6)  # from the demonstration's start


@pytest.fixture(scope="module")
def panda_policy(tmp_path_factory):
    run = tmp_path_factory.mktemp("panda") / "run"
    argv = ["train", "--task", "arm-reach", "--robot", "panda", "--planning", "zero",
            "--episodes", "3", "--experiments", "1", "--out", str(run), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    return run / "policy.policy.npz"


def test_a_panda_policy_starts_within_its_limits_and_takes_a_start_per_joint(
    panda_policy, tmp_path, capsys
):
    # issue 39: the README's export failed, its default start (all 0) outside panda_joint4's range
    panda = load_robot("panda")
    out = tmp_path / "p.csv"
    base = ["export", str(panda_policy), "--robot", "panda", "--format", "csv", "--unchecked"]
    base += ["--max-steps", "5"]
    assert main([*base, "--out", str(out)]) == 0, capsys.readouterr().err
    _, rows = read_csv(out)
    np.testing.assert_allclose(rows[0, 1:], panda.home, atol=1e-6)  # its home pose
    # seven angles, one per joint of the Panda (the seventh, not learned, holds its goal angle)
    seven = "--start-deg=0,-20,0,-100,0,90,30"
    assert main([*base, seven, "--out", str(out)]) == 0, capsys.readouterr().err
    _, rows = read_csv(out)
    np.testing.assert_allclose(np.degrees(rows[0, 1:7]), [0, -20, 0, -100, 0, 90], atol=1e-6)
    assert main([*base, "--start-deg=0,0", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--start-deg has 2 angles; give 6 or 7" in err and "\n" not in err
