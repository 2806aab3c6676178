"""Compiled damped-least-squares IK for a serial chain of revolute joints (every offered arm).

:meth:`RobotArm.inverse` runs on the live retargeting path once per 110 Hz frame, for every
robot. Written as a loop of Pinocchio and NumPy calls, an iteration costs tens of microseconds of
Python overhead for 6x6 algebra, and a frame's solve took milliseconds. Here the same algorithm
runs as one numba kernel over the chain's constant geometry, read once from the Pinocchio model
(:class:`SerialChain`): the forward kinematics, the geometric Jacobian, the rotation error (SO(3)
log) and the damped solve are each a few lines of arithmetic, and a whole solve takes tens of
microseconds. Pinocchio stays the one model: the chain is its joints' placements and axes, and the
tests hold the kernel's poses to Pinocchio's.

The same forward kinematics gives the height of each link's lowest point above the table the robot
stands on (:class:`LinkPoints`, :meth:`RobotArm.table_contacts`): asked for every pose the
retargeting and the planner consider, it cost more than a frame's IK as a loop over Pinocchio's
geometry placements.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numba import njit

from .._kernels import frozen
from ._checks import KinematicsError

STALLED_STEP = 1e-9
"""A solve stops where its next step would move no joint further than this (rad), within the
limits: it has stalled, at a target out of its reach from there or held at a limit, and the
iterations left would hold the pose (they move it by nanometres). On targets out of reach, most
solves stall within their first iterations; running the rest took two thirds of the Z1's IK
iterations over ``tests/kinematics/test_reach.py``, and changed no frame reached."""

_AXES = {"RX": (1.0, 0.0, 0.0), "RY": (0.0, 1.0, 0.0), "RZ": (0.0, 0.0, 1.0)}


@dataclass(frozen=True)
class SerialChain:
    """The constant geometry of a serial arm, as the kernel reads it.

    Attributes:
        rotations, translations: each joint's placement in its parent joint's frame at zero
            angle, shapes (n, 3, 3) and (n, 3).
        axes: each joint's rotation axis in its own frame, shape (n, 3).
        tool_rotation, tool_translation: the tool frame in the frame of joint ``tool_joint``.
        tool_joint: the 0-based joint that carries the tool.
        elbow_joint: the 0-based joint whose origin is the elbow.
    """

    rotations: np.ndarray
    translations: np.ndarray
    axes: np.ndarray
    tool_rotation: np.ndarray
    tool_translation: np.ndarray
    tool_joint: int
    elbow_joint: int

    @classmethod
    def from_model(cls, model: pin.Model, tool_frame: int, elbow_joint: int) -> SerialChain:
        """The chain of ``model`` (every joint revolute, each the child of the one before).

        Args:
            model: the Pinocchio model.
            tool_frame: the tool frame's id.
            elbow_joint: the elbow's Pinocchio joint index (1-based).

        Raises:
            KinematicsError: a joint that is not revolute, or a branching tree.
        """
        n = model.njoints - 1
        rotations, translations, axes = np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((n, 3))
        for i in range(1, n + 1):
            joint = model.joints[i]
            kind = joint.shortname().removeprefix("JointModel")
            if kind in _AXES:
                axes[i - 1] = _AXES[kind]
            elif kind == "RevoluteUnaligned":
                axes[i - 1] = np.asarray(joint.axis, dtype=float)
            else:
                raise KinematicsError(
                    f"Joint {model.names[i]!r} of {model.name!r} is a {kind} joint; the arm "
                    "IK drives revolute joints only."
                )
            if model.parents[i] != i - 1:
                raise KinematicsError(
                    f"{model.name!r} is not a serial chain; the arm IK needs one."
                )
            placement = model.jointPlacements[i]
            rotations[i - 1], translations[i - 1] = placement.rotation, placement.translation
        frame = model.frames[tool_frame]
        return cls(
            rotations,
            translations,
            axes,
            np.array(frame.placement.rotation),
            np.array(frame.placement.translation),
            int(frame.parentJoint) - 1,
            int(elbow_joint) - 1,
        )

    def _frames(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Each joint frame's rotation and origin at ``q``, and the tool's, by the kernel."""
        R, p = np.empty((len(self.axes), 3, 3)), np.empty((len(self.axes), 3))
        tool_R, tool_p = np.empty((3, 3)), np.empty(3)
        _forward(self.rotations, self.translations, self.axes, np.array(q, float), R, p)
        _tool(self, R, p, tool_R, tool_p)
        return R, p, tool_R, tool_p

    def forward(self, q: np.ndarray) -> np.ndarray:
        """The tool pose (4x4) at ``q``, computed by the kernel (for tests and checks)."""
        _, _, tool_R, tool_p = self._frames(q)
        out = np.eye(4)
        out[:3, :3], out[:3, 3] = tool_R, tool_p
        return out

    def jacobian(self, q: np.ndarray, rows: int = 6) -> np.ndarray:
        """The tool's geometric Jacobian at ``q`` (world axes), ``(rows, n)``: rows 0-2 its
        velocity, rows 3-5 (``rows=6``) its angular velocity; computed by the kernel."""
        R, p, _, tool_p = self._frames(q)
        J = np.empty((rows, len(self.axes)))
        _jacobian(R, p, self.axes, tool_p, min(len(self.axes), self.tool_joint + 1), J)
        return J


