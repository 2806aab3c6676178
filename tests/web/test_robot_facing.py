"""An arm whose URDF faces elsewhere than +x (the SO-100's faces -y) is drawn turned to face the
operator, as its targets are turned: the tool drawn is where the retargeting put it."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from studio.kinematics import MeshConfig, Retargeter, load_robot
from studio.web.scene._robot_view import arm_framing, arm_tool, arm_view


def test_the_so100_reaching_ahead_is_drawn_reaching_towards_the_operator():
    arm = load_robot("so100")
    retargeter = Retargeter(robot=arm)
    ahead = np.array([math.pi / 2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # the arm raised forward
    q = retargeter.robot_from_human(ahead)
    tool = arm_tool(arm)(q)
    # the operator stands on +x: the drawn tool is out in front of the base, not off to a side
    assert tool[0] > 2.0 * abs(tool[1])
    scale, pedestal = arm_framing(arm)
    target = retargeter.hand_target(ahead)[:3, 3]
    drawn_target = arm.base_rotation @ target * scale + [0.0, 0.0, pedestal]
    assert np.linalg.norm(tool - drawn_target) < 0.01 * scale  # within the 1 cm it was reached


def test_every_mesh_of_a_turned_arm_is_turned_with_its_tool():
    arm = load_robot("so100")
    view = arm_view(arm, MeshConfig())
    scale, pedestal = arm_framing(arm)
    q = np.clip(arm.home + 0.3, arm.lower, arm.upper)
    data, gdata = arm.model.createData(), arm.visual_model.createData()
    pin.updateGeometryPlacements(arm.model, data, arm.visual_model, gdata, q)
    turn = arm.base_rotation
    for part, pose in zip(view.parts, view.poses(q), strict=True):
        placed = gdata.oMg[int(part.frame)]
        np.testing.assert_allclose(pose[:3, :3], turn @ placed.rotation, atol=1e-9)
        expected = turn @ placed.translation * scale + [0.0, 0.0, pedestal]
        np.testing.assert_allclose(pose[:3, 3], expected, atol=1e-9)
