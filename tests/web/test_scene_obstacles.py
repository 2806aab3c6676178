"""The scene's obstacle boxes: placed for the next run with a handle each, moved by a drag, and a
watched run's drawn beside them (issue 40)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from studio.kinematics import Obstacle
from studio.web.scene._obstacles import SceneObstacles, robot_frame


class _Handle:
    def __init__(self, name: str, **kw: object) -> None:
        self.name, self.kw, self.callbacks, self.removed = name, kw, [], False
        self.position = kw.get("position")

    def on_update(self, callback) -> None:
        self.callbacks.append(callback)

    def remove(self) -> None:
        self.removed = True


class _Scene:
    def __init__(self) -> None:
        self.nodes: dict[str, _Handle] = {}

    def add_transform_controls(self, name: str, **kw: object) -> _Handle:
        self.nodes[name] = _Handle(name, **kw)
        return self.nodes[name]

    def add_box(self, name: str, **kw: object) -> _Handle:
        self.nodes[name] = _Handle(name, **kw)
        return self.nodes[name]


def _boxes() -> tuple[SceneObstacles, _Scene]:
    scene = _Scene()
    return SceneObstacles(SimpleNamespace(scene=scene)), scene


BOX = Obstacle((0.6, 0.4, 0.9), (0.15, 0.15, 0.15))


def test_a_dragged_handle_moves_its_box_and_keeps_its_size():
    boxes, scene = _boxes()
    boxes.edit([BOX])
    handle = scene.nodes["/obstacles/edit/0"]
    assert handle.kw["disable_rotations"] is True  # moved, not turned: boxes stay axis-aligned
    assert scene.nodes["/obstacles/edit/0/box"].kw["dimensions"] == BOX.size
    handle.position = (0.5, -0.2, 1.1)
    for callback in handle.callbacks:
        callback(SimpleNamespace(target=handle))
    assert boxes.edited() == [Obstacle((0.5, -0.2, 1.1), BOX.size)]
    handle.position = (float("nan"), 0.0, 0.0)  # not a place: the box stays
    for callback in handle.callbacks:
        callback(SimpleNamespace(target=handle))
    assert boxes.edited() == [Obstacle((0.5, -0.2, 1.1), BOX.size)]


def test_placing_again_replaces_the_boxes_and_a_watched_runs_are_drawn_apart():
    boxes, scene = _boxes()
    boxes.edit([BOX, BOX])
    first = scene.nodes["/obstacles/edit/1"]
    boxes.edit([])
    assert first.removed and boxes.edited() == []
    boxes.show_watched([BOX])
    assert boxes.watched_count() == 1
    assert scene.nodes["/obstacles/watched/0"].kw["position"] == BOX.centre
    boxes.show_watched(())
    assert boxes.watched_count() == 0


@pytest.mark.parametrize("robot", ["ur5", "so100"])
def test_boxes_are_drawn_where_their_robot_is_drawn_and_a_drag_comes_back(robot):
    """A box is in its robot's base frame; a robot other than the Puma560 is drawn raised on a
    pedestal (the SO-100 also turned and enlarged), so its box is drawn there, and a drag comes
    back into that base frame."""
    turn, scale, lift = robot_frame(robot)
    assert lift[2] > 0.2  # drawn at the base frame's origin, the box would miss the arm
    boxes, scene = _boxes()
    box = Obstacle((0.2, 0.1, 0.3), (0.04, 0.06, 0.08))
    boxes.edit([box], robot)
    handle = scene.nodes["/obstacles/edit/0"]
    assert np.allclose(handle.kw["position"], turn @ np.array(box.centre) * scale + lift)
    assert np.allclose(
        scene.nodes["/obstacles/edit/0/box"].kw["dimensions"], np.array(box.size) * scale
    )
    handle.position = tuple(turn @ np.array([0.25, -0.1, 0.2]) * scale + lift)
    for callback in handle.callbacks:
        callback(SimpleNamespace(target=handle))
    [moved] = boxes.edited()
    assert np.allclose(moved.centre, (0.25, -0.1, 0.2)) and moved.size == box.size
    boxes.show_watched([box], robot)
    assert np.allclose(scene.nodes["/obstacles/watched/0"].kw["position"], handle.kw["position"])


def test_the_placed_boxes_follow_the_robot_drawn():
    boxes, scene = _boxes()
    boxes.edit([BOX])
    assert scene.nodes["/obstacles/edit/0"].kw["position"] == BOX.centre  # the Puma560's frame
    boxes.follow_robot("ur5")
    lift = robot_frame("ur5")[2]
    assert np.allclose(scene.nodes["/obstacles/edit/0"].kw["position"], np.array(BOX.centre) + lift)
    assert boxes.edited() == [BOX]  # the same place in the base frame the run is trained in


def test_the_page_export_of_a_watched_rollout_is_checked_against_its_tasks_boxes(tmp_path):
    """The page's rollout export (``/api/robot/export/rollout.mcap``) refuses a rollout that
    passes through one of its task's boxes, as ``studio export`` does, and writes nothing."""
    from studio.export import SafetyError
    from studio.kinematics import load_robot
    from studio.web.services import export_rollout

    reach = np.radians([0.0, 45.0, -90.0, 0.0, 0.0, 0.0])
    box = Obstacle(tuple(load_robot("puma560").forward(reach)[:3, 3]), (0.02, 0.02, 0.02))
    swing = np.repeat(reach[None], 13, axis=0)
    swing[:, 0] = np.radians(np.linspace(-60, 60, 13))  # the tool through the box at joint 1 = 0
    times = np.arange(13, dtype=float)
    with pytest.raises(SafetyError) as refused:
        export_rollout(
            tmp_path / "swing.policy.npz", "puma560", "swing", times, swing, obstacles=(box,)
        )
    assert "obstacle 1" in str(refused.value)


@pytest.mark.parametrize("robot", ["puma560", "so100"])
def test_a_new_box_stands_beside_any_robot_where_it_stands_beside_the_puma560(robot):
    """ "Add obstacle" puts a box at one place in the scene, whatever robot is drawn: in the
    SO-100's base frame (turned, drawn 3x enlarged) that is a smaller box, nearer its base."""
    from studio.web.scene._obstacles import NEW_BOX

    boxes, scene = _boxes()
    new = boxes.new_box(robot)
    boxes.edit([new], robot)
    assert np.allclose(scene.nodes["/obstacles/edit/0"].kw["position"], NEW_BOX.centre)
    assert np.allclose(scene.nodes["/obstacles/edit/0/box"].kw["dimensions"], NEW_BOX.size)
    if robot != "puma560":
        assert max(new.size) < 0.06 and np.linalg.norm(new.centre) < 0.5
