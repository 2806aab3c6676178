"""The MuJoCo model is the studio's robot: the same kinematics, joints, limits and contacts."""

from __future__ import annotations

import numpy as np
import pytest

from studio.export import physics_model
from studio.kinematics import TABLE, load_robot, robot_names

FK_TOLERANCE_M = 1e-3
"""Issue 39: MuJoCo's forward kinematics within 1 mm of Pinocchio's."""


@pytest.mark.parametrize("name", robot_names())
def test_mujoco_and_pinocchio_put_the_tool_at_the_same_pose(name, physics_cache):
    arm = load_robot(name)
    model = physics_model(arm, physics_cache)
    rng = np.random.default_rng(7)
    q = rng.uniform(arm.lower, arm.upper, size=(50, arm.nq))
    got = model.tool_poses(q)
    for row, pose in zip(q, got, strict=True):
        want = arm.forward(row)
        assert np.linalg.norm(pose[:3, 3] - want[:3, 3]) <= FK_TOLERANCE_M
        # the same orientation: every axis within 1 mm at 1 m
        assert np.abs(pose[:3, :3] - want[:3, :3]).max() <= FK_TOLERANCE_M


@pytest.mark.parametrize("name", robot_names())
def test_the_model_has_the_arms_joints_limits_and_force_limits(name, physics_cache):
    arm = load_robot(name)
    model = physics_model(arm, physics_cache)
    mj = model.model
    assert mj.nq == arm.nq, "fingers and grippers are locked as the studio locks them"
    assert [mj.joint(i).name for i in range(mj.njnt)] == list(arm.joint_names)
    np.testing.assert_allclose(mj.jnt_range[:, 0], arm.hard_lower, atol=1e-9)
    np.testing.assert_allclose(mj.jnt_range[:, 1], arm.hard_upper, atol=1e-9)
    effort = np.array(arm.model.effortLimit)
    limited = effort > 0
    np.testing.assert_allclose(mj.jnt_actfrcrange[limited, 1], effort[limited])
    assert np.all(mj.jnt_actfrclimited[limited])
    assert np.all(mj.opt.gravity == [0.0, 0.0, -9.81])
    assert mj.geom(TABLE).size[0] == 0.0, "the table is the whole plane of the base"


def test_the_table_touches_only_links_after_the_first_joint(physics_cache):
    """The links the first joint turns about the vertical stand on the table (the studio's rule):
    the table never reports them, even though the base's meshes reach down to it."""
    arm = load_robot("panda")
    mj = physics_model(arm, physics_cache).model
    table = mj.geom(TABLE).id
    for g in range(mj.ngeom):
        if g == table:
            continue
        body = mj.body(mj.geom_bodyid[g]).name
        touches = bool(mj.geom_conaffinity[g] & mj.geom_contype[table])
        assert touches == (body not in ("panda_link0", "panda_link1")), body
