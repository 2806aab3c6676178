"""Obstacle boxes in the scene: the ones a person places for a run, and a watched run's.

A box (:class:`studio.kinematics.Obstacle`) lives in its robot's base frame; the scene draws it
where that robot is drawn (:func:`robot_frame`: a robot other than the Puma560 is turned to face
the operator, enlarged and raised on a pedestal), so the box stands where the task checks it
against the arm. The training form's boxes belong to the robot drawn (the one a run from the form
trains) and are drawn with a handle each (viser's transform controls, moved, not turned):
dragging one moves its box, and :meth:`SceneObstacles.edited` gives the boxes where they stand
now, for the run the form starts. A watched run's boxes are drawn see-through beside them, on
the policy's robot, without handles.
"""

from __future__ import annotations

import functools
import threading

import numpy as np
import viser

from studio.kinematics import DEFAULT_ROBOT, KinematicsError, Obstacle, load_robot

from ._robot_view import arm_framing, wxyz_of

EDIT_COLOR = (235, 140, 40)
"""The boxes placed for the next run."""
WATCH_COLOR = (200, 60, 60)
"""A watched run's boxes."""
OPACITY = 0.45
"""See-through, so the arm shows inside a box it touches."""
HANDLE_SCALE = 0.25
NEW_BOX = Obstacle((0.6, 0.4, 0.9), (0.15, 0.15, 0.15))
"""Where "Add obstacle" puts a box, in the scene (the Puma560's base frame): 15 cm a side, in
front of the robot and to its left, clear of the Puma560's default goal; another robot's new box
is put at the same place in the scene (:meth:`SceneObstacles.new_box`)."""


@functools.lru_cache(maxsize=8)
def robot_frame(robot: str) -> tuple[np.ndarray, float, np.ndarray]:
    """``(turn, scale, lift)``: where the scene draws ``robot``'s base frame, as it draws the
    robot (:func:`._robot_view.arm_framing`): a point ``p`` of that frame is drawn at
    ``turn @ p * scale + lift`` (the Puma560's: the identity, 1 and none)."""
    arm = load_robot(robot, geometry=False)
    scale, pedestal = arm_framing(arm)
    return np.asarray(arm.base_rotation, dtype=float), scale, np.array([0.0, 0.0, pedestal])


def _drawn(box: Obstacle, robot: str) -> dict[str, object]:
    """Where and how big the scene draws ``box`` of ``robot``."""
    turn, scale, lift = robot_frame(robot)
    return {
        "position": tuple(float(v) for v in turn @ np.asarray(box.centre) * scale + lift),
        "wxyz": tuple(float(v) for v in wxyz_of(turn)),
        "dimensions": tuple(float(s) * scale for s in box.size),
    }


class SceneObstacles:
    """The boxes the scene draws: those placed for the next run and a watched run's."""

    def __init__(self, server: viser.ViserServer) -> None:
        self.server = server
        self._lock = threading.Lock()
        self._edited: list[Obstacle] = []
        self._robot = DEFAULT_ROBOT  # the robot the placed boxes are drawn on
        self._edit_nodes: list[viser.SceneNodeHandle] = []
        self._watch_nodes: list[viser.SceneNodeHandle] = []

    def edited(self) -> list[Obstacle]:
        """The boxes placed for the next run, where their handles stand now."""
        with self._lock:
            return list(self._edited)

    def edit(self, boxes: list[Obstacle], robot: str | None = None) -> list[Obstacle]:
        """Draw ``boxes`` (in ``robot``'s base frame; None: the robot they were drawn on) as the
        ones placed for the next run, each with a handle to move it."""
        with self._lock:
            for node in self._edit_nodes:
                node.remove()
            self._edit_nodes = []
            self._edited = list(boxes)
            self._robot = robot or self._robot
            for i, box in enumerate(boxes):
                drawn = _drawn(box, self._robot)
                handle = self.server.scene.add_transform_controls(
                    f"/obstacles/edit/{i}",
                    scale=HANDLE_SCALE,
                    position=drawn["position"],
                    wxyz=drawn["wxyz"],
                    disable_rotations=True,
                    depth_test=False,
                )
                shape = self.server.scene.add_box(
                    f"/obstacles/edit/{i}/box",
                    color=EDIT_COLOR,
                    dimensions=drawn["dimensions"],
                    opacity=OPACITY,
                    cast_shadow=False,
                )
                handle.on_update(self._moved(i, self._robot))
                self._edit_nodes += [shape, handle]
            return list(self._edited)

    def new_box(self, robot: str) -> Obstacle:
        """A new box for ``robot``: :data:`NEW_BOX`'s place and size in the scene, in that robot's
        base frame (so it stands beside any robot drawn as beside the Puma560)."""
        turn, scale, lift = robot_frame(robot)
        centre = turn.T @ (np.asarray(NEW_BOX.centre) - lift) / scale
        size = np.asarray(NEW_BOX.size) / scale
        return Obstacle(tuple(float(v) for v in centre), tuple(float(v) for v in size))

    def follow_robot(self, robot: str) -> None:
        """Draw the placed boxes on ``robot``, now drawn in the scene (the same place in its base
        frame: the run the form starts is that robot's)."""
        with self._lock:
            boxes, same = list(self._edited), robot == self._robot
        if not same:
            self.edit(boxes, robot)

    def _moved(self, index: int, robot: str):
        turn, scale, lift = robot_frame(robot)

        def moved(event: viser.TransformControlsEvent) -> None:
            position = np.asarray(event.target.position, dtype=float)
            with self._lock:
                if (
                    robot != self._robot
                    or index >= len(self._edited)
                    or not np.all(np.isfinite(position))
                ):
                    return
                old = self._edited[index]
                centre = turn.T @ (position - lift) / scale  # back into the robot's base frame
                try:
                    self._edited[index] = Obstacle(tuple(float(v) for v in centre), old.size)
                except KinematicsError:  # dragged out of reach: it stays where it was
                    return

        return moved

    def show_watched(
        self, boxes: tuple[Obstacle, ...] | list[Obstacle], robot: str | None = None
    ) -> None:
        """Draw a watched run's boxes on its ``robot`` (None: the Puma560; no boxes: clear them)."""
        with self._lock:
            for node in self._watch_nodes:
                node.remove()
            self._watch_nodes = [
                self.server.scene.add_box(
                    f"/obstacles/watched/{i}",
                    color=WATCH_COLOR,
                    opacity=OPACITY,
                    cast_shadow=False,
                    **_drawn(box, robot or DEFAULT_ROBOT),  # type: ignore[arg-type]
                )
                for i, box in enumerate(boxes)
            ]

    def watched_count(self) -> int:
        """How many watched boxes are drawn (for tests)."""
        with self._lock:
            return len(self._watch_nodes)
