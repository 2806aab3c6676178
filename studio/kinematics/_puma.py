"""The Puma560 arm: Corke's standard-DH model as a Pinocchio model.

The model is built programmatically from the DH table (``DH_TABLE``), so forward kinematics is
exactly standard DH: ``0T6 = prod_i Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``. Each Pinocchio joint i
sits at DH frame i-1 and turns about its z axis; the fixed part ``Tz(d_i) Tx(a_i) Rx(alpha_i)``
is the placement of the next joint. The base frame (Pinocchio's universe) lies on the floor under
joint 1, so d1 = 0.67183 m is the pedestal, and the tool frame is DH frame 6 (the wrist centre;
Corke's model has no tool transform).

The model is immutable and one ``pinocchio.Data`` is kept as scratch space, so a ``Puma560`` is
cheap to call per frame but is not thread-safe: give each thread its own instance.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import pinocchio as pin

from ._checks import KinematicsError, positive_number, real_array, whole_number
from ._dh import DH_TABLE, DHRow, LinkVisual, urdf_from_dh

__all__ = [
    "DH_TABLE",
    "PUMA_QN",
    "PUMA_QR",
    "PUMA_QS",
    "PUMA_QZ",
    "DHRow",
    "IKConfig",
    "IKResult",
    "LinkVisual",
    "Puma560",
]


#: Zero angles: upper arm horizontal, forearm vertical.
PUMA_QZ = np.zeros(6)
#: The vertical "ready" pose.
PUMA_QR = np.array([0.0, math.pi / 2, -math.pi / 2, 0.0, 0.0, 0.0])
#: Corke's nominal, non-singular table-top pose. Its q3 = pi lies outside joint 3's +-135 deg
#: limit (as in the toolbox); ``forward`` accepts it, ``inverse`` never returns it.
PUMA_QN = np.array([0.0, math.pi / 4, math.pi, 0.0, math.pi / 4, 0.0])
#: The arm stretched out along x.
PUMA_QS = np.array([0.0, 0.0, -math.pi / 2, 0.0, 0.0, 0.0])

for _named in (PUMA_QZ, PUMA_QR, PUMA_QN, PUMA_QS):
    _named.setflags(write=False)


@dataclass(frozen=True)
class IKConfig:
    """Defaults of the damped-least-squares IK, documented once.

    Attributes:
        max_iterations: iterations per attempt (the warm-started one, then one per closed-form
            seed).
        tolerance: success when the error norm falls below this (m for position-only; the
            norm of [position error in m, rotation error in rad] for a full pose).
        damping: DLS damping lambda; keeps steps bounded near singularities (q5 = 0 is one).
        max_step: largest joint step per iteration (rad, infinity norm), so that the linear
            model stays valid far from the target.
        stall_steps: give up an attempt when the error has not dropped by ``stall_ratio``
            over this many iterations (stuck on a limit or a local minimum).
        stall_ratio: the relative improvement that counts as progress.
    """

    max_iterations: int = 100
    tolerance: float = 1e-6
    damping: float = 1e-3
    max_step: float = 0.5
    stall_steps: int = 10
    stall_ratio: float = 1e-3

    def __post_init__(self) -> None:
        whole_number(self.max_iterations, "IKConfig.max_iterations", 1)
        whole_number(self.stall_steps, "IKConfig.stall_steps", 1)
        for name in ("tolerance", "damping", "max_step", "stall_ratio"):
            positive_number(getattr(self, name), f"IKConfig.{name}")


@dataclass(frozen=True)
class IKResult:
    """The outcome of :meth:`Puma560.inverse`.

    Attributes:
        q: joint angles (rad, shape (6,)), always within the joint limits: the solution when
            ``success``, else the closest configuration found.
        success: whether the error fell below the tolerance.
        error: the final error norm (m for position-only; for a full pose the norm of
            [position error in m, rotation error in rad]).
        iterations: total iterations over all attempts.
        message: one sentence saying what happened (and what to change on failure).
    """

    q: np.ndarray
    success: bool
    error: float
    iterations: int
    message: str


def _pose(xyz: Sequence[float] = (0.0, 0.0, 0.0), axis: Literal["x", "y", "z"] = "z") -> np.ndarray:
    """A 4x4 pose at ``xyz`` whose z axis points along the given axis of the parent frame."""
    pose = np.eye(4)
    if axis == "x":
        pose[:3, :3] = pin.utils.rotate("y", math.pi / 2)
    elif axis == "y":
        pose[:3, :3] = pin.utils.rotate("x", -math.pi / 2)
    pose[:3, 3] = xyz
    pose.setflags(write=False)
    return pose


@dataclass(frozen=True)
class VisualStyle:
    """Sizes and colours of the robot's picture (only looks; the kinematics ignore them)."""

    pedestal_radius: float = 0.09
    plate_size: float = 0.36
    plate_thickness: float = 0.03
    shoulder_radius: float = 0.1
    shoulder_length: float = 0.24
    upper_arm_radius: float = 0.065
    elbow_radius: float = 0.07
    forearm_radius: float = 0.05
    wrist_radius: float = 0.045
    flange_radius: float = 0.03
    flange_length: float = 0.04
    tool_size: tuple[float, float, float] = (0.03, 0.08, 0.05)
    dark: tuple[float, float, float] = (0.25, 0.26, 0.28)
    body: tuple[float, float, float] = (0.86, 0.84, 0.78)
    accent: tuple[float, float, float] = (0.93, 0.55, 0.14)