def _tool(chain: SerialChain, R: np.ndarray, p: np.ndarray, tool_R: np.ndarray, tool_p: np.ndarray):
    j = chain.tool_joint
    tool_R[:] = R[j] @ chain.tool_rotation
    tool_p[:] = p[j] + R[j] @ chain.tool_translation


@dataclass(frozen=True)
class LinkPoints:
    """The collision geometries of a chain's links, as the compiled table check reads them
    (:meth:`RobotArm.table_contacts`): per geometry its joint, its placement in that joint's
    frame, a sphere around its points and the points (in its own frame), all stacked.

    Attributes:
        joints: each geometry's 0-based chain joint, shape (m,).
        rotations, translations: each geometry's placement in its joint's frame, (m, 3, 3) and
            (m, 3).
        centres, radii: each geometry's bounding sphere in its own frame, (m, 3) and (m,).
        starts: geometry ``k``'s points are ``points[starts[k]:starts[k + 1]]``, shape (m + 1,).
        points: every geometry's points in its own frame, (P, 3).
    """

    joints: np.ndarray
    rotations: np.ndarray
    translations: np.ndarray
    centres: np.ndarray
    radii: np.ndarray
    starts: np.ndarray
    points: np.ndarray

    @classmethod
    def from_geometry(
        cls, geom: pin.GeometryModel, found: list[tuple[int, np.ndarray, np.ndarray, float]]
    ) -> LinkPoints:
        """The stacked form of ``found``: (geometry index in ``geom``, its points, its sphere's
        centre and radius) per geometry."""
        objects = [geom.geometryObjects[k] for k, *_ in found]
        counts = [len(points) for _, points, _, _ in found]
        return cls(
            np.array([obj.parentJoint - 1 for obj in objects], dtype=np.int64),
            np.array([obj.placement.rotation for obj in objects], dtype=float).reshape(-1, 3, 3),
            np.array([obj.placement.translation for obj in objects], dtype=float).reshape(-1, 3),
            np.array([centre for _, _, centre, _ in found], dtype=float).reshape(-1, 3),
            np.array([radius for *_, radius in found], dtype=float),
            np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
            np.concatenate([p for _, p, _, _ in found] or [np.zeros((0, 3))]).astype(float),
        )

    def heights(self, chain: SerialChain, q: np.ndarray, margin: float) -> np.ndarray:
        """Each geometry's lowest point's height above the base's plane at ``q`` (m), or
        infinity where its bounding sphere is ``margin`` or more above it; shape (m,)."""
        out = np.empty(len(self.joints))
        _heights(
            chain.rotations,
            chain.translations,
            chain.axes,
            np.array(q, dtype=float),  # a writable copy: one compiled signature for every q
            self.joints,
            self.rotations,
            self.translations,
            self.centres,
            self.radii,
            self.starts,
            self.points,
            float(margin),
            out,
        )
        return out


@dataclass(frozen=True)
class ChainSolve:
    """The settings of one :func:`solve` call (see :meth:`RobotArm.inverse`)."""

    iterations: int
    elbow_iterations: int
    position_tolerance: float
    rotation_tolerance: float
    damping: float
    max_step: float


