"""One demonstration contract: a file holds its trajectory and its own goal, every stored field is
read (as every task reads it: ``checked_demonstration``), and bad input is one sentence."""

from __future__ import annotations

import json
import math

import pytest

from studio.capture import DemonstrationError
from studio.motion import checked_demonstration as load_demonstration
from studio.samples import SAMPLES_DIR


@pytest.fixture
def saved(tmp_path):
    """A demonstration as today's studio writes it (a shipped sample, saved again)."""
    demo = load_demonstration(SAMPLES_DIR / "sample-reach-1.demo.json")
    path = demo.save(tmp_path / "take.demo.json")
    return path, json.loads(path.read_text())


def test_the_file_holds_its_trajectory_its_robot_and_its_own_goal(saved):
    path, data = saved
    assert data["version"] == 2 and data["robot"] == "puma560"
    assert "mirror" not in data and "max_allowed" not in data["fit"]  # never read: not written
    assert "goal" not in data["grid"]  # the demonstration's own goal is stored once
    demo = load_demonstration(path)
    assert demo.goal == tuple(data["goal"]) and demo.grid_path == data["grid_path"]


def test_no_stored_field_goes_unread(saved, tmp_path):
    """Garbling any stored field changes what loads, or is refused with a sentence."""
    path, data = saved
    original = load_demonstration(path).to_dict()
    fields = [(k,) for k in data] + [("fit", k) for k in data["fit"]]
    for key in fields:
        garbled = json.loads(json.dumps(data))
        target = garbled
        for part in key[:-1]:
            target = target[part]
        target[key[-1]] = "?"
        other = tmp_path / "garbled.demo.json"
        other.write_text(json.dumps(garbled))
        try:
            loaded = load_demonstration(other).to_dict()
        except DemonstrationError as err:
            assert len(str(err).splitlines()) == 1
            continue
        assert loaded != original, f"{key} is stored but never read"


def _bad(saved, tmp_path, change) -> str:
    _, data = saved
    change(data)
    path = tmp_path / "bad.demo.json"
    path.write_text(json.dumps(data))
    with pytest.raises(DemonstrationError) as err:
        load_demonstration(path)
    assert err.value.reason == "bad_file" and len(str(err.value).splitlines()) == 1
    return str(err.value)


def test_a_demonstration_for_another_robot_is_one_sentence(saved, tmp_path):
    said = _bad(saved, tmp_path, lambda d: d.update(robot="so100"))
    assert "so100" in said and "puma560" in said


def test_a_demonstration_with_another_number_of_joints_is_one_sentence(saved, tmp_path):
    def seven(d):  # 6 rows of 7 angles used to be read silently as 7 rows of 6
        rows = d["trajectory"]["q_robot"][:6]
        d["trajectory"]["q_robot"] = [[*r, 0.0] for r in rows]
        d["trajectory"]["t"] = d["trajectory"]["t"][:6]

    said = _bad(saved, tmp_path, seven)
    assert "7 joint angles" in said and "another robot" in said


def test_nan_samples_are_one_sentence(saved, tmp_path):
    said = _bad(saved, tmp_path, lambda d: d["trajectory"]["q_robot"][3].__setitem__(1, math.nan))
    assert "NaN" in said and "sample 4" in said


@pytest.mark.parametrize("keep", [0, 1])
def test_a_zero_length_cut_is_one_sentence(saved, tmp_path, keep):
    def cut(d):
        d["trajectory"]["q_robot"] = d["trajectory"]["q_robot"][:keep]
        d["trajectory"]["t"] = d["trajectory"]["t"][:keep]

    assert "zero length" in _bad(saved, tmp_path, cut)
