"""Today's arms from example-robot-data: one model per robot, with limits, IK and self-collision.

The studio teaches the Puma560 (the paper's robot, whose URDF is built from its DH table with the
link meshes of ``rtb-data``, :mod:`._dh`) and the arms that ``example-robot-data`` ships with a
URDF and meshes: the Franka Panda, the UR3, UR5
and UR10, the SO-100 and SO-101 of the LeRobot community, the xArm7, the Unitree Z1 and the
Kinova Jaco (j2s6s200). :func:`load_robot` gives a :class:`RobotArm` for any of them:

- the arm's joints only (grippers and fingers locked at their lower limit), with the URDF's
  position and velocity limits; a URDF ``continuous`` joint gets the limits +-2 pi, so that every
  joint angle is one number;
- the tool pose (:meth:`RobotArm.forward`) and a damped-least-squares IK within the limits with a
  null-space task that keeps the elbow near a wanted point (:meth:`RobotArm.inverse`);
- self-collision distances on the URDF's collision geometry with Pinocchio and coal
  (:meth:`RobotArm.self_collisions`), adjacent links and the SRDF's disabled pairs excluded.

URDFs give no acceleration limits; :attr:`RobotSpec.acceleration` holds the makers' figures where
published (Panda) and otherwise twice the velocity limit per second, a conservative rule (the
Puma560's too: the sources of its speed and torque limits give none).
"""

from __future__ import annotations

import copy
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ._chain_ik import ChainSolve, LinkPoints, SerialChain, solve
from ._checks import KinematicsError, real_array
from ._robot_specs import DEFAULT_ROBOT as DEFAULT_ROBOT
from ._robot_specs import LIMIT_MARGIN_RAD as LIMIT_MARGIN_RAD
from ._robot_specs import ROBOT_SPECS as ROBOT_SPECS
from ._robot_specs import RobotSpec as RobotSpec
from ._robot_specs import robot_names as robot_names
from ._robot_specs import robot_spec as robot_spec
from ._robot_specs import robots_folder as robots_folder

IK_DAMPING = 1e-2
"""The damping (lambda, m) of :meth:`RobotArm.inverse`'s least-squares steps by default."""

TOOL_AXES = {
    "z": np.eye(3),
    # tool x along the fingers, tool y kept, tool z opposite the studio's tool x
    "x": np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]),
}
"""A robot's tool axes (columns) in the studio's tool frame (z along the fingers), by approach."""


def tool_errors(
    got: np.ndarray, oMdes: np.ndarray, orientation: bool = True
) -> tuple[float, float]:
    """How far (m) and how turned (rad) a tool pose ``got`` (4x4) is from ``oMdes`` (4x4); the
    angle is 0 when ``orientation`` is not asked (an arm that follows the position only)."""
    distance = float(np.linalg.norm(got[:3, 3] - oMdes[:3, 3]))
    if not orientation:
        return distance, 0.0
    cos = (np.trace(got[:3, :3].T @ oMdes[:3, :3]) - 1.0) / 2.0
    return distance, math.acos(float(np.clip(cos, -1.0, 1.0)))


@dataclass(frozen=True)
class RobotIK:
    """The outcome of :meth:`RobotArm.inverse`.

    Attributes:
        q: joint angles (rad), always within the limits: the solution, or the closest found.
        success: whether the tool reached the target within the tolerances.
        position_error: tool position error (m).
        rotation_error: tool rotation error (rad; 0 when only the position was asked).
        iterations: iterations used: fewer than allowed where the tool reached the target, or
            where the solve stalled (its next step would move no joint further than
            ``STALLED_STEP``, 1e-9 rad).
    """

    q: np.ndarray
    success: bool
    position_error: float
    rotation_error: float
    iterations: int


@dataclass(frozen=True)
class Collision:
    """Two links closer than the margin: ``distance`` is negative when they overlap (m)."""

    link_a: str
    link_b: str
    distance: float


