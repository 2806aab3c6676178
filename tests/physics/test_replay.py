"""A trajectory replayed in MuJoCo: a gentle one completes, one into the table reports the
contact, one too fast saturates the motors."""

from __future__ import annotations

import numpy as np
import pytest

from studio.export import physics_model, simulate_trajectory
from studio.kinematics import TABLE, load_robot
from studio.physics import JSON_KEYS, PhysicsError, simulate

from .motions import smooth_move


@pytest.fixture(scope="module")
def panda(physics_cache):
    arm = load_robot("panda")
    return arm, physics_model(arm, physics_cache)


def test_a_gentle_move_completes_with_small_errors(panda):
    arm, model = panda
    end = arm.home + np.array([0.3, 0.2, -0.2, 0.3, 0.2, -0.2, 0.3])
    times, q = smooth_move(arm.home, end, 2.0)
    report = simulate(model, times, q)
    assert report.completed
    assert report.max_joint_error_rad < 5e-3
    assert report.max_tool_error_m < 2e-3
    assert report.saturated_samples == 0
    assert report.contacts == ()
    assert list(report.as_json()) == list(JSON_KEYS)


def test_a_move_into_the_table_reports_the_contact(panda):
    arm, model = panda
    end = arm.home.copy()
    end[1], end[3] = 1.6, -0.5  # the hand 11 cm below the table top, Pinocchio says
    assert arm.table_contacts(end)
    times, q = smooth_move(arm.home, end, 2.0)
    report = simulate(model, times, q)
    on_table = [c for c in report.contacts if c.link_b == TABLE]
    assert on_table, report.contacts
    assert {c.link_a for c in on_table} <= {c.link_a for c in arm.table_contacts(end)}
    first = min(c.first_sample for c in on_table)
    assert not arm.table_contacts(q[max(first - 5, 0)])  # it touched when the plan reached it
    assert not report.completed, "the table stops the arm short of the end"
    assert report.as_json()["contacts"][0]["kind"] == "table"


def test_a_move_too_fast_for_the_motors_saturates_them(panda):
    arm, model = panda
    end = arm.home + np.array([1.5, 0.8, 0.0, 0.5, 0.0, 0.0, 0.0])
    times, q = smooth_move(arm.home, end, 0.3)
    report = simulate(model, times, q)
    assert report.saturated_samples > 0
    assert report.first_saturated_sample is not None
    assert "panda_joint1" in report.saturated_joints
    slow_times, slow_q = smooth_move(arm.home, end, 4.0)
    assert simulate(model, slow_times, slow_q).saturated_samples == 0, "slowed, it keeps up"


def test_joints_of_another_robot_are_refused_in_one_sentence(physics_cache):
    arm = load_robot("panda")
    times, q = smooth_move(arm.home, arm.home, 1.0)
    with pytest.raises(Exception, match="are not the Franka Emika Panda's") as err:
        simulate_trajectory(arm, times, q, names=load_robot("ur5").joint_names, cache=physics_cache)
    assert "give the --robot" in str(err.value)


@pytest.mark.parametrize(
    ("times", "q", "problem"),
    [
        ([0.0, 1.0], np.zeros((2, 6)), "has 7 joints"),
        ([0.0, 0.0], np.zeros((2, 7)), "do not increase"),
        ([0.0, 1.0], np.full((2, 7), np.nan), "NaN"),
        ([0.0], np.zeros((1, 7)), "at least 2 samples"),
    ],
)
def test_a_malformed_trajectory_is_refused_in_one_sentence(panda, times, q, problem):
    _, model = panda
    with pytest.raises(PhysicsError, match=problem):
        simulate(model, times, q)