def _build_visuals(dh: Sequence[DHRow], style: VisualStyle) -> tuple[LinkVisual, ...]:
    """Solids derived from the DH geometry, each in its DH frame (see ``LinkVisual``)."""
    d1, a2, d3, a3, d4 = dh[0].d, dh[1].a, dh[2].d, dh[2].a, dh[3].d
    pedestal = d1 - style.shoulder_radius
    tool_z = style.flange_length + style.tool_size[2] / 2
    return (
        LinkVisual(
            "base_plate",
            0,
            "box",
            (style.plate_size, style.plate_size, style.plate_thickness),
            _pose((0, 0, style.plate_thickness / 2)),
            style.dark,
        ),
        LinkVisual(
            "pedestal",
            0,
            "cylinder",
            (style.pedestal_radius, pedestal),
            _pose((0, 0, pedestal / 2)),
            style.dark,
        ),
        # DH frame 1 sits at the shoulder: y1 is up (joint 1's axis), z1 is joint 2's axis.
        LinkVisual(
            "waist",
            1,
            "cylinder",
            (style.pedestal_radius, style.shoulder_radius),
            _pose((0, -style.shoulder_radius / 2, 0), "y"),
            style.body,
        ),
        LinkVisual(
            "shoulder",
            1,
            "cylinder",
            (style.shoulder_radius, style.shoulder_length),
            _pose((0, 0, 0), "z"),
            style.body,
        ),
        # DH frame 2 sits on joint 3's axis at the elbow; the upper arm runs back along -x2.
        LinkVisual(
            "upper_arm",
            2,
            "cylinder",
            (style.upper_arm_radius, a2),
            _pose((-a2 / 2, 0, 0), "x"),
            style.body,
        ),
        LinkVisual(
            "elbow",
            2,
            "cylinder",
            (style.elbow_radius, d3 + 2 * style.elbow_radius),
            _pose((0, 0, d3 / 2), "z"),
            style.body,
        ),
        # DH frame 3: z3 runs along the forearm (joint 4's axis) to the wrist centre.
        LinkVisual(
            "elbow_offset",
            3,
            "cylinder",
            (style.forearm_radius, a3 + style.forearm_radius),
            _pose((-a3 / 2, 0, 0), "x"),
            style.body,
        ),
        LinkVisual(
            "forearm",
            3,
            "cylinder",
            (style.forearm_radius, d4),
            _pose((0, 0, d4 / 2), "z"),
            style.body,
        ),
        # DH frame 4: the wrist centre, z4 along joint 5's axis.
        LinkVisual(
            "wrist",
            4,
            "sphere",
            (style.wrist_radius,),
            _pose(),
            style.dark,
        ),
        # DH frame 6: the tool frame (wrist centre), z6 the approach direction.
        LinkVisual(
            "flange",
            6,
            "cylinder",
            (style.flange_radius, style.flange_length),
            _pose((0, 0, style.flange_length / 2), "z"),
            style.dark,
        ),
        LinkVisual(
            "tool",
            6,
            "box",
            style.tool_size,
            _pose((0, 0, tool_z), "z"),
            style.accent,
        ),
    )


