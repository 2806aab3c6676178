"""The scene's obstacle boxes: placed for the next run with a handle each, moved by a drag, and a
watched run's drawn beside them (issue 40)."""

from __future__ import annotations

from types import SimpleNamespace

from studio.kinematics import Obstacle
from studio.web.scene._obstacles import SceneObstacles


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
