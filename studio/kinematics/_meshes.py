"""Meshes to draw the two bodies (Gepetto's whole human and the Puma560's Toolbox link meshes),
and the operator's body posed with the tape on its sleeve.

Both come from installed data packages, never from the network:

- ``human.urdf``'s own meshes (example-robot-data's ``human_description``, BSD-2), posed by the
  full 36-joint Pinocchio model of the same file the arm fit uses. The taped arm's seven joints
  take the fitted ``q_human``; every other joint stays at its neutral (the other arm hangs).
  Poses are given in the taped arm's *arm base frame* (see :mod:`studio.kinematics.human._human`: Z
  up, shoulder at the origin), the frame the fit and the tape live in.
- The Puma560 link meshes of ``rtb-data`` (MIT, Peter Corke; the data files of the Robotics
  Toolbox for Python), which the Toolbox attaches as ``link{j}.stl`` to DH frame ``j`` of its
  standard-DH Puma560 (``link0`` to the base). Our :meth:`Puma560.joint_frames` are the same
  frames, so each mesh is drawn at ``joint_frames(q)[j]`` unchanged.

Meshes are simplified by vertex clustering (one vertex per cubic cell of
:attr:`MeshConfig.cell_m`), which keeps the shape to within a cell and cuts the triangle count
several times, so the scene stays smooth under software WebGL.

The operator at one live pose: the fit models the tape along the arm's bones, and drawn there it
would hide inside the arm's mesh. :func:`tape_on_sleeve` lifts every tape point closer to the
upper arm's (forearm's) axis than a sleeve's radius out onto it, radially; points away from the arm (on the back) stay.
:func:`pose_body` does one forward-kinematics pass per pose for both the meshes and the tape's
sleeve, so a viewer only places what it is given.
"""

from __future__ import annotations

import copy
import importlib.util
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ._checks import KinematicsError, check_side
from ._dh import PUMA_LINK_COLORS, PUMA_MESH_DIR
from .human._human import ARM_JOINTS, YUP_TO_ZUP, find_human_urdf

HUMAN_COLORS = {
    "skin": (0.89, 0.72, 0.60),
    "shirt": (0.28, 0.44, 0.64),
    "trousers": (0.30, 0.31, 0.36),
}
"""Colours of the operator: skin, shirt, trousers (rgb in [0, 1])."""


@dataclass(frozen=True)
class MeshConfig:
    """How the meshes are simplified.

    Attributes:
        cell_m: vertex-clustering cell (m); 0 keeps the meshes whole. The default keeps every
            feature larger than 2 cm, which is all that shows at the scene's viewing distance,
            and cuts the triangles about 10x (human 108,686 -> 10,858; Puma560 10,160 -> 1,378).
    """

    cell_m: float = 0.02


@dataclass(frozen=True)
class MeshPart:
    """One mesh, ready to draw: vertices already expressed in the frame it moves with.

    Attributes:
        name: a unique name (``"link3"``, ``"right_upperarm/upperarm_mesh"``).
        frame: where it is attached: an index into ``Puma560.joint_frames`` (robot), or a link
            name of ``human.urdf`` (operator).
        vertices: ``(V, 3)`` float32, metres, in that frame.
        faces: ``(F, 3)`` uint32 vertex indices.
        rgb: colour, floats in [0, 1].
    """

    name: str
    frame: int | str
    vertices: np.ndarray
    faces: np.ndarray
    rgb: tuple[float, float, float]


