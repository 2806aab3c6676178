"""The scene plays a policy's rollout on the policy's own robot when that robot is drawn, with
the tool traced by that robot's kinematics."""

from __future__ import annotations

import numpy as np
import pytest
import viser

from studio.kinematics import HumanBody, load_robot
from studio.web.scene._scene import SceneLayout, StudioScene
from tests.conftest import free_port
from tests.web.conftest import wait_for


@pytest.fixture
def scene():
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    sc = StudioScene(server, body=HumanBody("right"), layout=SceneLayout(rate_hz=100.0))
    yield sc
    sc.close()
    server.stop()


def test_a_rollout_plays_on_its_own_robot_when_drawn(scene):
    arm = load_robot("so100")
    scene.set_robot(arm)
    assert wait_for(lambda: scene.robot_name == "so100", timeout=120.0)
    q = np.tile(arm.home, (21, 1))
    q[:, 0] = np.linspace(arm.lower[0] / 2, arm.upper[0] / 2, 21)
    scene.play_trajectory(np.linspace(0.0, 0.2, 21), q, robot="so100")
    assert wait_for(lambda: not scene.playing, timeout=10.0)
    np.testing.assert_allclose(scene.current_q_robot(), q[-1], atol=1e-9)
    view = scene._view
    np.testing.assert_allclose(scene._trace_marks.points[-1], view.tool(q[-1]), atol=1e-4)
    # the SO-100's meshes stand where its own kinematics put them at the rollout's end
    for handle, pose in zip(scene._robot_handles, view.poses(q[-1]), strict=True):
        np.testing.assert_allclose(handle.position, pose[:3, 3], atol=1e-6)