class RobotArm:
    """One robot's arm: Pinocchio model of its arm joints, limits, IK and self-collision.

    Build it with :func:`load_robot` (cached per name). Not thread-safe: one per thread
    (:meth:`scratch_copy` gives another thread its own).

    Attributes:
        spec: the :class:`RobotSpec`.
        name: ``spec.name``.
        model, data: the Pinocchio model of the arm joints and its scratch data.
        visual_model, collision_model: geometry (both empty for a robot loaded without it,
            ``load_robot(name, geometry=False)``).
        joint_names: the URDF's names of the arm joints.
        nq: number of arm joints.
        hard_lower, hard_upper: the URDF's position limits (rad), which an exported URDF keeps.
        limit_margin: how far (rad, per joint) every plan keeps from them
            (:data:`LIMIT_MARGIN_RAD`, :meth:`with_limit_margin`).
        lower, upper: the usable position limits (rad): the hard ones less ``limit_margin``,
            which the IK, the learners and the export's checks keep to.
        velocity: velocity limits (rad/s).
        acceleration: acceleration limits (rad/s^2).
        home: a pose inside the limits the arm starts from (the middle of each joint's range,
            or 0 where 0 is inside it).
        shoulder: the point of the first joint's axis level with the second joint's origin (m,
            base frame): the centre of the arm's reach, whatever the first joint's angle (the
            second joint's origin itself swings around the axis on arms with a shoulder offset,
            such as the UR's).
        reach: the largest distance from ``shoulder`` to the tool over the limits (sampled, m).
        tool_axes: the tool frame's axes in the studio's tool frame, whose z points along the
            fingers (:data:`TOOL_AXES`).
        base_rotation: the URDF's base frame in the studio's robot frame (x where the arm faces,
            z up): a turn about z by ``-spec.facing``. Targets go into the base frame through
            its transpose, and the scene draws the arm turned by it.
        chain: the arm's joints as the compiled IK reads them (:class:`SerialChain`).
        urdf_text: the URDF the model was built from (for export).
    """

    def __init__(
        self,
        spec: RobotSpec,
        model: pin.Model,
        visual_model: pin.GeometryModel,
        collision_model: pin.GeometryModel,
        urdf_text: str,
        srdf: Path | None = None,
    ) -> None:
        self.spec = spec
        self.name = spec.name
        self.model = model
        self.data = model.createData()
        self.visual_model = visual_model
        self.collision_model = collision_model
        self.urdf_text = urdf_text
        self.nq = model.nq
        self.joint_names = tuple(model.names[i] for i in range(1, model.njoints))
        self.hard_lower = np.array(model.lowerPositionLimit, dtype=float)
        self.hard_upper = np.array(model.upperPositionLimit, dtype=float)
        self._set_margin(LIMIT_MARGIN_RAD)
        self.velocity = np.array(model.velocityLimit, dtype=float)
        if spec.acceleration:
            self.acceleration = np.array(spec.acceleration, dtype=float)
        else:
            self.acceleration = 2.0 * self.velocity
        for array in (self.hard_lower, self.hard_upper, self.velocity, self.acceleration):
            array.setflags(write=False)
        self._tool = _frame_id(model, spec)
        self.home = _home(self.joint_names, self.lower, self.upper, srdf)
        self.home.setflags(write=False)
        pin.forwardKinematics(model, self.data, self.home)
        self._elbow_joint = min(spec.elbow, model.njoints - 1)
        self.chain = SerialChain.from_model(model, self._tool, self._elbow_joint)
        self.shoulder = _shoulder(model, self.data, self.chain.axes[0])
        self.tool_axes = TOOL_AXES[spec.approach]
        c, s = math.cos(-spec.facing), math.sin(-spec.facing)
        self.base_rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        self.base_rotation.setflags(write=False)
        self.reach = self._sampled_reach()
        self._collision_data: pin.GeometryData | None = None
        self._table_points = _table_points(collision_model)
        self._table = LinkPoints.from_geometry(collision_model, self._table_points)
        if len(collision_model.geometryObjects):
            self._set_collision_pairs(srdf)

    def _set_margin(self, margin: float) -> None:
        """Usable limits :attr:`lower`, :attr:`upper`: the hard ones less ``margin`` (rad), or
        less a tenth of the joint's range where that is smaller."""
        self.lower, self.upper = usable_limits(self.hard_lower, self.hard_upper, margin)
        self.limit_margin = self.lower - self.hard_lower
        for array in (self.limit_margin, self.lower, self.upper):
            array.setflags(write=False)

    def with_limit_margin(self, margin: float) -> RobotArm:
        """The same robot planning ``margin`` (rad, >= 0) from each hard limit instead of
        :data:`LIMIT_MARGIN_RAD` (its own scratch data, as :meth:`scratch_copy`)."""
        if not (isinstance(margin, int | float) and math.isfinite(margin) and margin >= 0.0):
            raise KinematicsError(
                f"The limit margin is {margin!r}; give a finite number of radians, 0 or more."
            )
        other = self.scratch_copy()
        other._set_margin(float(margin))
        other.home = np.clip(self.home, other.lower, other.upper)
        other.home.setflags(write=False)
        return other

    def scratch_copy(self) -> RobotArm:
        """The same robot with scratch data of its own, for another thread: the model and the
        geometry are shared (never written), the data each computation writes is not."""
        other = copy.copy(self)
        other.data = self.model.createData()
        if self._collision_data is not None:
            other._collision_data = pin.GeometryData(self.collision_model)
        return other

    @property
    def tool_frame(self) -> int:
        """The id of the tool's frame in :attr:`model` (the pose :meth:`forward` gives)."""
        return self._tool

    # ------------------------------------------------------------------------------ kinematics

    def check_q(self, q: object, what: str = "q") -> np.ndarray:
        """``q`` as finite angles of shape (nq,), or a KinematicsError naming the robot."""
        arr = real_array(q, what, f"pass {self.nq} angles in radians")
        if arr.shape != (self.nq,):
            raise KinematicsError(
                f"{what} must have {self.nq} angles for the {self.spec.title}; got shape "
                f"{arr.shape}."
            )
        if not np.all(np.isfinite(arr)):
            raise KinematicsError(f"{what} contains NaN or infinite angles; pass finite radians.")
        return arr

    def forward(self, q: object) -> np.ndarray:
        """The tool pose in the base frame (4x4) at ``q``."""
        arr = self.check_q(q)
        pin.framesForwardKinematics(self.model, self.data, arr)
        return self.data.oMf[self._tool].homogeneous.copy()

    def joint_positions(self, q: object) -> np.ndarray:
        """Each joint's origin in the base frame at ``q``, shape (nq, 3) (m)."""
        arr = self.check_q(q)
        pin.forwardKinematics(self.model, self.data, arr)
        return np.array([self.data.oMi[i].translation for i in range(1, self.model.njoints)])

    def elbow(self, q: np.ndarray) -> np.ndarray:
        """The elbow's position at ``q`` (the third joint's origin; m)."""
        pin.forwardKinematics(self.model, self.data, q)
        return np.array(self.data.oMi[self._elbow_joint].translation)

    def _sampled_reach(self, samples: int = 512) -> float:
        rng = np.random.default_rng(0)
        best = 0.0
        for _ in range(samples):
            q = rng.uniform(self.lower, self.upper)
            pin.framesForwardKinematics(self.model, self.data, q)
            best = max(
                best, float(np.linalg.norm(self.data.oMf[self._tool].translation - self.shoulder))
            )
        return best

    def inverse(
        self,
        oMdes: object,
        q0: object | None = None,
        *,
        position_only: bool | None = None,
        elbow: object | None = None,
        iterations: int = 60,
        elbow_iterations: int = 200,
        position_tolerance: float = 1e-3,
        rotation_tolerance: float = math.radians(1.0),
        damping: float = IK_DAMPING,
        max_step: float = 0.2,
        lower: np.ndarray | None = None,
        upper: np.ndarray | None = None,
    ) -> RobotIK:
        """Joint angles that put the tool at ``oMdes``, by damped least squares within the limits.

        Each iteration takes ``dq = J^T (J J^T + lambda^2 I)^-1 e`` and, for arms with joints to
        spare, a null-space step moving the elbow towards ``elbow``; a joint held at a limit
        that the step would push beyond is left out of it (the others make up for it), and the
        result is projected onto the limits, so every returned ``q`` is within them.

        Args:
            oMdes: the tool's target pose (4x4) in the base frame, or its position (3,).
            q0: where to start (the previous frame's answer keeps motion continuous); default
                :attr:`home`.
            position_only: match the position only (default: when the spec says so or the
                target is a position).
            elbow: where the elbow should stay (3,), used in the null space only.
            elbow_iterations: null-space steps allowed once the tool is on target (a live
                caller takes one per frame and lets the elbow settle over frames).
            iterations, position_tolerance, rotation_tolerance, damping, max_step: the solver's
                settings (max_step in rad per iteration, infinity norm).
            lower, upper: bounds tighter than the limits for this solve (rad, within
                :attr:`lower`..:attr:`upper`), such as the joint motion one frame allows.

        Returns:
            A :class:`RobotIK`.
        """
        target = real_array(oMdes, "oMdes", "pass a 4x4 pose or a 3-vector position")
        if target.shape == (3,):
            target_p, target_R, pos_only = target, np.eye(3), True
        elif target.shape == (4, 4) and np.all(np.isfinite(target)):
            target_p, target_R = target[:3, 3], target[:3, :3]
            pos_only = (not self.spec.orientation) if position_only is None else position_only
        else:
            raise KinematicsError(
                f"oMdes must be a 4x4 pose or a 3-vector of finite numbers; got shape {target.shape}."
            )
        if position_only:
            pos_only = True
        lower = self.lower if lower is None else np.maximum(self.lower, lower)
        upper = self.upper if upper is None else np.minimum(self.upper, upper)
        q = np.clip(self.home if q0 is None else self.check_q(q0, "q0"), lower, upper)
        elbow_target = None if elbow is None else real_array(elbow, "elbow").reshape(3)
        settings = ChainSolve(
            iterations=iterations,
            elbow_iterations=elbow_iterations,
            position_tolerance=position_tolerance,
            rotation_tolerance=rotation_tolerance,
            damping=damping,
            max_step=max_step,
        )
        q, pos_err, rot_err, it = solve(
            self.chain,
            lower,
            upper,
            q,
            target_R,
            target_p,
            pos_only,
            elbow_target,
            settings,
        )
        success = pos_err <= position_tolerance and rot_err <= rotation_tolerance
        return RobotIK(q, bool(success), pos_err, rot_err, it)

    # ------------------------------------------------------------------------- self-collision

    def _set_collision_pairs(self, srdf: Path | None) -> None:
        geom = self.collision_model
        geom.addAllCollisionPairs()
        if srdf is not None and srdf.is_file():
            pin.removeCollisionPairs(self.model, geom, str(srdf))
        parents = self.model.parents
        keep = []
        for pair in geom.collisionPairs:
            a = geom.geometryObjects[pair.first].parentJoint
            b = geom.geometryObjects[pair.second].parentJoint
            if a == b or parents[a] == b or parents[b] == a:
                continue  # the same link, or adjacent links: they touch by design
            links = {
                _link_of(geom.geometryObjects[pair.first].name),
                _link_of(geom.geometryObjects[pair.second].name),
            }
            if any(links == set(close) for close in self.spec.close_by_design):
                continue
            keep.append(pair)
        geom.removeAllCollisionPairs()
        for pair in keep:
            geom.addCollisionPair(pair)
        self._collision_data = pin.GeometryData(geom)
        if srdf is None:
            # No SRDF: as MoveIt's setup does, pairs already touching at home are taken to touch
            # by design (meshes drawn overlapping at a folded rest pose).
            touching = {(c.link_a, c.link_b) for c in self.self_collisions(self.home)}
            for k in reversed(range(len(geom.collisionPairs))):
                pair = geom.collisionPairs[k]
                names = (
                    _link_of(geom.geometryObjects[pair.first].name),
                    _link_of(geom.geometryObjects[pair.second].name),
                )
                if names in touching:
                    geom.removeCollisionPair(pair)
            self._collision_data = pin.GeometryData(geom)

    def self_collisions(self, q: object, margin: float = 0.0) -> list[Collision]:
        """The link pairs closer than ``margin`` at ``q`` (overlaps have negative distances).

        An arm loaded without collision geometry (``geometry=False``) reports none.
        """
        arr = self.check_q(q)
        if self._collision_data is None:
            return []
        # Fresh scratch data for every query: coal warm-starts each pair's GJK from its previous
        # answer, and near contact that made the same pose read clear once and touching the next.
        geom = self.collision_model
        gdata = pin.GeometryData(geom)
        pin.computeDistances(self.model, self.data, geom, gdata, arr)
        found = []
        for k, pair in enumerate(geom.collisionPairs):
            distance = float(gdata.distanceResults[k].min_distance)
            if distance < margin:
                a = geom.geometryObjects[pair.first].name
                b = geom.geometryObjects[pair.second].name
                found.append(Collision(_link_of(a), _link_of(b), distance))
        return sorted(found, key=lambda c: c.distance)

    def table_contacts(self, q: object, margin: float = 0.0) -> list[Collision]:
        """The links lower than ``margin`` above the table the robot stands on, at ``q``:
        ``Collision(link, TABLE, height)`` with the height (m) of the link's lowest point above
        the plane of the robot's base (negative below it), lowest first.

        A robot of :func:`load_robot` is mounted on a table whose top is that plane; the links
        the first joint turns about the vertical (and the base) stay where they stand, the
        others (an elbow, a wrist, the hand) can be driven into it. An arm loaded without collision
        geometry (``geometry=False``) reports none.
        """
        arr = self.check_q(q)
        if not self._table_points:
            return []
        heights = self._table.heights(self.chain, arr, margin)  # compiled: every pose asks
        lowest: dict[str, float] = {}
        for i in np.flatnonzero(heights < margin):
            link = _link_of(self.collision_model.geometryObjects[self._table_points[i][0]].name)
            lowest[link] = min(lowest.get(link, math.inf), float(heights[i]))
        found = [Collision(link, TABLE, z) for link, z in lowest.items()]
        return sorted(found, key=lambda c: c.distance)

    def contacts(self, q: object, margin: float = 0.0) -> list[Collision]:
        """:meth:`self_collisions` and :meth:`table_contacts` at ``q``: every contact within
        ``margin`` a pose must not make, closest first."""
        found = self.self_collisions(q, margin) + self.table_contacts(q, margin)
        return sorted(found, key=lambda c: c.distance)

    @property
    def checks_collisions(self) -> bool:
        """Whether :meth:`self_collisions` has geometry to check."""
        return self._collision_data is not None