def simplify(
    vertices: np.ndarray, faces: np.ndarray, cell_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """Vertex clustering: merge the vertices of each ``cell_m`` cube, drop collapsed triangles.

    Args:
        vertices: ``(V, 3)`` positions (m).
        faces: ``(F, 3)`` indices.
        cell_m: cell size (m); 0 or less returns the mesh unchanged.

    Returns:
        The simplified ``(vertices float32, faces uint32)``; every vertex is the mean of the
        vertices it replaces, so the shape moves by less than one cell.
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    if cell_m <= 0 or len(v) == 0:
        return v.astype(np.float32), f.astype(np.uint32)
    keys = np.floor((v - v.min(axis=0)) / cell_m).astype(np.int64)
    _, cluster, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    cluster = cluster.reshape(-1)
    sums = np.zeros((len(counts), 3))
    np.add.at(sums, cluster, v)
    merged = sums / counts[:, None]
    g = cluster[f]
    keep = (g[:, 0] != g[:, 1]) & (g[:, 1] != g[:, 2]) & (g[:, 0] != g[:, 2])
    g = g[keep]
    # Two triangles of opposite winding on the same three clusters cancel: keep one.
    _, first = np.unique(np.sort(g, axis=1), axis=0, return_index=True)
    g = g[np.sort(first)]
    used, g = np.unique(g, return_inverse=True)
    return merged[used].astype(np.float32), g.reshape(-1, 3).astype(np.uint32)


def _load_stl(path: Path) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    mesh = trimesh.load(str(path), force="mesh", process=True)
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)


def puma560_mesh_dir() -> Path:
    """The folder of the installed ``rtb-data`` Puma560 link meshes.

    Raises:
        KinematicsError: ``rtb-data`` is not installed.
    """
    spec = importlib.util.find_spec("rtbdata")
    if spec is None or spec.origin is None:
        raise KinematicsError(
            "The Puma560 meshes (rtb-data) are not installed; install them with `pip install rtb-data`."
        )
    folder = Path(spec.origin).parent / PUMA_MESH_DIR
    if not (folder / "link0.stl").is_file():
        raise KinematicsError(
            f"The Puma560 meshes are missing from {folder}; reinstall them with `pip install --force-reinstall rtb-data`."
        )
    return folder


def puma560_meshes(config: MeshConfig | None = None) -> list[MeshPart]:
    """The seven Puma560 link meshes (base and links 1-6), each in its DH frame.

    Args:
        config: simplification (default :class:`MeshConfig`).

    Returns:
        Parts whose ``frame`` ``j`` indexes ``Puma560.joint_frames(q)``.
    """
    config = config if config is not None else MeshConfig()
    folder = puma560_mesh_dir()
    parts = []
    for j, rgb in enumerate(PUMA_LINK_COLORS):
        v, f = simplify(*_load_stl(folder / f"link{j}.stl"), config.cell_m)
        parts.append(MeshPart(f"link{j}", j, v, f, rgb))
    return parts


def robot_meshes(
    visual_model: pin.GeometryModel, config: MeshConfig | None = None
) -> list[MeshPart]:
    """The visual meshes of a robot of :func:`~studio.kinematics.load_robot`, from its URDF.

    Args:
        visual_model: the robot's ``RobotArm.visual_model`` (its ``.dae``/``.stl`` meshes).
        config: simplification (default :class:`MeshConfig`).

    Returns:
        One part per geometry object, its vertices scaled by the URDF's ``scale`` in the
        object's own frame; ``frame`` ``i`` indexes ``visual_model.geometryObjects`` (posed by
        ``pinocchio.updateGeometryPlacements``).

    Raises:
        KinematicsError: a mesh file is missing or unreadable.
    """
    config = config if config is not None else MeshConfig()
    parts = []
    for i, geom in enumerate(visual_model.geometryObjects):
        path = Path(geom.meshPath)
        try:
            v, f = _load_stl(path)
        except (OSError, ValueError) as err:
            raise KinematicsError(
                f"The robot mesh {path} cannot be read ({err}); reinstall example-robot-data."
            ) from None
        v = v * np.asarray(geom.meshScale, dtype=float)
        v, f = simplify(v, f, config.cell_m)
        r, g, b = (float(c) for c in np.asarray(geom.meshColor, dtype=float)[:3])
        parts.append(MeshPart(f"{i}-{geom.name}", i, v, f, (r, g, b)))
    return parts


def _human_color(link: str) -> tuple[float, float, float]:
    if any(k in link for k in ("head", "hand", "lowerarm")):
        return HUMAN_COLORS["skin"]
    if any(k in link for k in ("leg", "foot", "pelvis")):
        return HUMAN_COLORS["trousers"]
    return HUMAN_COLORS["shirt"]


class HumanBody:
    """Gepetto's whole human, posed with one arm following ``q_human`` and the rest at neutral.

    The studio has one tape, so one arm follows the fit and the other rests (hangs at neutral).
    :meth:`with_side` gives the same body taped on the other arm without loading the meshes
    again: the meshes are shared, only the taped arm's joints and the arm base frame differ.

    Args:
        side: the taped arm (``"right"`` or ``"left"``); poses are in its arm base frame.
        config: simplification (default :class:`MeshConfig`).

    Attributes:
        side: the taped arm.
        parts: the meshes, each attached to a ``human.urdf`` link (shared by both sides).
        moving: indices into ``parts`` of the meshes that move with the taped arm.
        floor_z: height of the lowest vertex in the neutral pose (arm base frame, m): the body
            stands on a floor at this height.
        model, data: the full Pinocchio model (immutable) and its scratch data (used under the
            body's own lock, so one body may be posed from several threads).
    """

    def __init__(self, side: str = "right", config: MeshConfig | None = None) -> None:
        check_side(side, "The taped arm")
        import yourdfpy

        config = config if config is not None else MeshConfig()
        urdf = find_human_urdf()
        self.model = pin.buildModelFromUrdf(str(urdf))
        root = urdf.parents[1]  # .../robots/human_description
        description = yourdfpy.URDF.load(str(urdf), load_meshes=False, build_scene_graph=False)
        parts: list[MeshPart] = []
        frame_ids: list[int] = []
        for link in description.robot.links:
            for visual in link.visuals:
                mesh = visual.geometry.mesh if visual.geometry is not None else None
                if mesh is None:
                    continue
                path = root / "meshes" / Path(mesh.filename).name
                v, f = _load_stl(path)
                if mesh.scale is not None:
                    v = v * np.asarray(mesh.scale, dtype=float)
                if visual.origin is not None:
                    v = v @ visual.origin[:3, :3].T + visual.origin[:3, 3]
                v, f = simplify(v, f, config.cell_m)
                name = f"{link.name}/{path.stem}"
                parts.append(MeshPart(name, link.name, v, f, _human_color(link.name)))
                frame_ids.append(self.model.getFrameId(link.name, pin.FrameType.BODY))
        self.parts = parts
        self._frame_ids = frame_ids
        self._tape_on(side)

    def with_side(self, side: str) -> HumanBody:
        """The same body with the tape on ``side``'s arm (this body itself when already so).

        Shares the meshes and the model; only the taped arm, its base frame and the scratch data
        are new, so switching arms costs milliseconds rather than reloading the meshes.

        Raises:
            KinematicsError: ``side`` is neither ``"right"`` nor ``"left"``.
        """
        check_side(side, "The taped arm")
        if side == self.side:
            return self
        other = copy.copy(self)
        other._tape_on(side)
        return other

    def _tape_on(self, side: str) -> None:
        """Make ``side``'s arm the taped one: its joints, base frame, moving meshes and floor."""
        self.side = side
        self.data = self.model.createData()
        self._lock = threading.Lock()
        self._q0 = pin.neutral(self.model)
        joints = [self.model.getJointId(f"{side}_{name}") for name in ARM_JOINTS]
        self._arm_idx_q = np.array([self.model.joints[j].idx_q for j in joints])
        # The arm base frame: Z up, origin at the taped side's shoulder at neutral (as HumanArm).
        pin.forwardKinematics(self.model, self.data, self._q0)
        shoulder = self.data.oMi[joints[0]].translation.copy()
        self._baseMurdf = np.eye(4)
        self._baseMurdf[:3, :3] = YUP_TO_ZUP
        self._baseMurdf[:3, 3] = -YUP_TO_ZUP @ shoulder
        first_arm_joint = joints[0]
        self.moving = [
            i
            for i, fid in enumerate(self._frame_ids)
            if self._below(self.model.frames[fid].parentJoint, first_arm_joint)
        ]
        rest = self.poses(None)
        self.floor_z = float(
            min(
                (p.vertices @ m[:3, :3].T + m[:3, 3])[:, 2].min()
                for p, m in zip(self.parts, rest, strict=True)
            )
        )

    def _below(self, joint: int, ancestor: int) -> bool:
        while joint > 0:
            if joint == ancestor:
                return True
            joint = self.model.parents[joint]
        return False

    def full_q(self, q_human: np.ndarray | None) -> np.ndarray:
        """The full model's configuration: the taped arm at ``q_human``, the rest at neutral."""
        q = self._q0.copy()
        if q_human is not None:
            q[self._arm_idx_q] = np.asarray(q_human, dtype=float).reshape(len(ARM_JOINTS))
        return q

    def poses(self, q_human: np.ndarray | None) -> np.ndarray:
        """Poses ``(len(parts), 4, 4)`` of every part in the arm base frame.

        Args:
            q_human: the taped arm's seven joints (rad), or None for the neutral pose.
        """
        q = self.full_q(q_human)
        out = np.empty((len(self.parts), 4, 4))
        with self._lock:
            pin.framesForwardKinematics(self.model, self.data, q)
            for k, fid in enumerate(self._frame_ids):
                out[k] = self._baseMurdf @ self.data.oMf[fid].homogeneous
        return out

    def link_pose(self, link: str, q_human: np.ndarray | None) -> np.ndarray:
        """The pose (4x4, arm base frame) of a ``human.urdf`` link."""
        return self.link_poses((link,), q_human)[0]

    def link_poses(self, links: Sequence[str], q_human: np.ndarray | None) -> np.ndarray:
        """The poses ``(len(links), 4, 4)`` (arm base frame) of ``human.urdf`` links, from one
        forward-kinematics pass (the scene asks for three links at every live pose)."""
        fids = []
        for link in links:
            fid = self.model.getFrameId(link, pin.FrameType.BODY)
            if fid >= len(self.model.frames):
                raise KinematicsError(f"human.urdf has no link {link!r}; give a link of the model.")
            fids.append(fid)
        q = self.full_q(q_human)
        with self._lock:
            pin.framesForwardKinematics(self.model, self.data, q)
            return np.stack([self._baseMurdf @ self.data.oMf[fid].homogeneous for fid in fids])


# ----------------------------------------------------------------- the body at one pose

SLEEVE_LIFT_M = (0.055, 0.045)
"""How far the tape lies from the upper arm's and the forearm's axis (m): on the sleeve, where
it is strapped, rather than inside the arm's mesh."""
SLEEVE_ROUNDS = 3
"""Rounds of pushing tape points off the arm's segments: a point pushed off one segment near
the elbow may land inside the other, and a few rounds settle it."""
ARM_LINKS = ("upperarm", "lowerarm", "hand")
"""The ``human.urdf`` links whose origins (shoulder, elbow, wrist) make the sleeve's axis."""


@dataclass(frozen=True, eq=False)
class PosedBody:
    """The operator's meshes and tape at one pose, in the taped arm's base frame.

    Attributes:
        parts: ``(len(body.parts), 4, 4)`` pose of every mesh.
        tape: ``(N, 3)`` tape points on the sleeve (m), or None without a tape.
    """

    parts: np.ndarray
    tape: np.ndarray | None


def tape_on_sleeve(
    tape: np.ndarray,
    axis: np.ndarray,
    lift_m: tuple[float, float] = SLEEVE_LIFT_M,
    rounds: int = SLEEVE_ROUNDS,
) -> np.ndarray:
    """Tape points lifted off the arm's axis onto its surface.

    Args:
        tape: ``(N, 3)`` tape points (m).
        axis: ``(3, 3)`` shoulder, elbow and wrist positions (m), in the tape's frame.
        lift_m: the sleeve's radius around the upper arm and around the forearm (m).
        rounds: passes over both segments.

    Returns:
        ``(N, 3)``: each point closer to a segment than its ``lift_m`` pushed out radially to
        that distance (a point on the axis itself goes to any side); the others unchanged.
    """
    axis = np.asarray(axis, dtype=float)
    out = np.array(tape, dtype=float)
    for _ in range(rounds):  # all points at once: this runs for every live pose shown
        for k, (a, b, lift) in enumerate(zip(axis[:-1], axis[1:], lift_m, strict=True)):
            ab = b - a
            along = (out - a) @ ab / (ab @ ab)
            t = np.clip(along, 0.0, 1.0)
            c = a + t[:, None] * ab
            away = out - c
            d = np.linalg.norm(away, axis=1)
            # Past the elbow, a point is the other segment's: pushed out of this one's end, a
            # point on the axis would go along it, then across the other, twice as far.
            beyond_elbow = (along > 1.0) if k == 0 else (along < 0.0)
            inside = (d < lift) & ~beyond_elbow
            if not inside.any():
                continue
            on_axis = inside & (d <= 1e-9)
            if on_axis.any():  # any direction across the axis
                across = np.cross(ab, np.eye(3)[int(np.argmin(np.abs(ab)))])
                away[on_axis] = across
                d[on_axis] = np.linalg.norm(across)
            out[inside] = c[inside] + away[inside] / d[inside, None] * lift
    return out


def sleeve_axis(body: HumanBody, parts: np.ndarray) -> np.ndarray:
    """The taped arm's shoulder, elbow and wrist ``(3, 3)`` from the mesh poses ``parts``
    (each arm link carries a mesh, posed at the link's frame)."""
    frames = [part.frame for part in body.parts]
    return np.stack([parts[frames.index(f"{body.side}_{link}"), :3, 3] for link in ARM_LINKS])


def pose_body(
    body: HumanBody,
    q_human: np.ndarray | None,
    tape: np.ndarray | None = None,
    lift_m: tuple[float, float] = SLEEVE_LIFT_M,
) -> PosedBody:
    """The body's meshes with the taped arm at ``q_human`` and ``tape`` on its sleeve, from one
    forward-kinematics pass.

    Args:
        body: the operator's meshes; ``body.side`` is the taped arm.
        q_human: the taped arm's seven joints (rad), or None for the neutral pose.
        tape: ``(N, 3)`` tape points in the arm base frame (m), or None.
        lift_m: the sleeve's radius around the upper arm and the forearm (m).
    """
    parts = body.poses(q_human)
    if tape is None or len(tape) < 2:
        return PosedBody(parts, None)
    return PosedBody(parts, tape_on_sleeve(tape, sleeve_axis(body, parts), lift_m))
