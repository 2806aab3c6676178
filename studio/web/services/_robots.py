"""The robots offered and the one the operator teaches: the scene draws it from its meshes and
the live chain retargets the operator onto it."""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable

from studio.kinematics import LIMIT_MARGIN_RAD, load_robot, robot_names, robot_spec
from studio.learning import default_goal_deg
from studio.motion import Motion

from ..live import Pipeline
from ..scene import RobotPlayer, RobotViews, Scene


class Robots:
    """The robot a studio teaches.

    Args:
        pipeline: the live pipeline, which retargets onto the robot taught.
        scene: the scene that draws it, or None (headless).
        player: what plays motions on the robot drawn (None without a scene).
    """

    def __init__(self, pipeline: Pipeline, scene: Scene | None, player: RobotPlayer | None) -> None:
        self.pipeline = pipeline
        self.scene = scene
        self.player = player
        self._lock = threading.Lock()  # one robot switch at a time
        self._switching: str | None = None  # the robot whose model loads (set_robot)

    def play_motion(self, what: str, key: Hashable, compute: Callable[[], Motion]) -> None:
        """Play ``what`` (``the simulated motion of ...``), made by ``compute`` for the robot
        taught (cached under ``key``, made in the background), on the robot in the scene; the
        page is told meanwhile through :meth:`state`'s notes. Nothing without a scene."""
        if self.player is None:
            return
        slug = "".join(c if c.isalnum() else "-" for c in str(key[-1]))
        self.player.play(self.taught, what, key, compute, f"played-{slug}")

    @property
    def taught(self) -> str:
        """The name of the robot taught now."""
        return self.pipeline.robot_name

    def choose(self, name: str) -> None:
        """Teach robot ``name``: the scene draws it from its meshes, and the live chain
        retargets the operator onto it once it is drawn (the robot drawn follows meanwhile).

        Raises:
            KinematicsError: an unknown name, or a model or mesh that cannot be read (the
                robot taught before stays).
        """
        with self._lock:
            self._switching = robot_spec(name).name
            try:
                arm = load_robot(self._switching)  # seconds the first time
            finally:
                self._switching = None
            live = arm.scratch_copy()  # the live thread's own scratch data
            if self.scene is None:
                self.pipeline.set_robot(live)
                return
            # its meshes are read in the background; the live chain drives it once it is drawn
            self.scene.set_robot(arm, drawn=self.pipeline.choose_robot(live))

    def state(self) -> dict[str, object]:
        """The robot the scene draws, the one whose meshes it reads, and one sentence for each
        thing the page should know about them (loading, retargeting, what cannot be shown)."""
        scene, player = self.scene, self.player
        if scene is None or player is None:
            return {"robot_drawn": None, "robot_loading": None, "robot_notes": []}
        busy, note = player.status()
        notes = [*scene.robot_notes(), *(s for s in (busy, note) if s)]
        switching = self._switching
        if switching is not None:
            title = RobotViews.title(switching)
            notes.insert(
                0, f"Loading the {title}'s model and meshes; the robot drawn stays meanwhile."
            )
        return {
            "robot_drawn": scene.robot_name,
            "robot_loading": switching or scene.robot_loading,
            "robot_notes": notes,
        }

    def public(self) -> dict[str, object]:
        """``RobotsPublic``: every offered robot with its joints and default goal, and the one
        taught."""
        robots = [
            {
                "name": name,
                "title": robot_spec(name).title,
                "joints": list(load_robot(name, geometry=False).joint_names),
                "goal_deg": list(default_goal_deg(name)),
                "joint_mode": robot_spec(name).joint_mode,
            }
            for name in robot_names()
        ]
        scene = self.scene
        return {
            "robots": robots,
            "robot": self.pipeline.robot_name,
            "drawn": None if scene is None else scene.robot_name,
            "drawn_meshes": 0 if scene is None else scene.robot_mesh_count,
            "limit_margin_rad": LIMIT_MARGIN_RAD,
        }