def _as_vector(value: object, size: int, what: str) -> np.ndarray:
    """``value`` as a finite float vector of ``size``, or a KinematicsError naming ``what``."""
    array = real_array(value, what, f"pass {size} numbers")
    if array.shape != (size,):
        raise KinematicsError(
            f"{what} must have shape ({size},), got {array.shape}; pass one value per joint."
            if what.startswith("q")
            else f"{what} must have shape ({size},), got {array.shape}; pass {size} numbers."
        )
    if not np.isfinite(array).all():
        raise KinematicsError(f"{what} contains NaN or infinite values; pass finite numbers.")
    return array


_LAST_ROW = np.array([0.0, 0.0, 0.0, 1.0])
_EYE3 = np.eye(3)
#: How far from (0, 0, 0, 1) a pose's last row and from orthonormal its rotation may be (float
#: noise of poses composed in single or double precision), before the pose counts as malformed.
_POSE_ATOL = 1e-9
_ROTATION_ATOL = 1e-6


def _as_pose(value: object, what: str, check_rotation: bool) -> np.ndarray:
    """``value`` (4x4 array or ``pin.SE3``) as a finite homogeneous pose, or a KinematicsError."""
    if isinstance(value, pin.SE3):
        value = value.homogeneous
    pose = real_array(value, what, "pass a 4x4 homogeneous pose")
    if pose.shape != (4, 4):
        raise KinematicsError(f"{what} must be a 4x4 homogeneous pose, got shape {pose.shape}.")
    if not np.isfinite(pose).all():
        raise KinematicsError(f"{what} contains NaN or infinite values; pass a finite pose.")
    if np.abs(pose[3] - _LAST_ROW).max() > _POSE_ATOL:
        raise KinematicsError(f"{what} must end with the row (0, 0, 0, 1), got {pose[3]}.")
    if check_rotation:
        r = pose[:3, :3]
        (a, b, c), (d, e, f), (g, h, i) = r.tolist()
        det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
        if np.abs(r.T @ r - _EYE3).max() > _ROTATION_ATOL or det < 0:
            raise KinematicsError(
                f"{what} has a rotation block that is not a proper rotation matrix; "
                "orthonormalise it (or pass position_only=True)."
            )
    return pose


#: How far (rad) a closed-form angle may lie beyond a limit through rounding alone.
_LIMIT_SLACK = 1e-9

_TURNS = tuple(k * 2 * math.pi for k in (0, -1, 1, -2, 2))


def _wrap_into_limits(
    q: Sequence[float], q_ref: Sequence[float], lower: Sequence[float], upper: Sequence[float]
) -> list[float] | None:
    """``q`` with each angle moved by whole turns into its limits, nearest ``q_ref``; None if
    some angle fits no turn (joints 4 and 6 span more than one turn, so several may fit)."""
    out = []
    for angle, ref, low, high in zip(q, q_ref, lower, upper, strict=True):
        # A target made at a joint limit comes back from the trigonometry a rounding error
        # beyond it: accept that, and clip it onto the limit.
        options = [
            min(max(angle + turn, low), high)
            for turn in _TURNS
            if low - _LIMIT_SLACK <= angle + turn <= high + _LIMIT_SLACK
        ]
        if not options:
            return None
        out.append(min(options, key=lambda v, ref=ref: abs(v - ref)))
    return out


