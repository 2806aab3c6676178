"""The operator drawn in the studio's scene: the part of :class:`StudioScene` that places the
operator's body, moves the tape to the arm a source is taped on, draws the taped arm following
the fit with the tape on its sleeve, and shows the hand guide's handle on that arm's hand, kept
apart so the scene module stays small.

The studio reads one tape, so the other arm rests: it hangs at its neutral pose. The taped arm is
the current source's (``TapeConfig.side``); :meth:`SceneOperator.set_side` moves the tape to the
other arm when a source taped there starts.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import viser
import viser.transforms as vtf

from studio.kinematics import HumanArm, HumanBody, MeshPart, PosedBody, pose_body

from ._hand_handle import HandHandle
from ._model import SceneLayout
from ._protocols import HandMoved
from ._robot_view import rgb255, wxyz_of


@dataclass(frozen=True, eq=False)
class _Operator:
    """The operator as taped now: the body (taped arm) and where its arm base frame stands.

    Replaced whole by :meth:`StudioScene.set_side` (under the scene's lock), so a reader that
    took one snapshot poses, places and draws the tape with one consistent arm.

    Attributes:
        body: the meshes, posed with the taped arm following the fit.
        worldMbase: world pose of the taped arm's base frame (4x4).
        version: increases with each switch; the scene thread redraws the operator when it
            differs from the version it drew.
        rest: the meshes posed at rest (the taped arm at neutral, no tape).
    """

    body: HumanBody
    worldMbase: np.ndarray
    version: int
    rest: PosedBody


class SceneOperator:
    """The operator's body, its taped arm and the tape, and the hand guide's handle.

    The scene sets ``server``, ``layout``, ``hand_handle``, ``_lock``, ``_wake``, ``_live`` and
    ``_side_shown``, calls :meth:`_init_operator` first and, while building,
    :meth:`_add_operator`; it provides ``current_q_human``.
    """

    server: viser.ViserServer
    layout: SceneLayout
    hand_handle: HandHandle
    _lock: threading.Lock
    _wake: threading.Event
    _live: object | None
    _side_shown: str
    current_q_human: Callable[[], np.ndarray]

    def _init_operator(self, body: HumanBody) -> None:
        self._bodies = {body.side: body}  # one per taped arm, sharing the meshes
        self._operator = self._operator_for(body, 0)
        self._switch_lock = threading.Lock()  # one set_side at a time
        self._taped = True  # the source is a tape: the tape is drawn on the sleeve (set_side)
        self._arms: dict[str, HumanArm] = {}  # the hand guide's arm model per side

    def _operator_for(self, body: HumanBody, version: int) -> _Operator:
        """The operator taped on ``body``'s arm, placed upright on the floor facing -X.

        The body's middle and feet are placed, not its shoulder, so the resting body stands on
        the same spot whichever arm is taped.
        """
        lay = self.layout
        rest = pose_body(body, None)
        pts = np.concatenate(
            [
                p.vertices @ m[:3, :3].T + m[:3, 3]
                for p, m in zip(body.parts, rest.parts, strict=True)
            ]
        )
        centre = (pts.min(axis=0) + pts.max(axis=0)) / 2
        rotation = vtf.SO3.from_z_radians(lay.operator_yaw).as_matrix()
        out = np.eye(4)
        out[:3, :3] = rotation
        target = np.array([lay.operator_position[0], lay.operator_position[1], 0.0])
        out[:3, 3] = target - rotation @ np.array([centre[0], centre[1], body.floor_z])
        return _Operator(body, out, version, rest)

    def _add_operator(self) -> list[viser.MeshHandle]:
        s = self.server.scene
        operator = self._operator
        poses = operator.worldMbase @ operator.rest.parts
        handles = []
        for part, pose in zip(operator.body.parts, poses, strict=True):
            handles.append(
                s.add_mesh_simple(
                    f"/operator/{part.name}",
                    part.vertices,
                    part.faces,
                    color=rgb255(part.rgb),
                    cast_shadow=False,
                    receive_shadow=False,
                    position=pose[:3, 3],
                    wxyz=wxyz_of(pose[:3, :3]),
                )
            )
        return handles

    @property
    def body(self) -> HumanBody:
        """The operator's meshes, with the tape on the current taped arm."""
        with self._lock:
            return self._operator.body

    @property
    def side(self) -> str:
        """The taped arm (``"right"`` or ``"left"``): the one following the fit."""
        return self.body.side

    def to_world(self, p: np.ndarray) -> np.ndarray:
        """Points ``(..., 3)`` in the taped arm's base frame (the tape's frame) to world points."""
        with self._lock:
            operator = self._operator
        return _to_world(operator, p)

    def tape_on_sleeve(self, tape: np.ndarray, q_human: np.ndarray) -> np.ndarray:
        """Tape points (arm base frame) on the taped arm's sleeve at ``q_human``, as drawn
        (:func:`studio.kinematics.pose_body`)."""
        posed = pose_body(self.body, q_human, tape, self.layout.tape_lift_m)
        return posed.tape if posed.tape is not None else np.array(tape, dtype=float)

    def operator_mesh_points(self, q_human: np.ndarray | None) -> list[np.ndarray]:
        """World vertices of each operator mesh with the taped arm at ``q_human``."""
        with self._lock:
            operator = self._operator
        poses = _operator_poses(operator, q_human)
        return [_placed(p, m) for p, m in zip(operator.body.parts, poses, strict=True)]

    def _push_operator(self, operator: _Operator, posed: PosedBody, whole: bool = False) -> None:
        """Place the taped arm's meshes (every mesh when ``whole``: the taped arm changed, and
        the tape goes until the new arm's first tape) and the tape on its sleeve, as posed."""
        poses = operator.worldMbase @ posed.parts
        moving = list(range(len(poses))) if whole else operator.body.moving
        quats = wxyz_of(poses[moving, :3, :3])
        for i, wxyz in zip(moving, quats, strict=True):
            self._operator_handles[i].position = poses[i, :3, 3]
            self._operator_handles[i].wxyz = wxyz
        if posed.tape is not None:
            self._tape.points = _to_world(operator, posed.tape).astype(np.float32)
            if not self._tape.visible:
                self._tape.visible = True
        elif whole and self._tape.visible:
            self._tape.visible = False

    def set_side(self, side: str, taped: bool = True) -> None:
        """Put the tape on the operator's ``side`` arm: it follows the fit, the other rests.

        Called when a source taped on that arm starts (``TapeConfig.side``); ``taped`` False
        for a source without a tape (the camera, the hand guide), whose arm is drawn without
        one: the tape of an earlier source goes at once and stays away. Only the operator
        changes: the same meshes, posed from the new arm's base frame. A live pose given before
        the switch belongs to the other arm and is dropped; the next :meth:`update_live` poses
        the new arm. Returns at once; the scene thread redraws the operator (at rest, the tape
        hidden until the new arm's first tape). Nothing happens when nothing changes.

        Raises:
            KinematicsError: ``side`` is neither ``"right"`` nor ``"left"``.
        """
        with self._switch_lock:
            with self._lock:
                current = self._operator
            body = self._bodies.get(side) if isinstance(side, str) else None
            if body is None:
                body = current.body.with_side(side)  # checks the side; shares the meshes
                self._bodies[body.side] = body
            if body is current.body and bool(taped) == self._taped:
                return
            operator = self._operator_for(body, current.version + 1)
            with self._lock:
                self._operator = operator
                self._live = None
                self._taped = bool(taped)
        self._wake.set()

    def show_hand_handle(self, side: str | None, on_move: HandMoved | None) -> None:
        """Show the hand guide's handle on the ``side`` hand (None hides it); dragging it calls
        ``on_move(position, wxyz)`` with the hand pose in the arm frame."""
        if side is None or on_move is None:
            self.hand_handle.hide()
            return
        self.set_side(side)
        with self._lock:
            operator = self._operator
        arm = self._arms.get(side) or self._arms.setdefault(side, HumanArm(side=side))
        baseMhand = arm.forward(self.current_q_human()).hand
        self.hand_handle.show(
            operator.worldMbase, baseMhand, on_move, lambda q: arm.forward(q).hand
        )

    @property
    def shown_side(self) -> str:
        """The taped arm the scene has drawn (lags :attr:`side` until the next push)."""
        with self._lock:
            return self._side_shown


def _operator_poses(operator: _Operator, q_human: np.ndarray | None) -> np.ndarray:
    """World poses of every operator mesh with the taped arm at ``q_human`` (None: at rest)."""
    return operator.worldMbase @ operator.body.poses(q_human)


def _to_world(operator: _Operator, p: np.ndarray) -> np.ndarray:
    m = operator.worldMbase
    return np.asarray(p, dtype=float) @ m[:3, :3].T + m[:3, 3]


def _placed(part: MeshPart, pose: np.ndarray) -> np.ndarray:
    return part.vertices.astype(float) @ pose[:3, :3].T + pose[:3, 3]
