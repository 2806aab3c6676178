"""The UR arms' hollow: the column around the first axis their raised arm cannot enter.

The retargeting keeps hand targets out of it (``RobotSpec.hollow``), along a direction that a
hand's noise near the axis does not swing, and the page says so.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.kinematics import HumanArm, Retargeter, load_robot, reachable, tool_reaches
from studio.kinematics._retarget import into_hollow, out_of_hollow
from studio.web.live._pipeline import robot_note

HOLLOW, WIDTH = 0.19, 0.1
FORWARD = np.array([1.0, 0.0])
OFFSETS = st.tuples(st.floats(-0.6, 0.6), st.floats(-0.6, 0.6)).map(np.array)


@settings(max_examples=300, deadline=None)
@given(across=OFFSETS)
def test_an_offset_inside_is_moved_beyond_the_hollow_and_one_outside_stays(across):
    moved = out_of_hollow(across, HOLLOW, WIDTH, FORWARD)
    radius = float(np.linalg.norm(across))
    assert float(np.linalg.norm(moved)) >= HOLLOW
    if radius >= HOLLOW + WIDTH:
        assert np.array_equal(moved, across)
    else:
        assert float(np.linalg.norm(moved)) > radius
    # the tear is the one point (HOLLOW + WIDTH / 2) behind the axis: away from it, a hand
    # offset is found that lands where this one did (the hand guide's way back from a robot)
    if np.linalg.norm(across + (HOLLOW + WIDTH / 2) * FORWARD) > 0.02:
        back = into_hollow(moved, HOLLOW, WIDTH, FORWARD)
        np.testing.assert_allclose(out_of_hollow(back, HOLLOW, WIDTH, FORWARD), moved, atol=1e-3)


def test_a_hand_still_over_the_axis_keeps_its_target_still():
    # a hand held over the shoulder, its reading wandering 2 mm around the axis: moved straight
    # out, its targets would spread round the hollow's whole edge; this way they stay together
    angles = np.linspace(0.0, 2 * math.pi, 36, endpoint=False)
    noise = 0.002 * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    moved = np.array([out_of_hollow(p, HOLLOW, WIDTH, FORWARD) for p in noise])
    spread = np.linalg.norm(moved[:, None] - moved[None], axis=2).max()
    assert spread < 0.01, spread
    radial = HOLLOW * noise / np.linalg.norm(noise, axis=1, keepdims=True)
    assert np.linalg.norm(radial[:, None] - radial[None], axis=2).max() > 2 * HOLLOW - 1e-9


def test_a_ur5_reaches_a_hand_hanging_below_the_shoulder_in_front_of_its_hollow():
    ur5 = load_robot("ur5", geometry=False)
    hanging = HumanArm().neutral
    retargeter = Retargeter(robot=ur5)
    for _ in range(60):  # settle, as a live session does
        q = retargeter.robot_from_human(hanging)
    target = retargeter.hand_target(hanging)
    # its workspace's centre stands in front of the hollow: the hand lands there, not moved
    assert retargeter.pushed_out == 0.0
    assert np.hypot(*target[:2, 3]) > ur5.spec.hollow * ur5.reach
    assert tool_reaches(ur5, q, target)
    assert robot_note(ur5, retargeter) is None
    # an arm stretched back, over the base, is moved out and the page says so
    behind = np.array([-1.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0])
    for _ in range(60):
        retargeter.robot_from_human(behind)
    assert retargeter.pushed_out > 0.1
    note = robot_note(ur5, retargeter)
    assert note is not None and "straight above or below the shoulder" in note, note
    # without the hollow the target lies where no pose of the UR5 reaches
    plain = ur5.scratch_copy()
    plain.spec = dataclasses.replace(ur5.spec, hollow=0.0)
    unmoved = Retargeter(robot=plain).hand_target(hanging)
    assert np.hypot(*unmoved[:2, 3]) < 0.05
    assert not reachable(plain, unmoved)
