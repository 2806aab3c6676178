"""The hand guide's handle: viser transform controls on the operator's hand.

Shown only while the hand guide is the source. Dragging it (in any browser showing the scene)
hands the new hand pose, in the operator's arm frame, to the same function ``POST
/api/source/hand`` calls (:meth:`studio.web.services.Sources.hand_moved`): the arm follows by IK and
the robot mirrors it through the live pipeline.

A pose a browser sends that is not a pose (NaN, infinite, a zero quaternion) is refused before
viser passes it on to the other browsers showing the scene: the handle is put back where it was,
in every browser.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Mapping

import numpy as np
import viser
import viser.transforms as vtf

from studio import StudioError

from ._protocols import HandMoved

log = logging.getLogger(__name__)

HANDLE_NAME = "/hand_guide"
"""The handle's node in the scene tree."""
HANDLE_SCALE = 0.22
"""Size of the gizmo (m): about a hand's length, so it is easy to grab and hides little."""

MIN_INTERVAL_S = 1.0 / 60.0
"""Drag updates closer together than this are skipped (the release is always handed on), so a
fast mouse stays well under the hand source's flood limit and the IK keeps up."""

HandOf = Callable[[np.ndarray], np.ndarray]
"""The hand's 4x4 pose in the arm frame for a ``q_human``."""


def pose_in_base(worldMbase: np.ndarray, position: np.ndarray, wxyz: np.ndarray) -> np.ndarray:
    """A world pose (the handle's) in the arm base frame, as a 4x4."""
    worldMhand = np.eye(4)
    worldMhand[:3, :3] = vtf.SO3(np.asarray(wxyz, dtype=float)).as_matrix()
    worldMhand[:3, 3] = position
    return np.linalg.inv(worldMbase) @ worldMhand


class HandHandle:
    """One transform-controls handle, placed at the operator's hand in world coordinates.

    Args:
        server: the viser server.
    """

    def __init__(self, server: viser.ViserServer) -> None:
        self.server = server
        self._lock = threading.Lock()
        self._handle: viser.TransformControlsHandle | None = None
        self._worldMbase = np.eye(4)
        self._on_move: HandMoved | None = None
        self._hand_of: HandOf | None = None
        self.moves = 0  # drags handed on, for tests
        self.refused = 0  # poses that were not poses, put back
        self._last_move = 0.0
        self._good: tuple[np.ndarray, np.ndarray] | None = None  # the last pose that was one
        # updates put back, by id: their drag callback (run next, the event alive till then)
        # hands nothing on
        self._put_back: set[int] = set()

    @property
    def visible(self) -> bool:
        """Whether the handle is shown."""
        return self._handle is not None

    def show(
        self,
        worldMbase: np.ndarray,
        baseMhand: np.ndarray,
        on_move: HandMoved,
        hand_of: HandOf | None = None,
    ) -> None:
        """Show the handle at ``baseMhand`` (the hand in the arm base frame at ``worldMbase``).

        ``hand_of`` gives the hand's pose for an arm pose: when a drag ends out of reach, the
        handle goes back onto the hand, where the arm stopped.
        """
        worldMhand = worldMbase @ baseMhand
        with self._lock:
            self.hide_locked()
            self._worldMbase = np.array(worldMbase, dtype=float)
            self._on_move = on_move
            self._hand_of = hand_of
            handle = self.server.scene.add_transform_controls(
                HANDLE_NAME,
                scale=HANDLE_SCALE,
                position=worldMhand[:3, 3],
                wxyz=vtf.SO3.from_matrix(worldMhand[:3, :3]).wxyz,
                depth_test=False,
            )
            # first, and awaited: viser passes the pose on to the other browsers only after it
            handle.on_update(self._checked)
            handle.on_update(self._dragged)
            self._handle = handle
            self._good = (np.array(handle.position), np.array(handle.wxyz))

    def hide(self) -> None:
        """Remove the handle (another source is live)."""
        with self._lock:
            self.hide_locked()

    def hide_locked(self) -> None:
        if self._handle is not None:
            self._handle.remove()
            self._handle = None
        self._on_move = None

    async def _checked(self, event: viser.TransformControlsEvent) -> None:
        """Put the handle back where it was when a browser sent a pose that is not one, before
        viser passes it on to the other browsers (it sends the handle's pose once this returns)."""
        handle = event.target
        position = np.asarray(handle.position, dtype=float)
        wxyz = np.asarray(handle.wxyz, dtype=float)
        if _is_pose(position, wxyz):
            self._good = (position, wxyz)
            return
        good = self._good
        self.refused += 1
        log.warning("A scene client sent the hand handle to %s %s; put back.", position, wxyz)
        if good is not None:
            handle.position, handle.wxyz = good  # to every browser, the sender's too
        self._put_back.add(id(event))

    def _dragged(self, event: viser.TransformControlsEvent) -> None:
        if id(event) in self._put_back:
            self._put_back.discard(id(event))
            return
        now = time.monotonic()
        if getattr(event, "phase", "update") == "update" and now - self._last_move < MIN_INTERVAL_S:
            return
        self._last_move = now
        target = event.target
        position = np.asarray(target.position, dtype=float)
        reached = self.move(position, np.asarray(target.wxyz, dtype=float))
        if getattr(event, "phase", "update") == "end" and reached is not None:
            self.snap(reached)

    def snap(self, answer: Mapping[str, object]) -> None:
        """Put the handle back on the hand when the arm stopped short of it (out of reach)."""
        with self._lock:
            handle, hand_of, worldMbase = self._handle, self._hand_of, self._worldMbase
        if handle is None or hand_of is None or answer.get("reached", True):
            return
        worldMhand = worldMbase @ hand_of(np.asarray(answer["q_human"], dtype=float))
        handle.position = worldMhand[:3, 3]
        handle.wxyz = vtf.SO3.from_matrix(worldMhand[:3, :3]).wxyz
        self._good = (np.array(handle.position), np.array(handle.wxyz))

    def move(self, position: np.ndarray, wxyz: np.ndarray) -> Mapping[str, object] | None:
        """The handle was dragged to a world pose: hand it on in the arm frame.

        Returns what the hand guide reached, or None when the update was refused.
        """
        with self._lock:
            on_move, worldMbase = self._on_move, self._worldMbase
        if on_move is None:
            return None
        baseMhand = pose_in_base(worldMbase, position, wxyz)
        try:
            answer = on_move(baseMhand[:3, 3], vtf.SO3.from_matrix(baseMhand[:3, :3]).wxyz)
        except StudioError as err:  # a flood or a switched source: the next drag tries again
            log.debug("hand handle update refused: %s", err)
            return None
        self.moves += 1
        return answer if isinstance(answer, Mapping) else None


def _is_pose(position: np.ndarray, wxyz: np.ndarray) -> bool:
    """Whether a handle's position and quaternion make a pose (finite, a non-zero quaternion)."""
    return (
        position.shape == (3,)
        and wxyz.shape == (4,)
        and bool(np.isfinite(position).all() and np.isfinite(wxyz).all())
        and float(np.linalg.norm(wxyz)) > 1e-9
    )