def solve(
    chain: SerialChain,
    lower: np.ndarray,
    upper: np.ndarray,
    q0: np.ndarray,
    target_R: np.ndarray,
    target_p: np.ndarray,
    position_only: bool,
    elbow: np.ndarray | None,
    settings: ChainSolve,
) -> tuple[np.ndarray, float, float, int]:
    """Projected DLS from ``q0`` towards the tool pose; returns (q, position error, rotation
    error, iterations). ``q`` is always within ``lower``..``upper``."""
    q = np.array(q0, dtype=float)
    out = np.zeros(3)
    use_elbow = elbow is not None
    it = _solve(
        chain.rotations,
        chain.translations,
        chain.axes,
        chain.tool_rotation,
        chain.tool_translation,
        chain.tool_joint,
        chain.elbow_joint,
        frozen(lower),
        frozen(upper),
        q,
        np.ascontiguousarray(target_R, dtype=float),
        np.ascontiguousarray(target_p, dtype=float),
        position_only,
        np.zeros(3) if elbow is None else np.ascontiguousarray(elbow, dtype=float),
        use_elbow,
        settings.iterations,
        settings.elbow_iterations,
        settings.position_tolerance,
        settings.rotation_tolerance,
        settings.damping,
        settings.max_step,
        out,
    )
    return q, float(out[0]), float(out[1]), int(it)


@njit(nogil=True, cache=True, inline="always")
def _matmul3(A, B, out):  # pragma: no cover - compiled
    """``out = A @ B`` for 3x3 matrices (written out: BLAS costs more than the product)."""
    for i in range(3):
        a0, a1, a2 = A[i, 0], A[i, 1], A[i, 2]
        for j in range(3):
            out[i, j] = a0 * B[0, j] + a1 * B[1, j] + a2 * B[2, j]


@njit(nogil=True, cache=True, inline="always")
def _matvec3(A, v, out):  # pragma: no cover - compiled
    """``out = A @ v`` for a 3x3 matrix."""
    x, y, z = v[0], v[1], v[2]
    for i in range(3):
        out[i] = A[i, 0] * x + A[i, 1] * y + A[i, 2] * z


@njit(nogil=True, cache=True)
def _forward(rotations, translations, axes, q, R, p):  # pragma: no cover - compiled
    """Each joint frame's rotation ``R[k]`` and origin ``p[k]`` in the base frame at ``q``."""
    for k in range(q.shape[0]):
        # the parent frame, then the fixed placement, then the rotation about the joint's axis
        if k == 0:
            for i in range(3):
                p[0, i] = translations[0, i]
                for j in range(3):
                    R[0, i, j] = rotations[0, i, j]
        else:
            _matmul3(R[k - 1], rotations[k], R[k])
            parent, t = R[k - 1], translations[k]
            for i in range(3):
                p[k, i] = p[k - 1, i] + (
                    parent[i, 0] * t[0] + parent[i, 1] * t[1] + parent[i, 2] * t[2]
                )
        x, y, z = axes[k, 0], axes[k, 1], axes[k, 2]
        c, s = math.cos(q[k]), math.sin(q[k])
        t1 = 1.0 - c
        r00, r01, r02 = c + x * x * t1, x * y * t1 - z * s, x * z * t1 + y * s
        r10, r11, r12 = y * x * t1 + z * s, c + y * y * t1, y * z * t1 - x * s
        r20, r21, r22 = z * x * t1 - y * s, z * y * t1 + x * s, c + z * z * t1
        Rk = R[k]
        for i in range(3):  # Rk = Rk @ rot, in place: each row is read before it is written
            a0, a1, a2 = Rk[i, 0], Rk[i, 1], Rk[i, 2]
            Rk[i, 0] = a0 * r00 + a1 * r10 + a2 * r20
            Rk[i, 1] = a0 * r01 + a1 * r11 + a2 * r21
            Rk[i, 2] = a0 * r02 + a1 * r12 + a2 * r22


