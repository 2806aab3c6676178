"""Obstacle boxes in the scene: the ones a person places for a run, and a watched run's.

A box (:class:`studio.kinematics.Obstacle`) lives in the robot's base frame. The training form's
boxes are drawn with a handle each (viser's transform controls, moved, not turned): dragging one
moves its box, and :meth:`SceneObstacles.edited` gives the boxes where they stand now, for the
run the form starts. A watched run's boxes are drawn see-through beside them, without handles.
"""

from __future__ import annotations

import threading

import numpy as np
import viser

from studio.kinematics import KinematicsError, Obstacle

EDIT_COLOR = (235, 140, 40)
"""The boxes placed for the next run."""
WATCH_COLOR = (200, 60, 60)
"""A watched run's boxes."""
OPACITY = 0.45
"""See-through, so the arm shows inside a box it touches."""
HANDLE_SCALE = 0.25


class SceneObstacles:
    """The boxes the scene draws, in the Puma560's frame (the scene's world: its base at the
    origin, z up)."""

    def __init__(self, server: viser.ViserServer) -> None:
        self.server = server
        self._lock = threading.Lock()
        self._edited: list[Obstacle] = []
        self._edit_nodes: list[viser.SceneNodeHandle] = []
        self._watch_nodes: list[viser.SceneNodeHandle] = []

    def edited(self) -> list[Obstacle]:
        """The boxes placed for the next run, where their handles stand now."""
        with self._lock:
            return list(self._edited)

    def edit(self, boxes: list[Obstacle]) -> list[Obstacle]:
        """Draw ``boxes`` as the ones placed for the next run, each with a handle to move it."""
        with self._lock:
            for node in self._edit_nodes:
                node.remove()
            self._edit_nodes = []
            self._edited = list(boxes)
            for i, box in enumerate(boxes):
                handle = self.server.scene.add_transform_controls(
                    f"/obstacles/edit/{i}",
                    scale=HANDLE_SCALE,
                    position=box.centre,
                    disable_rotations=True,
                    depth_test=False,
                )
                shape = self.server.scene.add_box(
                    f"/obstacles/edit/{i}/box",
                    color=EDIT_COLOR,
                    dimensions=box.size,
                    opacity=OPACITY,
                    cast_shadow=False,
                )
                handle.on_update(self._moved(i))
                self._edit_nodes += [shape, handle]
            return list(self._edited)

    def _moved(self, index: int):
        def moved(event: viser.TransformControlsEvent) -> None:
            position = np.asarray(event.target.position, dtype=float)
            with self._lock:
                if index >= len(self._edited) or not np.all(np.isfinite(position)):
                    return
                old = self._edited[index]
                try:
                    self._edited[index] = Obstacle(tuple(position), old.size)
                except KinematicsError:  # dragged out of reach: it stays where it was
                    return

        return moved

    def show_watched(self, boxes: tuple[Obstacle, ...] | list[Obstacle]) -> None:
        """Draw a watched run's boxes (none: clear them)."""
        with self._lock:
            for node in self._watch_nodes:
                node.remove()
            self._watch_nodes = [
                self.server.scene.add_box(
                    f"/obstacles/watched/{i}",
                    color=WATCH_COLOR,
                    dimensions=box.size,
                    position=box.centre,
                    opacity=OPACITY,
                    cast_shadow=False,
                )
                for i, box in enumerate(boxes)
            ]

    def watched_count(self) -> int:
        """How many watched boxes are drawn (for tests)."""
        with self._lock:
            return len(self._watch_nodes)
