"""Hand guide: the 7-DOF human arm that puts the operator's hand at a dragged pose.

The scene's handle gives a target pose of the hand (``oMhand``: the hand frame of
:meth:`HumanArm.forward`, in the arm base frame: shoulder at the origin, x forward, y left, z up).
Damped least squares on the arm's hand-frame Jacobian (Pinocchio, world-aligned) moves the joints
toward it, each step projected into the joint limits. The hand's position comes first: the
orientation error is weighed as ``HandIKConfig.rotation_weight`` metres per radian, so where the
full pose cannot be met the hand still lands on the handle's position. A target beyond the arm's
reach gives the closest arm (stretched toward it) and ``reached=False``; the solution then moves
smoothly as the handle moves, because every solve starts from the caller's seed (the previous
solution) and damping bounds each step.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .._checks import (
    KinematicsError,
    check_side,
    instance_of,
    positive_number,
    real_array,
    whole_number,
)
from ._human import HumanArm, _as_q
from ._pose import _closed_form, _cross, _Reading, default_arm

SWIVELS = 8
"""Elbow positions tried around the shoulder-wrist axis for a cold start (evenly spaced)."""


@dataclass(frozen=True)
class HandIKConfig:
    """Defaults of the hand-guide IK, documented once.

    Attributes:
        rotation_weight: metres of position error one radian of orientation error counts as
            (small: the hand's position comes first).
        damping: DLS damping (m): bounds steps near singular arms (a straight elbow).
        max_step: largest joint step per iteration (rad, infinity norm).
        max_iterations: iterations per start.
        tolerance: stop when the position error (m) and the weighted orientation error are
            below this.
        reach_tolerance: the hand counts as on the handle within this distance (m).
        polished: how many of the closed-form starts (best first) the DLS refines when the
            seed does not reach.
        continuity_m: when no start reaches, the seed's arm is kept unless another start's
            hand is closer to the target by more than this (m): the arm follows a handle
            dragged out of reach without jumping between equally close arms.
    """

    rotation_weight: float = 0.05
    damping: float = 0.01
    max_step: float = 0.4
    max_iterations: int = 40
    tolerance: float = 1e-4
    reach_tolerance: float = 0.01
    polished: int = 2
    continuity_m: float = 0.001

    def __post_init__(self) -> None:
        for name in (
            "rotation_weight",
            "damping",
            "max_step",
            "tolerance",
            "reach_tolerance",
            "continuity_m",
        ):
            positive_number(getattr(self, name), f"HandIKConfig.{name}")
        whole_number(self.max_iterations, "HandIKConfig.max_iterations", 1)
        whole_number(self.polished, "HandIKConfig.polished", 1)


@dataclass(frozen=True)
class HandFit:
    """The arm solved for a hand target.

    Attributes:
        q_human: joint angles (rad, (7,)), within the arm's limits.
        position_error_m: distance from the hand to the target's position.
        rotation_error_rad: angle between the hand's and the target's orientations.
        reached: the hand is within ``HandIKConfig.reach_tolerance`` (1 cm) of the target.
        iterations: DLS iterations used over all starts.
    """

    q_human: np.ndarray
    position_error_m: float
    rotation_error_rad: float
    reached: bool
    iterations: int = 0


def _check_target(oMhand: object) -> np.ndarray:
    """``oMhand`` as a finite 4x4 rigid transform, or one sentence."""
    M = real_array(oMhand, "The hand target oMhand", "pass a 4x4 pose in the arm base frame")
    if M.shape != (4, 4):
        raise KinematicsError(
            f"The hand target oMhand must be a 4x4 pose; got shape {M.shape}; pass a homogeneous "
            "transform in the arm base frame."
        )
    if not np.all(np.isfinite(M)):
        raise KinematicsError("The hand target oMhand contains NaN or infinite values.")
    R = M[:3, :3]
    if not (np.allclose(R.T @ R, np.eye(3), atol=1e-6) and np.linalg.det(R) > 0):
        raise KinematicsError(
            "The hand target oMhand's rotation is not a rotation (its 3x3 block must be "
            "orthonormal with determinant 1); normalise the handle's quaternion."
        )
    return M


_scratch = threading.local()


def _data(side: str) -> pin.Data:
    """This thread's Pinocchio data of ``side``'s default arm, made once (not per solve)."""
    cache = getattr(_scratch, "data", None)
    if cache is None:
        cache = _scratch.data = {}
    if side not in cache:
        cache[side] = default_arm(side).model.createData()
    return cache[side]


class _Solver:
    """One DLS run's scratch: the arm's model, a data, the target."""

    def __init__(self, side: str, target: np.ndarray, cfg: HandIKConfig) -> None:
        self.arm = default_arm(side)
        self.model = self.arm.model
        self.data = _data(side)
        self.frame = self.arm.hand_frame
        self.p_des = target[:3, 3]
        self.R_des = target[:3, :3]
        self.cfg = cfg
        self.weights = np.array([1.0] * 3 + [cfg.rotation_weight] * 3)
        self.damping = cfg.damping**2 * np.eye(6)

    def errors(self, q: np.ndarray, jacobians: bool = False) -> tuple[np.ndarray, float, float]:
        """(weighted 6-vector error, position error m, rotation error rad) at ``q``.

        With ``jacobians``, the joint Jacobians are computed in the same pass (for
        :meth:`jacobian`).
        """
        if jacobians:
            pin.computeJointJacobians(self.model, self.data, q)
        else:
            pin.forwardKinematics(self.model, self.data, q)
        oMf = pin.updateFramePlacement(self.model, self.data, self.frame)
        e = np.empty(6)
        e[:3] = self.p_des - oMf.translation
        e[3:] = pin.log3(self.R_des @ oMf.rotation.T)  # world-aligned rotation error
        return e * self.weights, float(np.linalg.norm(e[:3])), float(np.linalg.norm(e[3:]))

    def closed_form_starts(self, q_hold: np.ndarray) -> list[np.ndarray]:
        """Arms meeting the target in closed form (then clamped), best first.

        The wrist lies a hand's length behind the hand along its fingers; the shoulder-wrist
        distance fixes the elbow's flexion, and the elbow may swivel about the shoulder-wrist
        axis: :data:`SWIVELS` swivels, on both shoulder branches, each turned into joint
        angles by the landmark fit's closed form.
        """
        arm = self.arm
        hand_axis = -self.R_des[:, 1]  # the fingers point along the hand frame's -y
        W = self.p_des - arm.hand_length * hand_axis
        upper, fore = arm.upper_arm_length, arm.forearm_length
        d = float(np.clip(np.linalg.norm(W), abs(upper - fore) + 1e-6, upper + fore - 1e-9))
        axis = W / np.linalg.norm(W) if np.linalg.norm(W) > 1e-9 else np.array([0.0, 0.0, -1.0])
        W = d * axis
        cos_a = (upper**2 + d**2 - fore**2) / (2 * upper * d)
        sin_a = math.sqrt(max(0.0, 1.0 - cos_a**2))
        down = np.array([0.0, 0.0, -1.0]) - axis[2] * -axis  # elbow down first
        if np.linalg.norm(down) < 1e-6:
            down = np.array([1.0, 0.0, 0.0]) - axis[0] * axis
        b1 = down / np.linalg.norm(down)
        b2 = _cross(axis, b1)
        candidates = []
        # Elbow down first, then swivelling out both ways: a natural arm is usually found first.
        for k in sorted(range(SWIVELS), key=lambda k: min(k, SWIVELS - k)):
            phi = 2 * math.pi * k / SWIVELS
            E = upper * (cos_a * axis + sin_a * (math.cos(phi) * b1 + math.sin(phi) * b2))
            reading = _Reading(
                upper=E / upper,
                fore=(W - E) / np.linalg.norm(W - E),
                hand=hand_axis,
                palm=self.R_des[:, 0],
                palm_sine=1.0,
                points=np.stack([np.zeros(3), E, W, self.p_des]),
                lengths=np.array([upper, fore]),
            )
            for overhead in (False, True):
                q = _closed_form(reading, arm, self.data, q_hold, overhead)
                error = float(np.linalg.norm(self.errors(q)[0]))
                if error < self.cfg.tolerance:  # meets the target within the limits: done
                    return [q]
                candidates.append((error, float(np.linalg.norm(q - q_hold)), q))
        candidates.sort(key=lambda c: (round(c[0], 3), c[1]))
        return [c[2] for c in candidates]

    def run(self, q: np.ndarray) -> tuple[np.ndarray, float, float, int]:
        """DLS from ``q``: (q, position error, rotation error, iterations)."""
        cfg, arm = self.cfg, self.arm
        ref = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        e, pos, rot = self.errors(q, jacobians=True)
        for it in range(1, cfg.max_iterations + 1):
            if np.linalg.norm(e) < cfg.tolerance:
                return q, pos, rot, it - 1
            J = pin.getFrameJacobian(self.model, self.data, self.frame, ref) * self.weights[:, None]
            dq = J.T @ np.linalg.solve(J @ J.T + self.damping, e)
            largest = float(np.max(np.abs(dq)))
            if largest > cfg.max_step:
                dq *= cfg.max_step / largest
            q = np.clip(q + dq, arm.lower, arm.upper)
            e, pos, rot = self.errors(q, jacobians=True)
        return q, pos, rot, cfg.max_iterations


def oMhand_position(arm: HumanArm, q: np.ndarray) -> np.ndarray:
    """The hand's position (m, arm base frame) at ``q``."""
    return arm.forward(q).hand[:3, 3]


def fit_hand_pose(
    oMhand: object,
    side: str = "right",
    q_seed: object = None,
    *,
    config: HandIKConfig | None = None,
) -> HandFit:
    """The arm angles that put the hand at ``oMhand``, within the joint limits.

    Args:
        oMhand: target pose of the hand (4x4) in the arm base frame, the frame of
            ``HumanArm(side).forward(q).hand``.
        side: ``"right"`` or ``"left"``.
        q_seed: where to start (rad, (7,)); pass the previous solution while dragging, so the
            arm moves continuously. Default: the neutral arm.
        config: solver defaults.

    Returns:
        A :class:`HandFit`; where the target is out of reach, the closest arm found.

    Raises:
        KinematicsError: a bad target, side or seed.
    """
    side = check_side(side, "The hand guide's side")
    instance_of(config, HandIKConfig, "fit_hand_pose's config", optional=True)
    cfg = config or HandIKConfig()
    target = _check_target(oMhand)
    arm = default_arm(side)
    reach = 0.995 * (arm.upper_arm_length + arm.forearm_length + arm.hand_length)
    distance = float(np.linalg.norm(target[:3, 3]))
    if distance > reach:  # out of reach: aim at the nearest point the hand may reach
        target = target.copy()
        target[:3, 3] *= reach / distance
    solver = _Solver(side, target, cfg)
    if q_seed is None:
        seed = arm.neutral.copy()
    else:
        seed = _as_q(q_seed, arm.nq, "q_seed")
        if seed.shape != (arm.nq,):
            raise KinematicsError(f"q_seed must have shape (7,); got shape {seed.shape}.")
        seed = np.clip(seed, arm.lower, arm.upper)
    best: tuple[float, np.ndarray, float, float] | None = None
    iterations = 0

    def attempt(start: np.ndarray) -> bool:
        nonlocal best, iterations
        q, pos, rot, used = solver.run(start)
        iterations += used
        score = math.hypot(pos, cfg.rotation_weight * rot)
        if best is None or score < best[0]:
            best = (score, q, pos, rot)
        return pos <= cfg.reach_tolerance and score <= cfg.reach_tolerance

    if q_seed is None or not attempt(seed):
        from_seed = best
        for start in solver.closed_form_starts(seed)[: cfg.polished]:
            if attempt(start):
                break
        # Out of reach, keep the seed's arm when its hand is as close: no jump while dragging.
        if from_seed is not None and from_seed[2] <= best[2] + cfg.continuity_m:
            best = from_seed
    assert best is not None
    if best[2] > cfg.reach_tolerance:  # out of reach: the position alone, as near as can be
        solver.weights[3:] = 0.0
        q, pos, rot, used = solver.run(best[1])
        iterations += used
        if pos < best[2]:
            best = (pos, q, pos, rot)
    _, q, pos, rot = best
    if distance > reach:  # measure against the handle itself
        pos = float(np.linalg.norm(oMhand_position(arm, q) - np.asarray(oMhand)[:3, 3]))
    return HandFit(
        q_human=q.copy(),
        position_error_m=pos,
        rotation_error_rad=rot,
        reached=pos <= cfg.reach_tolerance,
        iterations=iterations,
    )