@njit(nogil=True, cache=True)
def _log3(M, w):  # pragma: no cover - compiled
    """``w`` = the rotation vector of the rotation matrix ``M`` (SO(3) log)."""
    cos = 0.5 * (M[0, 0] + M[1, 1] + M[2, 2] - 1.0)
    cos = min(1.0, max(-1.0, cos))
    theta = math.acos(cos)
    vx, vy, vz = M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1]
    if theta < 1e-6:
        w[0], w[1], w[2] = 0.5 * vx, 0.5 * vy, 0.5 * vz
    elif theta < math.pi - 1e-4:
        f = theta / (2.0 * math.sin(theta))
        w[0], w[1], w[2] = f * vx, f * vy, f * vz
    else:  # near a half turn: the axis from the symmetric part, its sign from the skew part
        k = 0
        if M[1, 1] > M[k, k]:
            k = 1
        if M[2, 2] > M[k, k]:
            k = 2
        one_minus = 1.0 - cos
        axis = np.empty(3)
        axis[k] = math.sqrt(max(0.0, (M[k, k] - cos) / one_minus))
        for j in range(3):
            if j != k:
                axis[j] = (M[k, j] + M[j, k]) / (2.0 * one_minus * axis[k])
        if axis[0] * vx + axis[1] * vy + axis[2] * vz < 0.0:
            axis = -axis
        norm = math.sqrt(axis[0] ** 2 + axis[1] ** 2 + axis[2] ** 2)
        for j in range(3):
            w[j] = theta * axis[j] / norm


