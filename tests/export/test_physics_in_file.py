"""``studio export`` replays what it writes in MuJoCo and states the report in the file: the
CSV's comment lines, the MCAP's metadata, the LeRobot ``info.json``."""

from __future__ import annotations

import json

import numpy as np
import pytest
from mcap.reader import make_reader

from studio.export import Motion, export_motion, read_trajectory
from studio.kinematics import load_robot
from tests.physics.motions import smooth_move


@pytest.fixture(scope="module")
def motion():
    arm = load_robot("panda")
    times, q = smooth_move(arm.home, arm.home + 0.2, 1.5, rate_hz=50.0)
    return Motion("demonstration", "gentle", arm, times, q, True, 50.0)


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("physics-cache")


def test_the_csv_states_the_report_in_its_comment_lines(motion, cache, tmp_path):
    done = export_motion(motion, "csv", tmp_path / "m.csv", simulate=True, cache=cache)
    assert done.physics is not None and done.physics.completed
    notes = read_trajectory(tmp_path / "m.csv").notes
    assert any(n.startswith("physics (MuJoCo, panda") and "completed" in n for n in notes)
    assert "saturation: none" in notes and "contacts: none (self or table)" in notes


def test_without_simulate_the_file_states_no_physics(motion, tmp_path):
    done = export_motion(motion, "csv", tmp_path / "m.csv")
    assert done.physics is None
    assert not any(n.startswith("physics") for n in read_trajectory(tmp_path / "m.csv").notes)


def test_the_mcap_states_the_report_in_its_metadata(motion, cache, tmp_path):
    done = export_motion(motion, "mcap", tmp_path / "m.mcap", simulate=True, cache=cache)
    with open(tmp_path / "m.mcap", "rb") as f:
        meta = {m.name: m.metadata for m in make_reader(f).iter_metadata()}["teach_studio"]
    assert json.loads(meta["physics_json"]) == done.physics.as_json()
    assert meta["physics"].startswith("physics (MuJoCo, panda")


def test_the_lerobot_info_states_the_report(motion, cache, tmp_path):
    done = export_motion(motion, "lerobot", tmp_path / "m", simulate=True, cache=cache)
    info = json.loads((tmp_path / "m" / "meta" / "info.json").read_text())
    physics = info["teach_studio"]["physics"]
    assert physics["report"] == done.physics.as_json()
    assert physics["report"]["completed"] is True


def test_a_motion_the_motors_cannot_follow_is_said_so_in_the_file(cache, tmp_path):
    arm = load_robot("panda")
    times, q = smooth_move(arm.home, arm.home + np.array([1.5, 0.8, 0, 0.5, 0, 0, 0]), 0.3)
    fast = Motion("demonstration", "fast", arm, times, q, True, 100.0)
    export_motion(fast, "csv", tmp_path / "f.csv", unchecked=True, simulate=True, cache=cache)
    notes = read_trajectory(tmp_path / "f.csv").notes
    assert any(n.startswith("saturation:") and "panda_joint1" in n for n in notes), notes
