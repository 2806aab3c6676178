"""How the scene draws a robot: its meshes, and where each one is at a joint configuration.

The Puma560 is drawn from the Toolbox's link meshes on its DH frames, at the origin, as ever.
Any other robot of :func:`studio.kinematics.load_robot` is drawn from its URDF's own meshes
(:func:`studio.kinematics.robot_meshes`), posed by Pinocchio, and framed where the Puma560
stands: its base at the origin facing +X (turned by ``RobotArm.base_rotation`` where its URDF
faces elsewhere, as the retargeting turns its targets), raised on a pedestal so its shoulder is at the
Puma560's, and enlarged (never shrunk) to the Puma560's reach, so a small arm such as the SO-100
reads at the scene's distance from the operator beside it.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pinocchio as pin
import viser
import viser.transforms as vtf

from studio.kinematics import (
    MeshConfig,
    MeshPart,
    Puma560,
    RobotArm,
    load_robot,
    puma560_meshes,
    robot_spec,
)

from ._mesh_cache import cached_parts, mesh_key
from ._simplify import Geometry, Visuals, simplified, simplified_elsewhere


@dataclass(frozen=True, eq=False)
class RobotView:
    """One robot as the scene draws it.

    Attributes:
        name: the robot's name (``puma560``, ``panda``, ...).
        parts: its meshes, vertices in the world's scale.
        nq: its number of joints (a pose of another width is not its pose).
        q0: the pose it is drawn at before any other.
        poses: joint angles -> world pose of every part ``(P, 4, 4)``.
        tool: joint angles -> world position of the tool ``(3,)``.
        pedestal: height of the pedestal under its base (m; 0: it stands on the floor).
    """

    name: str
    parts: list[MeshPart]
    nq: int
    q0: np.ndarray
    poses: Callable[[np.ndarray], np.ndarray]
    tool: Callable[[np.ndarray], np.ndarray]
    pedestal: float = 0.0


def puma_view(puma: Puma560, config: MeshConfig) -> RobotView:
    """The Puma560 on its DH frames, its base at the origin."""
    parts = puma560_meshes(config)

    def poses(q: np.ndarray) -> np.ndarray:
        frames = puma.joint_frames(np.asarray(q, dtype=float))
        return np.stack([frames[int(p.frame)] for p in parts])

    return RobotView(
        "puma560", parts, 6, np.array(puma.qz, dtype=float), poses, puma_view_tool(puma)
    )


def puma_view_tool(puma: Puma560) -> Callable[[np.ndarray], np.ndarray]:
    """Joint angles -> world position of the Puma560's tool (its base is the world's origin)."""

    def tool(q: np.ndarray) -> np.ndarray:
        return puma.forward(np.asarray(q, dtype=float))[:3, 3]

    return tool


def arm_framing(arm: RobotArm) -> tuple[float, float]:
    """``(scale, pedestal)``: how ``arm`` is framed where the Puma560 stands.

    Enlarged to the Puma560's reach (never shrunk), and raised so its shoulder is at the
    Puma560's shoulder height.
    """
    puma = load_robot("puma560", geometry=False)  # its reach and shoulder: no meshes needed
    scale = max(1.0, puma.reach / arm.reach)
    pedestal = max(0.0, float(puma.shoulder[2]) - scale * float(arm.shoulder[2]))
    return scale, pedestal


def arm_tool(arm: RobotArm) -> Callable[[np.ndarray], np.ndarray]:
    """Joint angles -> world position of ``arm``'s tool, framed as :func:`arm_view` draws it
    (needs no meshes: a path's tool line is ready before its robot is drawn)."""
    scale, pedestal = arm_framing(arm)  # the Puma560's own: 1 and 0
    data = arm.model.createData()  # its own scratch data, as the retargeting has its own
    lock = threading.Lock()
    lift = np.array([0.0, 0.0, pedestal])
    turn = arm.base_rotation  # facing the operator, as its targets do

    def tool(q: np.ndarray) -> np.ndarray:
        with lock:
            pin.framesForwardKinematics(arm.model, data, np.asarray(q, dtype=float))
            return turn @ data.oMf[arm.tool_frame].translation * scale + lift

    return tool


def arm_view(
    arm: RobotArm, config: MeshConfig, cache: Path | None = None, elsewhere: bool = False
) -> RobotView:
    """A robot of :func:`~studio.kinematics.load_robot` drawn from its URDF's meshes (kept
    simplified in the ``cache`` folder, :mod:`._mesh_cache`, when one is given; read and
    simplified in a child process when ``elsewhere``, as the studio's scene asks).

    Raises:
        KinematicsError: a mesh file is missing or unreadable.
    """
    scale, pedestal = arm_framing(arm)
    # simplified at the size drawn: an enlarged arm keeps the detail of a full-size one
    at_size = replace(config, cell_m=config.cell_m / scale)
    visuals = Visuals(
        tuple(
            Geometry(
                g.name,
                str(g.meshPath),
                tuple(float(x) for x in np.asarray(g.meshScale, dtype=float)),
                tuple(float(x) for x in np.asarray(g.meshColor, dtype=float)),
            )
            for g in arm.visual_model.geometryObjects
        )
    )

    def build() -> list[MeshPart]:
        return (simplified_elsewhere if elsewhere else simplified)(visuals, at_size, scale)

    geometries = arm.visual_model.geometryObjects
    files = [str(g.meshPath) for g in geometries]
    # the parts are attached to the visual model's objects by index: the key covers that model
    model = [(g.name, int(g.parentJoint), int(g.parentFrame)) for g in geometries]
    key = mesh_key(files, at_size.cell_m, scale, arm.model.nq, model)
    parts = cached_parts(cache, arm.name, key, build, frames=range(len(geometries)))
    # Its own scratch data: the arm's own is the retargeting's, in another thread.
    data, geometry_data = arm.model.createData(), arm.visual_model.createData()
    lock = threading.Lock()
    lift = np.array([0.0, 0.0, pedestal])
    turn = arm.base_rotation  # facing the operator, as its targets do
    tool = arm_tool(arm)

    def poses(q: np.ndarray) -> np.ndarray:
        with lock:
            pin.updateGeometryPlacements(
                arm.model, data, arm.visual_model, geometry_data, np.asarray(q, dtype=float)
            )
            out = np.stack([geometry_data.oMg[int(p.frame)].homogeneous for p in parts])
        out[:, :3, :3] = turn @ out[:, :3, :3]
        out[:, :3, 3] = out[:, :3, 3] * scale @ turn.T + lift
        return out

    return RobotView(
        arm.name, parts, arm.nq, np.array(arm.home, dtype=float), poses, tool, pedestal
    )


log = logging.getLogger(__name__)


class RobotViews:
    """The robots' views, each built once; another robot's meshes are read in the background.

    Args:
        puma: the scene's Puma560 (its view is built at once: the scene starts with it).
        config: mesh simplification.
        cache: the folder keeping the simplified meshes (None: none kept).
    """

    def __init__(self, puma: Puma560, config: MeshConfig, cache: Path | None = None) -> None:
        self.puma = puma_view(puma, config)
        self._config = config
        self._cache = cache
        self._views = {self.puma.name: self.puma}
        self._lock = threading.Lock()
        self._wanted = self.puma.name
        self.failed = ""
        """Why the robot last chosen could not be drawn (empty when it could)."""

    @property
    def wanted(self) -> str:
        """The robot chosen last."""
        with self._lock:
            return self._wanted

    def built(self, name: str) -> RobotView | None:
        """The view of robot ``name`` if it has been built."""
        with self._lock:
            return self._views.get(name)

    @staticmethod
    def title(name: str) -> str:
        """A robot's name as a sentence says it (its title without the remark in brackets:
        ``Franka Emika Panda``, ``Puma560``)."""
        return robot_spec(name).title.split(" (")[0]

    def request(self, arm: RobotArm | None, ready: Callable[[RobotView], None]) -> None:
        """Build ``arm``'s view (None: the Puma560's) and hand it to ``ready``, unless another
        robot was requested meanwhile; a mesh that cannot be read is logged (nothing drawn)."""
        name = self.puma.name if arm is None else arm.name
        with self._lock:
            self._wanted = name
            self.failed = ""
        if arm is None or name in self._views:
            self._ready(name, self._views[name], ready)
            return
        thread = threading.Thread(
            target=self._load, args=(arm, ready), name="studio-robot-meshes", daemon=True
        )
        thread.start()

    def _load(self, arm: RobotArm, ready: Callable[[RobotView], None]) -> None:
        try:
            view = arm_view(arm, self._config, self._cache, elsewhere=True)
        except Exception as err:
            log.exception("The %s meshes could not be read; the robot drawn stays.", arm.name)
            with self._lock:
                if self._wanted == arm.name:
                    self.failed = (
                        f"The {arm.spec.title}'s meshes could not be read ({err}); the robot "
                        "drawn stays: reinstall example-robot-data, or pick another robot."
                    )
            return
        with self._lock:
            self._views.setdefault(arm.name, view)
        self._ready(arm.name, self._views[arm.name], ready)

    def _ready(self, name: str, view: RobotView, ready: Callable[[RobotView], None]) -> None:
        with self._lock:  # under the lock: a robot chosen meanwhile is never overdrawn
            if self._wanted == name:
                ready(view)


def wxyz_of(rotations: np.ndarray) -> np.ndarray:
    """Unit quaternions (w, x, y, z) of rotation matrices ``(..., 3, 3)`` (viser's convention)."""
    return np.asarray(vtf.SO3.from_matrix(np.asarray(rotations, dtype=float)).wxyz)


def rgb255(rgb: Sequence[float]) -> tuple[int, int, int]:
    """A colour of floats in [0, 1] as viser's 0-255 integers."""
    r, g, b = (int(round(255 * min(max(float(c), 0.0), 1.0))) for c in rgb)
    return r, g, b


def add_robot(
    server: viser.ViserServer,
    root: str,
    view: RobotView,
    opacity: float | None = None,
    visible: bool = True,
) -> list[viser.MeshHandle]:
    """Add ``view``'s meshes under ``root``, posed at its ``q0``."""
    handles = []
    for part, pose in zip(view.parts, view.poses(view.q0), strict=True):
        handles.append(
            server.scene.add_mesh_simple(
                f"{root}/{part.name}",
                part.vertices,
                part.faces,
                color=rgb255(part.rgb),
                opacity=opacity,
                cast_shadow=False,
                receive_shadow=False,
                position=pose[:3, 3],
                wxyz=wxyz_of(pose[:3, :3]),
                visible=visible,
            )
        )
    return handles
