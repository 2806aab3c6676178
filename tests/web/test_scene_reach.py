"""The scene shows the operator's reach and the robot's workspace, so the person sees where to
move (issue 39): two see-through balls, hidden until asked for, that follow the robot chosen."""

from __future__ import annotations

import numpy as np
import pytest
import viser

from studio.kinematics import HumanArm, HumanBody, Retargeter, load_robot, robot_names
from studio.web.scene._model import SceneLayout
from studio.web.scene._reach import robot_workspace_ball
from studio.web.scene._robot_view import arm_framing
from studio.web.scene._scene import StudioScene
from tests.conftest import free_port
from tests.web.conftest import wait_for

LOAD_S = 120.0
"""Reading a robot's meshes takes seconds alone, far longer on a shared machine."""

OUTSTRETCHED = np.array([np.pi / 2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
"""The operator's arm raised forward, straight: their hand as far out as it goes."""


@pytest.fixture(scope="module")
def scene():
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    sc = StudioScene(server, body=HumanBody("right"), layout=SceneLayout(rate_hz=100.0))
    yield sc
    sc.close()
    server.stop()


def on_ball(point: np.ndarray, ball: tuple[np.ndarray, float]) -> float:
    """How far ``point`` is from the ball's surface (m)."""
    centre, radius = ball
    return abs(float(np.linalg.norm(point - centre)) - radius)


def test_hidden_until_asked_then_both_shown_and_the_toggle_agrees(scene):
    handles = scene._reach_handles
    assert set(handles) == {"operator", "robot"} and not scene.reach_shown
    assert not any(h.visible for h in handles.values())
    scene.show_reach(True)
    assert scene.reach_shown and scene._reach_toggle.value
    assert all(h.visible for h in handles.values())
    scene._reach_toggle.value = False  # the checkbox in the scene's panel
    scene.show_reach(scene._reach_toggle.value)
    assert not any(h.visible for h in handles.values())


def test_the_operators_ball_is_their_reach_around_the_taped_shoulder(scene):
    arm = HumanArm(side=scene.side)
    hand = scene.to_world(arm.forward(OUTSTRETCHED).hand[:3, 3])
    assert on_ball(hand, scene.reach_balls()["operator"]) < 1e-6
    bent = OUTSTRETCHED.copy()
    bent[3] = 1.5  # the elbow bent: the hand inside
    inside = scene.to_world(arm.forward(bent).hand[:3, 3])
    centre, radius = scene.reach_balls()["operator"]
    assert np.linalg.norm(inside - centre) < radius - 0.1


@pytest.mark.parametrize("name", robot_names())
def test_the_outstretched_hand_lands_on_each_robots_ball(name):
    """Where the retargeting places an outstretched hand, in the world as the scene frames the
    robot, lies on the ball drawn for it: the ball is the workspace the reach maps into."""
    arm = load_robot(name, geometry=False)
    target = Retargeter(robot=arm).hand_target(OUTSTRETCHED)[:3, 3]
    scale, pedestal = arm_framing(arm)
    world = arm.base_rotation @ target * scale + np.array([0.0, 0.0, pedestal])
    # within a millimetre of the robot's own size (the soft limits bend the target by less)
    assert on_ball(world, robot_workspace_ball(name)) < 1e-3 * scale


def test_the_robots_ball_follows_the_robot_chosen(scene):
    puma = scene.reach_balls()["robot"]
    np.testing.assert_allclose(puma[0], robot_workspace_ball("puma560")[0])
    scene.set_robot(load_robot("so100"))
    so100 = robot_workspace_ball("so100")
    assert wait_for(
        lambda: np.allclose(scene.reach_balls()["robot"][0], so100[0]), timeout=LOAD_S
    ), scene.robot_notes()
    assert scene.robot_name == "so100"
    centre, radius = scene.reach_balls()["robot"]
    assert radius == pytest.approx(so100[1])
    assert not np.allclose(centre, puma[0]) or radius != pytest.approx(puma[1])
    handle = scene._reach_handles["robot"]
    np.testing.assert_allclose(handle.position, centre)
    assert handle.radius == pytest.approx(radius)