@njit(nogil=True, cache=True, inline="always")
def _spd_solve(A, b, L, y, x):  # pragma: no cover - compiled
    """``x = A^-1 b`` for a small symmetric positive-definite ``A`` (Cholesky into ``L``, forward
    substitution into ``y``)."""
    n = A.shape[0]
    for i in range(n):
        for j in range(i + 1):
            s = A[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                L[i, i] = math.sqrt(max(s, 1e-300))
            else:
                L[i, j] = s / L[j, j]
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= L[i, k] * y[k]
        y[i] = s / L[i, i]
    for i in range(n - 1, -1, -1):
        s = y[i]
        for k in range(i + 1, n):
            s -= L[k, i] * x[k]
        x[i] = s / L[i, i]


@njit(nogil=True, cache=True, inline="always")
def _transpose_times(J, y, out):  # pragma: no cover - compiled
    """``out = J.T @ y``."""
    out[:] = 0.0
    for i in range(J.shape[0]):
        for k in range(J.shape[1]):
            out[k] += J[i, k] * y[i]


@njit(nogil=True, cache=True, inline="always")
def _jacobian(R, p, axes, point, columns, J):  # pragma: no cover - compiled
    """The geometric Jacobian (world axes) of ``point`` in the first ``columns`` joints' frames;
    rows 0-2 its velocity, rows 3-5 (when ``J`` has them) the angular velocity."""
    J[:, :] = 0.0
    for k in range(columns):
        Rk, a = R[k], axes[k]
        z0 = Rk[0, 0] * a[0] + Rk[0, 1] * a[1] + Rk[0, 2] * a[2]
        z1 = Rk[1, 0] * a[0] + Rk[1, 1] * a[1] + Rk[1, 2] * a[2]
        z2 = Rk[2, 0] * a[0] + Rk[2, 1] * a[1] + Rk[2, 2] * a[2]
        d0, d1, d2 = point[0] - p[k, 0], point[1] - p[k, 1], point[2] - p[k, 2]
        J[0, k] = z1 * d2 - z2 * d1
        J[1, k] = z2 * d0 - z0 * d2
        J[2, k] = z0 * d1 - z1 * d0
        if J.shape[0] == 6:
            J[3, k], J[4, k], J[5, k] = z0, z1, z2


@njit(nogil=True, cache=True, inline="always")
def _damped_gram(J, damping, A):  # pragma: no cover - compiled
    """``A = J J^T + damping^2 I``."""
    rows, n = J.shape
    for i in range(rows):
        for j in range(i + 1):
            total = 0.0
            for k in range(n):
                total += J[i, k] * J[j, k]
            A[i, j] = total
            A[j, i] = total
        A[i, i] += damping * damping


@njit(nogil=True, cache=True, inline="always")
def _elbow_pull(R, p, axes, elbow_joint, elbow, Je, toward, pull):  # pragma: no cover - compiled
    """``pull = J_e^T (elbow - p_e)``: the joint motion that pulls the elbow's origin towards
    ``elbow`` (``Je`` and ``toward`` are scratch)."""
    _jacobian(R, p, axes, p[elbow_joint], elbow_joint, Je)
    for i in range(3):
        toward[i] = elbow[i] - p[elbow_joint, i]
    _transpose_times(Je, toward, pull)


@njit(nogil=True, cache=True)
def _clamped_step(  # pragma: no cover - compiled
    J, e, pull, secondary_task, q, lower, upper, damping, A, dq, secondary, locked, L, y, x, Jpull
):
    """The DLS step ``J^T (J J^T + damping^2 I)^-1 e`` plus ``pull`` projected into the tool
    task's null space, with the joints held at a limit they would be pushed beyond taken out.

    A joint at a limit that the step would push further is locked (its column of ``J`` and its
    ``pull`` zeroed) and the step solved again by the others, until none is pushed beyond:
    clipping it afterwards instead left the rest of the step aimed at a motion that does not
    happen, and the solve stalled with the tool short of a target the other joints could reach.
    Writes the step into ``dq`` and its null-space part into ``secondary``; ``J`` and ``pull``
    are overwritten, ``A``, ``locked``, ``L``, ``y``, ``x`` and ``Jpull`` are scratch.
    """
    rows, n = J.shape
    locked[:] = False
    dq[:] = 0.0
    secondary[:] = 0.0
    for _ in range(n):
        for k in range(n):
            if locked[k]:
                J[:, k] = 0.0
                pull[k] = 0.0
        _damped_gram(J, damping, A)
        _spd_solve(A, e, L, y, x)
        _transpose_times(J, x, dq)
        if secondary_task:
            for i in range(rows):
                total = 0.0
                for k in range(n):
                    total += J[i, k] * pull[k]
                Jpull[i] = total
            _spd_solve(A, Jpull, L, y, x)
            _transpose_times(J, x, secondary)
            for k in range(n):
                secondary[k] = pull[k] - secondary[k]
                dq[k] += secondary[k]
        more = False
        for k in range(n):
            pushed = (q[k] <= lower[k] and dq[k] < 0.0) or (q[k] >= upper[k] and dq[k] > 0.0)
            if pushed and not locked[k]:
                locked[k] = True
                more = True
        if not more:
            break


@njit(nogil=True, cache=True, inline="always")
def _largest(v):  # pragma: no cover - compiled
    """The largest absolute value in ``v``."""
    out = 0.0
    for value in v:
        out = max(out, abs(value))
    return out


@njit(nogil=True, cache=True, inline="always")
def _tool_error(  # noqa: PLR0913 - the kernel's flat arguments  # pragma: no cover - compiled
    R, p, tool_joint, tool_rotation, tool_translation, target_R, target_p, position_only,
    tool_R, tool_p, err_R, w, e,
):  # fmt: skip
    """The tool's pose for the joints' frames ``R``, ``p`` (into ``tool_R``, ``tool_p``) and its
    error towards the target (into ``e``: position, then rotation unless ``position_only``);
    returns (position error, rotation error). ``err_R`` and ``w`` are scratch."""
    _matmul3(R[tool_joint], tool_rotation, tool_R)
    _matvec3(R[tool_joint], tool_translation, tool_p)
    for i in range(3):
        tool_p[i] += p[tool_joint, i]
        e[i] = target_p[i] - tool_p[i]
    pos_err = math.sqrt(e[0] ** 2 + e[1] ** 2 + e[2] ** 2)
    if position_only:
        return pos_err, 0.0
    _matmul3(target_R, tool_R.T, err_R)
    _log3(err_R, w)
    e[3], e[4], e[5] = w[0], w[1], w[2]
    return pos_err, math.sqrt(w[0] ** 2 + w[1] ** 2 + w[2] ** 2)


@njit(nogil=True, cache=True)
def _solve(  # noqa: PLR0913 - the kernel's flat arguments  # pragma: no cover - compiled
    rotations,
    translations,
    axes,
    tool_rotation,
    tool_translation,
    tool_joint,
    elbow_joint,
    lower,
    upper,
    q,
    target_R,
    target_p,
    position_only,
    elbow,
    use_elbow,
    iterations,
    elbow_iterations,
    position_tolerance,
    rotation_tolerance,
    damping,
    max_step,
    out,
):
    """Projected DLS in place on ``q``; ``out`` = (position error, rotation error); returns the
    iterations used. The algorithm of :meth:`RobotArm.inverse`; every array it needs is made
    once here, none in the loop."""
    n = q.shape[0]
    rows = 3 if position_only else 6
    R = np.empty((n, 3, 3))
    p = np.empty((n, 3))
    tool_R = np.empty((3, 3))
    tool_p = np.empty(3)
    err_R = np.empty((3, 3))
    e = np.zeros(rows)
    w = np.zeros(3)
    J = np.zeros((rows, n))
    A = np.empty((rows, rows))
    Je = np.zeros((3, n))
    toward = np.empty(3)
    pull = np.zeros(n)
    dq = np.zeros(n)
    secondary = np.zeros(n)
    locked = np.zeros(n, dtype=np.bool_)
    L = np.zeros((rows, rows))
    y = np.empty(rows)
    x = np.empty(rows)
    Jpull = np.empty(rows)
    pos_err = math.inf
    rot_err = math.inf
    elbow_steps = elbow_iterations
    it = 0
    for it in range(iterations + 1):
        _forward(rotations, translations, axes, q, R, p)
        pos_err, rot_err = _tool_error(
            R, p, tool_joint, tool_rotation, tool_translation, target_R, target_p, position_only,
            tool_R, tool_p, err_R, w, e,
        )  # fmt: skip
        reached = pos_err <= position_tolerance and rot_err <= rotation_tolerance
        if it == iterations or (reached and not use_elbow):
            break
        _jacobian(R, p, axes, tool_p, min(n, tool_joint + 1), J)
        secondary_task = use_elbow and n > rows
        if secondary_task:  # the elbow's pull, J_e^T (target - elbow), halved
            _elbow_pull(R, p, axes, elbow_joint, elbow, Je, toward, pull)
            for k in range(n):
                pull[k] = 0.5 * pull[k]
        else:
            pull[:] = 0.0
        _clamped_step(
            J, e, pull, secondary_task, q, lower, upper, damping, A, dq, secondary, locked, L, y,
            x, Jpull,
        )  # fmt: skip
        if secondary_task:
            biggest_secondary = _largest(secondary)
            if reached and (elbow_steps <= 0 or biggest_secondary < 1e-4):
                break  # the elbow is as near as the tool lets it be, or left to next time
            if reached:
                elbow_steps -= 1
        biggest = _largest(dq)
        if biggest > max_step:
            scale = max_step / biggest
            for k in range(n):
                dq[k] *= scale
        moved = 0.0
        for k in range(n):
            moved = max(moved, abs(min(max(q[k] + dq[k], lower[k]), upper[k]) - q[k]))
        if moved < STALLED_STEP:
            break  # stalled: the iterations left would hold this pose
        for k in range(n):
            q[k] = min(max(q[k] + dq[k], lower[k]), upper[k])
    out[0] = pos_err
    out[1] = rot_err
    return it


@njit(nogil=True, cache=True)
def _heights(  # noqa: PLR0913 - the kernel's flat arguments  # pragma: no cover - compiled
    rotations,
    translations,
    axes,
    q,
    joints,
    geometry_rotations,
    geometry_translations,
    centres,
    radii,
    starts,
    points,
    margin,
    out,
):
    """``out[k]``: geometry ``k``'s lowest point's height (base z) at ``q``, or infinity where
    its bounding sphere lies ``margin`` or more above the base's plane (see
    :meth:`LinkPoints.heights`)."""
    n = q.shape[0]
    R = np.empty((n, 3, 3))
    p = np.empty((n, 3))
    _forward(rotations, translations, axes, q, R, p)
    for k in range(joints.shape[0]):
        j = joints[k]
        Rg, pg = geometry_rotations[k], geometry_translations[k]
        # the geometry's frame is the joint's times its placement; its up row is the third
        r0, r1, r2 = R[j, 2, 0], R[j, 2, 1], R[j, 2, 2]
        u0 = r0 * Rg[0, 0] + r1 * Rg[1, 0] + r2 * Rg[2, 0]
        u1 = r0 * Rg[0, 1] + r1 * Rg[1, 1] + r2 * Rg[2, 1]
        u2 = r0 * Rg[0, 2] + r1 * Rg[1, 2] + r2 * Rg[2, 2]
        height = p[j, 2] + (r0 * pg[0] + r1 * pg[1] + r2 * pg[2])
        c = centres[k]
        if u0 * c[0] + u1 * c[1] + u2 * c[2] + height - radii[k] >= margin:
            out[k] = math.inf  # its bounding sphere clears the table
            continue
        lowest = math.inf
        for i in range(starts[k], starts[k + 1]):
            lowest = min(lowest, u0 * points[i, 0] + u1 * points[i, 1] + u2 * points[i, 2])
        out[k] = lowest + height