def _rz_rx(theta: float, alpha: float) -> np.ndarray:
    """The rotation ``Rz(theta) Rx(alpha)`` of one DH row."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array([[ct, -st * ca, st * sa], [st, ct * ca, -ct * sa], [0.0, sa, ca]])


def closed_form_solutions(
    dh: Sequence[DHRow],
    p: np.ndarray,
    R: np.ndarray | None,
    q_ref: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
) -> list[np.ndarray]:
    """The Puma's closed-form IK solutions within the limits, nearest ``q_ref`` first.

    Valid for Puma-shaped DH tables (a1 = d2 = 0, alpha = (pi/2, 0, -pi/2, pi/2, -pi/2, 0),
    d5 = d6 = a4..a6 = 0: a spherical wrist whose centre is the tool). Up to eight branches:
    shoulder left/right, elbow up/down, wrist flip. The wrist centre fixes q1..q3; with
    ``R is None`` (position only) the wrist angles are kept from ``q_ref``.

    Args:
        dh: the DH table.
        p: tool position in the base frame.
        R: tool rotation in the base frame, or None for position only.
        q_ref: the angles to stay near (rad, shape (6,)).
        lower, upper: joint limits (rad).

    Returns:
        The solutions (possibly none), each of shape (6,).
    """
    d1, a2, d3, a3, d4 = dh[0].d, dh[1].a, dh[2].d, dh[2].a, dh[3].d
    px, py, pz = (float(v) for v in p)
    ref, low, high = q_ref.tolist(), lower.tolist(), upper.tolist()
    radial = math.hypot(px, py)
    if radial < abs(d3):
        return []  # inside the cylinder the shoulder offset d3 sweeps: unreachable
    phi = math.atan2(py, px)
    lean = math.asin(d3 / radial)
    forearm = math.hypot(a3, d4)
    beta = math.atan2(d4, a3)
    Y = pz - d1
    solutions: list[list[float]] = []
    for q1 in (phi + lean, phi + math.pi - lean):
        X = px * math.cos(q1) + py * math.sin(q1)
        cos_elbow = (X * X + Y * Y - a2 * a2 - forearm * forearm) / (2 * a2 * forearm)
        if abs(cos_elbow) > 1.0 + 1e-12:
            continue
        elbow = math.acos(max(-1.0, min(1.0, cos_elbow)))
        for u in (elbow, -elbow):
            q3 = u - beta
            q2 = math.atan2(Y, X) - math.atan2(forearm * math.sin(u), a2 + forearm * math.cos(u))
            if R is None:
                wrists = [ref[3:6]]
            else:
                R03 = _rz_rx(q1, dh[0].alpha) @ _rz_rx(q2, dh[1].alpha) @ _rz_rx(q3, dh[2].alpha)
                (m00, _, m02), (m10, _, m12), (m20, m21, m22) = (R03.T @ R).tolist()
                s5 = math.hypot(m02, m12)
                if s5 < 1e-9:  # wrist singular: only q4 + q6 matters; keep q4 from q_ref
                    if m22 < 0:
                        continue  # q5 = pi is beyond joint 5's limits
                    wrists = [[ref[3], 0.0, math.atan2(m10, m00) - ref[3]]]
                else:
                    q4 = math.atan2(-m12, -m02)
                    q5 = math.atan2(s5, m22)
                    q6 = math.atan2(-m21, m20)
                    wrists = [[q4, q5, q6], [q4 + math.pi, -q5, q6 + math.pi]]
            for wrist in wrists:
                q = _wrap_into_limits([q1, q2, q3, *wrist], ref, low, high)
                if q is not None:
                    solutions.append(q)
    solutions.sort(key=lambda q: sum((a - b) ** 2 for a, b in zip(q, ref, strict=True)))
    return [np.array(q) for q in solutions]


class Puma560:
    """The Puma560 arm (Corke's standard DH model) with FK, Jacobian and DLS IK.

    Args:
        ik: defaults of :meth:`inverse`.
        style: sizes and colours of :meth:`visuals`.

    Attributes:
        model: the immutable Pinocchio model: joints ``joint1`` ... ``joint6``, operational
            frames ``dh1`` ... ``dh6`` (the DH frames) and ``tool``.
        data: Pinocchio scratch space (one per instance, hence not thread-safe).
        dh: the DH table (``DH_TABLE``).
        nq: number of joints (6).
        lower, upper: joint limits (rad, shape (6,), read-only).
        qz, qr, qn, qs: Corke's named poses (see ``PUMA_QZ`` etc.).
        reach: largest distance from the shoulder (joint 2's axis on joint 1's) to the tool (m).
        name: its name in the robot registry (:func:`studio.kinematics.load_robot` loads the
            same robot, built from the same DH table, as a ``RobotArm``).
    """

    name = "puma560"
    nq = 6
    qz = PUMA_QZ
    qr = PUMA_QR
    qn = PUMA_QN
    qs = PUMA_QS

    def __init__(self, ik: IKConfig | None = None, style: VisualStyle | None = None) -> None:
        self.ik = ik or IKConfig()
        self.style = style or VisualStyle()
        self.dh = DH_TABLE
        self.model = self._build_model()
        self.data = self.model.createData()
        self.lower = np.array([row.lower for row in self.dh])
        self.upper = np.array([row.upper for row in self.dh])
        self.lower.setflags(write=False)
        self.upper.setflags(write=False)
        self._tool = self.model.getFrameId("tool")
        # jointMframe: DH frame i in Pinocchio joint i's frame (identity for the base).
        self._jointMdh = [pin.SE3.Identity()] + [row.fixed() for row in self.dh]
        self._jointMtool = self.model.frames[self._tool].placement
        self._damping3 = np.eye(3) * self.ik.damping**2
        self._damping6 = np.eye(6) * self.ik.damping**2
        self._visuals = _build_visuals(self.dh, self.style)
        self._visual_joints = np.array([v.joint for v in self._visuals])
        self._visual_offsets = np.stack([v.offset for v in self._visuals])
        self._shoulder = np.array([0.0, 0.0, self.dh[0].d])
        forearm = math.hypot(self.dh[2].a, self.dh[3].d)
        self.reach = math.hypot(self.dh[1].a + forearm, self.dh[2].d)

    def _build_model(self) -> pin.Model:
        model = pin.Model()
        model.name = self.name
        parent, placement = 0, pin.SE3.Identity()
        for i, row in enumerate(self.dh, start=1):
            parent = model.addJoint(parent, pin.JointModelRZ(), placement, f"joint{i}")
            model.addJointFrame(parent)
            model.addFrame(pin.Frame(f"dh{i}", parent, row.fixed(), pin.FrameType.OP_FRAME))
            placement = row.fixed()
        model.addFrame(pin.Frame("tool", parent, self.dh[-1].fixed(), pin.FrameType.OP_FRAME))
        model.lowerPositionLimit = np.array([row.lower for row in self.dh])
        model.upperPositionLimit = np.array([row.upper for row in self.dh])
        model.velocityLimit = np.array([row.velocity for row in self.dh])
        model.effortLimit = np.array([row.effort for row in self.dh])
        return model

    # ----------------------------------------------------------------------------- kinematics

    def forward(self, q: object) -> np.ndarray:
        """The tool pose in the base frame, ``oMtool``.

        Args:
            q: joint angles (rad), shape (6,). Angles outside the limits are accepted.

        Returns:
            A new 4x4 homogeneous matrix.

        Raises:
            KinematicsError: ``q`` has the wrong shape or is not finite.
        """
        q = _as_vector(q, self.nq, "q")
        pin.forwardKinematics(self.model, self.data, q)
        return (self.data.oMi[self.nq] * self._jointMtool).homogeneous

    def joint_frames(self, q: object) -> np.ndarray:
        """The base frame and the six DH frames, for drawing.

        Element 0 is the base (floor under joint 1), element i the standard-DH frame i (the
        frame carried by joint i, origin at the end of link i); element 6 is the tool frame.

        Args:
            q: joint angles (rad), shape (6,).

        Returns:
            Array of shape (7, 4, 4), poses in the base frame.
        """
        q = _as_vector(q, self.nq, "q")
        pin.forwardKinematics(self.model, self.data, q)
        frames = np.empty((self.nq + 1, 4, 4))
        frames[0] = np.eye(4)
        for i in range(1, self.nq + 1):
            frames[i] = (self.data.oMi[i] * self._jointMdh[i]).homogeneous
        return frames

    def jacobian(self, q: object) -> np.ndarray:
        """The tool Jacobian in the base frame ("local world aligned").

        Rows 0-2 map joint rates to the velocity of the tool origin, rows 3-5 to the tool's
        angular velocity, both expressed in the base frame: ``[v; w] = J(q) dq``.

        Args:
            q: joint angles (rad), shape (6,).

        Returns:
            Array of shape (6, 6).
        """
        q = _as_vector(q, self.nq, "q")
        return self._jacobian(q).copy()

    def _jacobian(self, q: np.ndarray) -> np.ndarray:
        """Jacobian (world aligned) and, as a side effect, ``data.oMf[tool]`` at ``q``."""
        pin.computeJointJacobians(self.model, self.data, q)
        pin.updateFramePlacement(self.model, self.data, self._tool)
        return pin.getFrameJacobian(
            self.model, self.data, self._tool, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )

    # ------------------------------------------------------------------------------------ IK

    def inverse(
        self,
        oMdes: object,
        q0: object | None = None,
        position_only: bool = False,
        max_iterations: int | None = None,
        tolerance: float | None = None,
    ) -> IKResult:
        """Joint angles that put the tool at ``oMdes``, by damped least squares.

        Each iteration takes the DLS step ``dq = J^T (J J^T + lambda^2 I)^-1 e`` and projects
        the result onto the joint limits, so every returned ``q`` is within them. The first
        attempt starts from ``q0`` (warm start, e.g. the previous frame's solution). If it
        fails (a joint limit or a local minimum in the way), or when there is no ``q0``, the
        Puma's closed-form solutions that lie within the limits seed the attempts, nearest to
        ``q0`` first, so a reachable target is always found. Failure is reported (``success=False`` and a
        message), with ``q`` the closest configuration found.

        Args:
            oMdes: desired tool pose in the base frame (4x4 or ``pin.SE3``); with
                ``position_only`` a 3-vector position is accepted too.
            q0: starting angles (rad, shape (6,)); clipped to the limits. Default: none; the
                solution nearest ``qn`` (with joint 3 folded into its limits) is returned.
            position_only: match the tool position only and leave its orientation free.
            max_iterations: iterations per attempt (default ``IKConfig.max_iterations``).
            tolerance: success threshold on the error norm (default ``IKConfig.tolerance``).

        Returns:
            An :class:`IKResult`.

        Raises:
            KinematicsError: a malformed target, ``q0`` or setting.
        """
        cfg = self.ik
        iterations_per_attempt = whole_number(
            cfg.max_iterations if max_iterations is None else max_iterations, "max_iterations", 1
        )
        tol = positive_number(cfg.tolerance if tolerance is None else tolerance, "tolerance")

        if isinstance(oMdes, pin.SE3):
            oMdes = oMdes.homogeneous
        oMdes = real_array(oMdes, "oMdes", "pass a 4x4 pose (or a 3-vector with position_only)")
        if position_only and oMdes.shape == (3,):
            target_p = _as_vector(oMdes, 3, "the target position")
            target_R = np.eye(3)
        else:
            pose = _as_pose(oMdes, "oMdes", check_rotation=not position_only)
            target_p, target_R = pose[:3, 3].copy(), pose[:3, :3].copy()
        start = self._default_seed() if q0 is None else _as_vector(q0, self.nq, "q0")
        start = np.clip(start, self.lower, self.upper)

        distance = float(np.linalg.norm(target_p - self._shoulder))
        if distance > self.reach + tol:
            return IKResult(
                q=start,
                success=False,
                error=distance - self.reach,
                iterations=0,
                message=(
                    f"the target is {distance:.3f} m from the shoulder, beyond the arm's reach "
                    f"of {self.reach:.3f} m; move it closer."
                ),
            )

        best_q, best_err, total = start, math.inf, 0
        candidates: list[np.ndarray] | None = None
        seed: np.ndarray | None = start
        if q0 is None:  # nothing to stay near: start from the closed form's nearest solution
            candidates = self._closed_form(target_p, target_R, position_only, start)
            seed = candidates.pop(0) if candidates else start
        while seed is not None:
            q, err, used = self._solve(
                seed, target_p, target_R, position_only, iterations_per_attempt, tol
            )
            total += used
            if err < best_err:
                best_q, best_err = q, err
            if err <= tol:
                return IKResult(
                    q=q,
                    success=True,
                    error=err,
                    iterations=total,
                    message=f"converged to {err:.1e} in {total} iterations.",
                )
            if candidates is None:
                candidates = self._closed_form(target_p, target_R, position_only, start)
            seed = candidates.pop(0) if candidates else None
        unit = "m" if position_only else "(m, rad norm)"
        return IKResult(
            q=best_q,
            success=False,
            error=best_err,
            iterations=total,
            message=(
                f"no configuration within the joint limits reaches the target: the closest "
                f"found is {best_err:.3g} {unit} away; move the target"
                + ("." if position_only else " or use position_only=True.")
            ),
        )

    def _closed_form(
        self, p: np.ndarray, R: np.ndarray, position_only: bool, q_ref: np.ndarray
    ) -> list[np.ndarray]:
        return closed_form_solutions(
            self.dh, p, None if position_only else R, q_ref, self.lower, self.upper
        )

    def _default_seed(self) -> np.ndarray:
        """A non-singular pose inside the limits (``qn`` with joint 3 folded back in range)."""
        return np.clip(
            np.array([0.0, math.pi / 4, -math.pi / 2, 0.0, math.pi / 4, 0.0]),
            self.lower,
            self.upper,
        )

    def _solve(
        self,
        q: np.ndarray,
        target_p: np.ndarray,
        target_R: np.ndarray,
        position_only: bool,
        max_iterations: int,
        tol: float,
    ) -> tuple[np.ndarray, float, int]:
        """One projected-DLS attempt from ``q``: (final q, final error norm, iterations)."""
        cfg = self.ik
        model, data, tool = self.model, self.data, self._tool
        damping = self._damping3 if position_only else self._damping6
        lower, upper = self.lower, self.upper
        rows = 3 if position_only else 6
        e = np.empty(rows)
        q = q.copy()
        last_progress_err, last_progress_it = math.inf, 0
        err_norm = math.inf
        for it in range(max_iterations + 1):
            pin.forwardKinematics(model, data, q)
            oMtool = pin.updateFramePlacement(model, data, tool)
            e[:3] = target_p - oMtool.translation
            if not position_only:
                e[3:] = pin.log3(target_R @ oMtool.rotation.T)
            err_norm = math.sqrt(float(e @ e))
            if err_norm <= tol or it == max_iterations:
                return q, err_norm, it
            if err_norm < last_progress_err * (1.0 - cfg.stall_ratio):
                last_progress_err, last_progress_it = err_norm, it
            elif it - last_progress_it >= cfg.stall_steps:
                return q, err_norm, it
            pin.computeJointJacobians(model, data, q)
            J = pin.getFrameJacobian(model, data, tool, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            if position_only:
                J = J[:3]
            dq = J.T @ np.linalg.solve(J @ J.T + damping, e)
            biggest = max(float(dq.max()), -float(dq.min()))
            if biggest > cfg.max_step:
                dq *= cfg.max_step / biggest
            q = np.minimum(np.maximum(q + dq, lower), upper)
        return q, err_norm, max_iterations

    # ------------------------------------------------------------------------------- visuals

    def visuals(self) -> list[LinkVisual]:
        """The robot's picture: simple solids derived from the DH geometry.

        Each solid is attached to one of :meth:`joint_frames` (``LinkVisual.joint``); its world
        pose is ``joint_frames(q)[v.joint] @ v.offset`` (see :meth:`visual_poses`).
        """
        return list(self._visuals)

    def visual_poses(self, q: object) -> np.ndarray:
        """World poses of :meth:`visuals` at ``q``, shape (len(visuals), 4, 4)."""
        frames = self.joint_frames(q)
        return frames[self._visual_joints] @ self._visual_offsets

    def urdf(self) -> str:
        """A URDF of this robot that Pinocchio and yourdfpy load: its joints with their position,
        speed and torque limits, and :meth:`visuals` as its visual and collision shapes (a file
        that needs no mesh; the robot registry's ``load_robot("puma560")`` carries the meshes)."""
        return urdf_from_dh(self.dh, self.visuals())
