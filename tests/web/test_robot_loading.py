"""Another robot's meshes are read and simplified in a child process: the live scene, the fit
and the page's requests never wait for them (the first switch to the Panda froze them for 20 s)."""

from __future__ import annotations

import numpy as np

from studio.kinematics import MeshConfig, Puma560, load_robot
from studio.web.scene import _robot_view, _simplify
from studio.web.scene._robot_view import RobotViews, arm_view
from tests.web.conftest import wait_for


def test_a_robots_meshes_are_simplified_outside_the_studios_process(tmp_path, monkeypatch):
    arm = load_robot("so100")
    here = arm_view(arm, MeshConfig())  # read and simplified in this process, to compare

    def not_here(*args, **kwargs):
        raise AssertionError("the meshes were simplified in the studio's own process")

    monkeypatch.setattr(_simplify, "robot_meshes", not_here)
    views = RobotViews(Puma560(), MeshConfig(), cache=tmp_path)
    drawn: list[_robot_view.RobotView] = []
    views.request(arm, drawn.append)
    assert wait_for(lambda: bool(drawn) or bool(views.failed), 300), "no view was built"
    assert not views.failed, views.failed
    (view,) = drawn
    assert view.name == "so100" and len(view.parts) == len(here.parts)
    for a, b in zip(view.parts, here.parts, strict=True):
        assert a.name == b.name and a.frame == b.frame
        np.testing.assert_array_equal(a.faces, b.faces)
        np.testing.assert_allclose(a.vertices, b.vertices)
    assert list(tmp_path.glob("so100-*.npz"))  # kept for the next studio
