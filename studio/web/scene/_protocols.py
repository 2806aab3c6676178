"""What the web layer's parts ask of the scene: the live pose it shows, and the scene itself.

The live pipeline, the services and the routers hold the scene by these protocols, so a test can
hand in a recording fake and the studio runs headless with none. Sources are held by
:class:`studio.capture.FrameSource`; a kind's own calls (playback, the simulator's reach, a fed
source's ``submit``) are made after an ``isinstance`` check.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import NamedTuple, Protocol

import numpy as np

from studio.kinematics import RobotArm

from ._model import Playback
from ._obstacles import SceneObstacles
from ._views import SceneCamera


class LivePose(NamedTuple):
    """The newest fitted pose, as the pipeline hands it to the scene.

    Attributes:
        q_human: the fitted arm's joints ``(7,)`` (rad).
        q_robot: the retargeted Puma560 joints ``(6,)`` (rad).
        tape: the reconstructed tape ``(regions + 1, 3)`` in the arm's base frame (m), or None
            (no tape: a camera or the hand guide teaches).
    """

    q_human: np.ndarray
    q_robot: np.ndarray
    tape: np.ndarray | None = None


HandMoved = Callable[[np.ndarray, np.ndarray], Mapping[str, object]]
"""Called with a hand position (3,) and orientation wxyz (4,) in the arm frame when the hand
guide's handle is dragged; returns the ``HandPublic`` fields (``q_human``, ``reached``, ...)."""


class LiveScene(Protocol):
    """What the live pipeline asks of the scene."""

    def show_live(self, pose: LivePose) -> None:
        """Show the newest live pose (latest wins, never blocks)."""

    def set_side(self, side: str, taped: bool = True) -> None:
        """Make ``side`` the operator's arm that follows the fit, with the tape drawn on it
        unless the source has none (``taped`` False: the camera, the hand guide)."""


class JointLimits(Protocol):
    """A robot's joint limits (rad)."""

    lower: np.ndarray
    upper: np.ndarray


class Scene(LiveScene, Protocol):
    """What the studio and its routers ask of the scene (:class:`~._scene.StudioScene`)."""

    @property
    def playing(self) -> bool:
        """Whether a playback runs."""

    def set_goal(self, q_robot_goal: np.ndarray | None, robot: str | None = None) -> None:
        """Show ``robot``'s goal (the Puma560's when None) as its ghost (None forgets goals)."""

    def show_path(self, name: str, q_robot_path: np.ndarray, robot: str | None = None) -> None:
        """Draw the tool path of ``robot``'s joint path (the Puma560's when None)."""

    def clear_path(self, name: str | None = None) -> None:
        """Remove a path (every path when None)."""

    def play_trajectory(
        self,
        times: np.ndarray,
        q_robot: np.ndarray,
        states: Sequence[int] | None = None,
        robot: str | None = None,
    ) -> None:
        """Animate ``robot`` (the Puma560 when None) along a trajectory of its joints."""

    def stop_playback(self) -> None:
        """Stop a playback."""

    def set_robot(self, arm: RobotArm | None, drawn: Callable[[], None] | None = None) -> None:
        """Draw ``arm`` (None: the Puma560) from its own meshes; ``drawn()`` once it is."""

    @property
    def robot_name(self) -> str:
        """The robot drawn."""

    @property
    def robot_mesh_count(self) -> int:
        """How many meshes draw it."""

    @property
    def robot_loading(self) -> str | None:
        """The robot chosen whose meshes are being read (None once drawn)."""

    def robot_notes(self) -> list[str]:
        """Sentences saying what cannot be shown on the robot drawn now, and why."""

    def current_q_robot(self) -> np.ndarray:
        """The robot joints shown now."""

    def shown_robot(self) -> tuple[np.ndarray, int]:
        """The robot joints shown now and the playback sample they are (-1: live)."""

    robot: JointLimits
    camera: SceneCamera
    obstacles: SceneObstacles

    def tool_positions(self, q_robot: np.ndarray, robot: str | None = None) -> np.ndarray:
        """World tool positions of ``robot``'s joint configurations ``(N, n)`` -> ``(N, 3)``."""

    def scrub(
        self,
        t: float | None = None,
        speed: float | None = None,
        paused: bool | None = None,
        step: int = 0,
    ) -> tuple[Playback, float] | None:
        """Reschedule the playback (or only read it); None when nothing was played."""

    def hold_pose(self, q_robot: np.ndarray, robot: str | None = None) -> None:
        """Show ``robot`` (the Puma560 when None) at a pose posed by hand."""

    def show_hand_handle(self, side: str | None, on_move: HandMoved | None) -> None:
        """Show the hand guide's handle on ``side``'s hand (None hides it)."""
