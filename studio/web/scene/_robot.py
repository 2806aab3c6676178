"""The robot drawn in the studio's scene and its goal: the part of :class:`StudioScene` that
chooses, draws and poses the robot (any robot of :func:`studio.kinematics.load_robot`) and shows
each robot's goal on it as a see-through ghost, kept apart so the scene module stays small.

Joint paths are a robot's own: a playback, a path or a goal names the robot its joints belong to
(the Puma560 when it names none: the policies' and the paper's robot), and the scene shows it
only on that robot. What cannot be shown on the robot drawn is said by :meth:`robot_notes`.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np
import viser

from studio.kinematics import DEFAULT_ROBOT, Puma560, RobotArm, load_robot

from ._model import Playback, SceneLayout
from ._robot_view import RobotView, RobotViews, add_robot, arm_tool, wxyz_of

PUMA = DEFAULT_ROBOT
"""The robot a joint path belongs to when it names none (policies, the grid's goals): the
default robot, as a policy file that names none is its."""


class SceneRobot:
    """The robot drawn, its pedestal, and a goal (a ghost and a marker) per robot.

    The scene sets ``server``, ``layout``, ``robot`` (the Puma560), ``_lock``, ``_wake``,
    ``_q_robot_shown`` and ``_playback``, then calls :meth:`_init_robot` and, while building,
    :meth:`_build_robot`.
    """

    server: viser.ViserServer
    layout: SceneLayout
    robot: Puma560
    _lock: threading.Lock
    _wake: threading.Event
    _q_robot_shown: np.ndarray
    _playback: Playback | None
    _place_reach: Callable[[], None]  # SceneReach's

    def _init_robot(self, views: RobotViews) -> None:
        self._views = views
        self._view = views.puma  # the robot drawn
        self._next_view: RobotView | None = None  # a robot chosen, for the scene thread to draw
        self._next_drawn: Callable[[], None] | None = None  # called once it is drawn
        self._goals: dict[str, np.ndarray] = {}  # each robot's goal (set_goal)
        self._pedestal: viser.SceneNodeHandle | None = None

    def _build_robot(self) -> None:
        lay = self.layout
        self._robot_handles = add_robot(self.server, "/robot", self._view)
        self._ghost_handles = add_robot(
            self.server, "/goal/ghost", self._view, opacity=lay.ghost_opacity, visible=False
        )
        self._goal_marker = self.server.scene.add_icosphere(
            "/goal/marker", radius=0.035, color=lay.colors["goal"], opacity=0.85, visible=False
        )
        self._push_robot(self._robot_handles, self._q_robot_shown)

    def _draw_robot(self, view: RobotView) -> None:
        """Replace the robot (and its ghost) by ``view``'s, on a pedestal when it has one."""
        for h in [*self._robot_handles, *self._ghost_handles]:
            h.remove()
        if self._pedestal is not None:
            self._pedestal.remove()
            self._pedestal = None
        robot = add_robot(self.server, "/robot", view)
        ghost = add_robot(
            self.server, "/goal/ghost", view, opacity=self.layout.ghost_opacity, visible=False
        )
        self._robot_handles, self._ghost_handles = robot, ghost
        with self._lock:
            self._q_robot_shown = view.q0.copy()
        self._view = view  # last: readers of the name see its meshes and its pose
        self._place_goal()  # this robot's goal, if it has one
        self._place_reach()  # its workspace
        if view.pedestal > 0:
            self._pedestal = self.server.scene.add_box(
                "/robot_pedestal",
                color=(150, 152, 158),
                dimensions=(0.3, 0.3, view.pedestal),
                position=(0.0, 0.0, view.pedestal / 2),
                cast_shadow=False,
            )

    def _push_robot(self, handles: list[viser.MeshHandle], q_robot: np.ndarray) -> None:
        if len(q_robot) != self._view.nq:
            return  # a pose of the robot drawn before a switch
        poses = self._view.poses(q_robot)
        quats = wxyz_of(poses[:, :3, :3])
        for h, pose, wxyz in zip(handles, poses, quats, strict=True):
            h.position = pose[:3, 3]
            h.wxyz = wxyz

    # ------------------------------------------------------------------ the goal

    def set_goal(self, q_robot_goal: np.ndarray | None, robot: str | None = None) -> None:
        """Show ``robot``'s goal (the Puma560's when None) as a see-through ghost of it and a
        marker at its tool, whenever that robot is drawn; a goal of None forgets every goal."""
        with self._lock:
            if q_robot_goal is None:
                self._goals.clear()
            else:
                self._goals[robot or PUMA] = np.asarray(q_robot_goal, dtype=float).copy()
        with self.server.atomic():
            self._place_goal()

    def _place_goal(self) -> None:
        """Show the drawn robot's goal (hidden when it has none, or one of another width)."""
        with self._lock:
            q = self._goals.get(self._view.name)
        visible = q is not None and len(q) == self._view.nq
        if q is not None and visible:
            self._push_robot(self._ghost_handles, q)
            self._goal_marker.position = self._view.tool(q)
        for h in self._ghost_handles:
            h.visible = visible
        self._goal_marker.visible = visible

    @property
    def goal_shown(self) -> bool:
        """Whether the robot drawn shows a goal."""
        with self._lock:
            q = self._goals.get(self._view.name)
        return q is not None and len(q) == self._view.nq

    # ------------------------------------------------------------------ the robot

    def set_robot(self, arm: RobotArm | None, drawn: Callable[[], None] | None = None) -> None:
        """Draw ``arm`` (a robot of :func:`~studio.kinematics.load_robot`; None or the
        ``puma560``: the Puma560) from its own meshes, framed where the Puma560 stands.

        Returns at once: its meshes are read in the background (from the mesh cache after the
        first time) and the scene thread then draws it (:attr:`robot_name` names it once drawn,
        :attr:`robot_loading` meanwhile), and calls ``drawn()`` once it has.
        """
        self._views.request(arm, lambda view: self._draw_next(view, drawn))

    def _draw_next(self, view: RobotView, drawn: Callable[[], None] | None = None) -> None:
        with self._lock:
            self._next_view, self._next_drawn = view, drawn
        self._wake.set()

    @property
    def robot_name(self) -> str:
        """The name of the robot the scene has drawn (lags :meth:`set_robot` until drawn)."""
        return self._view.name

    @property
    def robot_loading(self) -> str | None:
        """The robot chosen whose meshes are being read (None once it is drawn)."""
        wanted = self._views.wanted
        return None if wanted == self._view.name or self._views.failed else wanted

    @property
    def robot_mesh_count(self) -> int:
        """How many meshes the scene draws the robot with."""
        return len(self._robot_handles)

    def tool_positions(self, q_robot: np.ndarray, robot: str | None = None) -> np.ndarray:
        """World tool positions of ``robot``'s joint paths ``(N, nq)`` -> ``(N, 3)``, where that
        robot is drawn (the Puma560's when None: policies and the grid's paths are its)."""
        q = np.atleast_2d(np.asarray(q_robot, dtype=float))
        name = robot or PUMA
        view = self._views.built(name)
        tool = view.tool if view is not None else arm_tool(load_robot(name, geometry=False))
        return np.array([tool(qi) for qi in q])

    def robot_notes(self) -> list[str]:
        """One sentence for each thing that cannot be shown on the robot drawn now: its meshes
        still loading or unreadable, a playback of another robot, no goal for it."""
        title = self._views.title
        notes = []
        loading = self.robot_loading
        if loading is not None:
            notes.append(f"Loading the {title(loading)}'s meshes; the robot drawn stays meanwhile.")
        if self._views.failed:
            notes.append(self._views.failed)
        drawn = self._view.name
        with self._lock:
            playback = self._playback
        if playback is not None and playback.robot != drawn and loading is None:
            notes.append(
                f"What plays now was made for the {title(playback.robot)}, so the {title(drawn)} "
                "follows the live source meanwhile: play the demonstration or recording again to "
                f"see it on the {title(drawn)} (a policy plays on the robot it was learnt on)."
            )
        with self._lock:  # the robot whose pose the goal is, when it is not the one drawn
            owner = next((name for name in self._goals if name != drawn), None)
        if not self.goal_shown and owner is not None and loading is None:
            notes.append(
                f"The training goal is a {title(owner)} pose, so the {title(drawn)} shows a goal "
                "once a demonstration plays on it: the demonstration's end pose, retargeted."
            )
        return notes