def _shoulder(model: pin.Model, data: pin.Data, axis: np.ndarray) -> np.ndarray:
    """The point of joint 1's axis nearest joint 2's origin (``data`` holds a forward pass)."""
    base = data.oMi[1]
    origin, direction = np.array(base.translation), base.rotation @ axis
    second = np.array(data.oMi[min(2, model.njoints - 1)].translation)
    return origin + direction * float(direction @ (second - origin))


def usable_limits(lower: np.ndarray, upper: np.ndarray, margin: float = LIMIT_MARGIN_RAD) -> tuple:
    """Hard limits less ``margin`` (rad), or less a tenth of a joint's range where smaller."""
    kept = np.minimum(float(margin), 0.1 * (np.asarray(upper) - np.asarray(lower)))
    return np.asarray(lower) + kept, np.asarray(upper) - kept


def _home(
    names: tuple[str, ...], lower: np.ndarray, upper: np.ndarray, srdf: Path | None
) -> np.ndarray:
    """The SRDF's ``home`` or ``default`` state, else 0 where allowed and mid-range elsewhere."""
    zero_inside = (lower <= 0.0) & (upper >= 0.0)
    home = np.where(zero_inside, 0.0, 0.5 * (lower + upper))
    if srdf is not None and srdf.is_file():
        text = srdf.read_text()
        for state in ("home", "default"):
            block = re.search(rf'<group_state\s+name="{state}".*?</group_state>', text, re.S)
            if block is None:
                continue
            values = dict(re.findall(r'<joint\s+name="([^"]+)"\s+value="([^"]+)"', block.group(0)))
            for i, name in enumerate(names):
                if name in values:
                    home[i] = float(values[name])
            break
    return np.clip(home, lower, upper)


