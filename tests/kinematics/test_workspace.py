"""The operator's reach mapped into each robot's workspace (issue 39).

A person's natural reach is the robot's natural reach: on every arm the studio offers, the hand
targets of the three sample demonstrations and of random arm poses lie within the robot's reach
(none drawn back), above the table, and the map is undone exactly where the simulator asks for
the arm that puts the robot somewhere.
"""

from __future__ import annotations

import numpy as np
import pytest

from studio.capture import human_angles, read_any_recording
from studio.kinematics import HumanArm, Retargeter, load_robot, robot_names
from studio.kinematics._workspace import Workspace
from studio.motion import checked_demonstration
from studio.samples import SAMPLES_DIR

ARMS = [name for name in robot_names() if name != "puma560"]


def _sample(k: int) -> tuple[np.ndarray, str]:
    demo = checked_demonstration(SAMPLES_DIR / f"sample-reach-{k}.demo.json")
    rec = read_any_recording(demo.recording)
    return human_angles(rec, rec.segment(demo.t0, demo.t1)), rec.side


@pytest.mark.parametrize("name", ARMS)
def test_no_frame_of_the_samples_goes_beyond_any_arms_reach(name):
    robot = load_robot(name, geometry=False)
    for k in (1, 2, 3):
        q_human, side = _sample(k)
        retargeter = Retargeter(robot=robot, arm=HumanArm(side=side))
        tolerance = retargeter.config.reach_tolerance
        drawn = np.array([retargeter._target(q)[1] for q in q_human[::3]])
        assert (drawn > tolerance).mean() <= 0.05, f"sample-reach-{k}: {drawn.max():.3f} m"


@pytest.mark.parametrize("name", ["panda", "ur5", "so101"])
def test_an_outstretched_arm_reaches_the_workspaces_edge_and_never_below_the_table(name):
    robot = load_robot(name, geometry=False)
    retargeter = Retargeter(robot=robot)
    space = retargeter.workspace
    rng = np.random.default_rng(0)
    for q in rng.uniform(retargeter.arm.lower, retargeter.arm.upper, (60, 7)):
        target = retargeter.hand_target(q)[:3, 3]
        assert target[2] >= retargeter.config.floor_height
        assert np.linalg.norm(target - robot.shoulder) <= space.radius + 1e-9
    for direction in np.eye(3):
        np.testing.assert_allclose(space.share(space.into(direction)), 1.0)
        np.testing.assert_allclose(space.out_of(space.into(0.5 * direction)), 0.5 * direction)


def test_the_map_keeps_directions_and_only_scales_lengths():
    space = Workspace.of(load_robot("panda", geometry=False), 0.7, 0.1)
    rng = np.random.default_rng(1)
    for reach in rng.normal(size=(40, 3)):
        reach *= 0.9 / np.linalg.norm(reach)
        placed = space.into(reach) - space.centre
        cosine = placed @ reach / np.linalg.norm(placed) / np.linalg.norm(reach)
        assert cosine == pytest.approx(1.0)
