"""``studio simulate FILE --robot NAME [--json]``: an exported file replayed in physics, and
bad inputs refused in one sentence with exit status 2."""

from __future__ import annotations

import json

import numpy as np
import pytest

from studio.cli import main
from studio.export import read_trajectory, write_csv, write_mcap
from studio.kinematics import load_robot
from studio.physics import JSON_KEYS
from tests.physics.motions import smooth_move


@pytest.fixture(scope="module")
def physics_cache(tmp_path_factory):
    return tmp_path_factory.mktemp("physics-cache")


@pytest.fixture(scope="module")
def gentle(tmp_path_factory):
    """A gentle Panda move written as CSV and as MCAP (as `studio export` writes them)."""
    arm = load_robot("panda")
    times, q = smooth_move(arm.home, arm.home + 0.2, 1.5)
    folder = tmp_path_factory.mktemp("simulate")
    write_csv(folder / "gentle.csv", arm.joint_names, times, q, ["a note"])
    start = 1_765_000_000_123_456_789  # a real time, as exports stamp them
    for name, states in (("gentle.mcap", False), ("states.mcap", True)):
        write_mcap(
            folder / name, arm.joint_names, times, q, states=states, metadata={}, start_ns=start
        )
    return folder, times, q


@pytest.mark.parametrize("name", ["gentle.csv", "gentle.mcap", "states.mcap"])
def test_the_export_formats_read_back_whole(gentle, name):
    folder, times, q = gentle
    trajectory = read_trajectory(folder / name)
    assert trajectory.names == load_robot("panda").joint_names
    np.testing.assert_allclose(trajectory.times, times, atol=1e-9)
    np.testing.assert_allclose(trajectory.q, q, rtol=1e-8)


def test_json_is_one_object_with_exactly_the_keys(gentle, capsys, physics_cache):
    folder, _, _ = gentle
    code = main(
        ["simulate", str(folder / "gentle.mcap"), "--robot", "panda", "--json",
         "--data-dir", str(physics_cache)]
    )  # fmt: skip
    assert code == 0
    report = json.loads(capsys.readouterr().out)
    assert list(report) == list(JSON_KEYS)
    assert report["completed"] is True and report["contacts"] == []
    assert report["saturated_samples"] == 0
    assert 0 <= report["max_tool_error_m"] < 0.002


def test_the_human_report_says_the_verdict(gentle, capsys, physics_cache):
    folder, _, _ = gentle
    args = ["simulate", str(folder / "gentle.csv"), "--robot", "panda"]
    assert main([*args, "--data-dir", str(physics_cache)]) == 0
    out = capsys.readouterr().out
    assert "completed" in out and "saturation: none" in out and "contacts: none" in out


@pytest.mark.parametrize(
    ("name", "content", "robot", "problem"),
    [
        ("missing.csv", None, "panda", "cannot open"),
        ("gentle.csv", "", "ur5", "are not the Universal Robots UR5's"),
        ("gentle.csv", "", "nosuchrobot", "Unknown robot"),
        ("bad.csv", "time,a\n1,x\n", "panda", "not numbers"),
        ("noheader.csv", "1,2,3\n", "panda", "header"),
        ("bad.mcap", "not an mcap", "panda", "cannot be read as MCAP"),
        ("traj.txt", "x", "panda", "neither a .csv nor a .mcap"),
    ],
)
def test_a_bad_input_is_one_sentence_and_exit_2(gentle, capsys, name, content, robot, problem):
    folder, _, _ = gentle
    path = folder / name
    if content:
        path.write_text(content)
    args = ["simulate", str(path), "--robot", robot, "--json", "--data-dir", str(folder)]
    assert main(args) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert problem in captured.err and captured.err.count("\n") == 1, captured.err


def test_a_policy_rollouts_q_columns_are_the_robots_joints_in_order(tmp_path, capsys):
    """``studio export POLICY`` alone writes ``time,q1..q6``: simulated on the Puma560."""
    arm = load_robot("puma560")
    times, q = smooth_move(arm.home, arm.home + 0.1, 1.0)
    names = [f"q{i + 1}" for i in range(arm.nq)]
    write_csv(tmp_path / "rollout.csv", names, times, q)
    args = ["simulate", str(tmp_path / "rollout.csv"), "--robot", "puma560", "--json"]
    assert main([*args, "--data-dir", str(tmp_path)]) == 0
    assert json.loads(capsys.readouterr().out)["completed"] is True


def test_an_obstacle_in_the_way_is_reported_as_a_contact(tmp_path, capsys, physics_cache):
    """``studio simulate --obstacle``: the box is a MuJoCo geom, and the arm swinging through it
    touches it; the same file without it reports no contact with a box."""
    arm = load_robot("puma560")
    reach = np.radians([0.0, 45.0, -90.0, 0.0, 0.0, 0.0])
    start, end = reach.copy(), reach.copy()
    start[0], end[0] = np.radians(-40), np.radians(40)
    times, q = smooth_move(start, end, 2.0)
    write_csv(tmp_path / "swing.csv", arm.joint_names, times, q, [])
    x, y, z = arm.forward(reach)[:3, 3]
    argv = ["simulate", str(tmp_path / "swing.csv"), "--robot", "puma560", "--json"]
    argv += ["--data-dir", str(physics_cache)]
    assert main([*argv, f"--obstacle={x},{y},{z},0.05,0.05,0.05"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert list(report) == list(JSON_KEYS)
    boxes = [c for c in report["contacts"] if c["kind"] == "obstacle"]
    assert boxes and boxes[0]["link_b"] == "obstacle_1"
    assert main(argv) == 0
    report = json.loads(capsys.readouterr().out)
    assert not [c for c in report["contacts"] if c["kind"] == "obstacle"]
    argv.remove("--json")  # a box away from the swing: the sentences say it was checked
    assert main([*argv, "--obstacle=-0.6,-0.6,0.3,0.1,0.1,0.1"]) == 0
    out = capsys.readouterr().out
    assert "contacts: none (self, table or the 1 obstacle box(es))" in out