def _frame_id(model: pin.Model, spec: RobotSpec) -> int:
    """The tool frame's id (a link's frame when a joint has the same name)."""
    matches = [i for i, frame in enumerate(model.frames) if frame.name == spec.tool]
    if not matches:
        raise KinematicsError(
            f"The {spec.title} model has no frame {spec.tool!r}; its URDF changed: report it."
        )
    bodies = [i for i in matches if model.frames[i].type == pin.FrameType.BODY]
    return (bodies or matches)[0]


TABLE = "table"
"""The name :meth:`RobotArm.table_contacts` gives the table the robot stands on."""


def _table_points(
    geom: pin.GeometryModel,
) -> list[tuple[int, np.ndarray, np.ndarray, float]]:
    """For each collision geometry a joint after the first moves: its index, the points (in its
    own frame) its lowest point is among (a convex hull's vertices, a box's corners), and the
    centre and radius of a sphere around them (a quick test that it clears the table)."""
    found = []
    for k, obj in enumerate(geom.geometryObjects):
        if obj.parentJoint < 2:  # the base, or a link turned about the vertical first axis
            continue
        points = shape_points(obj.geometry)
        if len(points):
            centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
            radius = float(np.linalg.norm(points - centre, axis=1).max())
            found.append((k, points, centre, radius))
    return found


def shape_points(shape: object) -> np.ndarray:
    """A collision shape's points in its own frame: a convex hull's vertices, else its box's."""
    if hasattr(shape, "points") and callable(shape.points):
        return np.array([np.array(p, dtype=float) for p in shape.points()])
    shape.computeLocalAABB()
    low, high = np.array(shape.aabb_local.min_), np.array(shape.aabb_local.max_)
    corners = [
        (x, y, z) for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])
    ]
    return np.array(corners)


def _link_of(geometry_name: str) -> str:
    """A geometry object's link (Pinocchio names them ``<link>_<index>``)."""
    head, _, tail = geometry_name.rpartition("_")
    return head if head and tail.isdigit() else geometry_name
