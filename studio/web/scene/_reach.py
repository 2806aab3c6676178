"""The operator's reach and the robot's workspace drawn in the studio's scene, so the person
sees where to move: the part of :class:`StudioScene` that draws them, kept apart so the scene
module stays small.

Two see-through balls, hidden until "Show reach" (the scene's panel, or
:meth:`SceneReach.show_reach`) turns them on:

- the operator's reach: around the taped arm's shoulder, as far as their hand reaches with the
  arm outstretched (:class:`studio.kinematics.HumanArm`'s lengths);
- the robot's workspace: the ball the retargeting maps that reach into
  (:attr:`studio.kinematics.Retargeter.workspace`: around the robot's shoulder, within its usable
  reach, cut by the table it stands on), framed as the robot is drawn (turned to face the
  operator, raised on its pedestal and enlarged as :func:`arm_framing` frames it).

An outstretched arm puts the tool on the robot's ball, whichever way it points; a bent one
inside it. Both follow the robot drawn and the arm taped.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np
import viser

from studio.kinematics import HumanArm, Retargeter, load_robot

from ._model import SceneLayout
from ._robot_view import RobotView, arm_framing

REACH_OPACITY = 0.12
"""How see-through the two balls are: the bodies inside them stay readable."""

REACH_COLORS = {"operator": (60, 150, 230), "robot": (240, 150, 40)}
"""The operator's reach in the operator's blue, the robot's workspace in the trace's orange."""


def robot_workspace_ball(name: str) -> tuple[np.ndarray, float]:
    """The world centre and radius (m) of robot ``name``'s workspace ball, framed as the scene
    draws the robot."""
    arm = load_robot(name, geometry=False)
    workspace = Retargeter(robot=arm).workspace
    scale, pedestal = arm_framing(arm)
    centre = arm.base_rotation @ workspace.shoulder * scale + np.array([0.0, 0.0, pedestal])
    return centre, workspace.radius * scale


def arm_reach(side: str) -> float:
    """How far (m) the operator's hand reaches from their shoulder, the arm outstretched."""
    arm = HumanArm(side=side)
    return arm.upper_arm_length + arm.forearm_length + arm.hand_length


class SceneReach:
    """The two balls and their toggle.

    The scene sets ``server``, ``layout``, ``_lock``, ``_view`` and ``_operator``, provides
    ``to_world``, and calls :meth:`_build_reach` while building and :meth:`_place_reach` when
    the robot drawn or the arm taped changes.
    """

    server: viser.ViserServer
    layout: SceneLayout
    _lock: threading.Lock
    _view: RobotView
    side: str  # the taped arm (SceneOperator's)
    to_world: Callable[
        [np.ndarray], np.ndarray
    ]  # its arm base frame to the world (SceneOperator's)

    def _build_reach(self) -> None:
        self._reach_on = False
        self._reach_balls: dict[str, tuple[np.ndarray, float]] = {}
        self._reach_handles = {
            what: self.server.scene.add_icosphere(
                f"/reach/{what}",
                radius=1.0,
                color=color,
                opacity=REACH_OPACITY,
                cast_shadow=False,
                receive_shadow=False,
                visible=False,
            )
            for what, color in REACH_COLORS.items()
        }
        self._reach_toggle = self.server.gui.add_checkbox(
            "Show reach",
            initial_value=False,
            hint="The operator's reach (blue) and the robot's workspace it maps into (orange)",
        )
        self._reach_toggle.on_update(lambda _: self.show_reach(self._reach_toggle.value))
        self._place_reach()

    def _place_reach(self) -> None:
        """Put both balls where the robot drawn and the arm taped are now."""
        balls = {
            "operator": (self.to_world(np.zeros(3)), arm_reach(self.side)),
            "robot": robot_workspace_ball(self._view.name),
        }
        for what, (centre, radius) in balls.items():
            handle = self._reach_handles[what]
            handle.position = tuple(float(x) for x in centre)
            handle.radius = float(radius)
        with self._lock:
            self._reach_balls = balls

    def show_reach(self, on: bool) -> None:
        """Show (``on``) or hide the operator's reach and the robot's workspace."""
        with self._lock:
            self._reach_on = bool(on)
        with self.server.atomic():
            for handle in self._reach_handles.values():
                handle.visible = bool(on)
        if self._reach_toggle.value != bool(on):
            self._reach_toggle.value = bool(on)

    @property
    def reach_shown(self) -> bool:
        """Whether the two balls are shown."""
        with self._lock:
            return self._reach_on

    def reach_balls(self) -> dict[str, tuple[np.ndarray, float]]:
        """The world centre and radius (m) of ``"operator"``'s reach and ``"robot"``'s
        workspace, as drawn now."""
        with self._lock:
            return {
                what: (centre.copy(), radius)
                for what, (centre, radius) in self._reach_balls.items()
            }
