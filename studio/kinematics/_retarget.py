"""Retargeting: the operator's arm angles to Puma560 joint angles, mirrored by default.

The paper mirrors the operator (for ergonomics): facing the robot, the operator moves as in
front of a mirror. In the robot's base frame (x forward, z up, like the arm base frame) mirroring
is the reflection y -> -y: the operator's right arm reaching out to their right drives the robot
to *its* left, i.e. the same side as seen by the operator.

Two modes, switchable at run time (``retargeter.mode = "cartesian"``):

*joint* - each Puma joint follows one human joint, ``q_robot[j] = offset[j] + sign[j] *
q_human[i]``, then is clamped at the Puma's limits (:data:`JOINT_MAP`):

====  ===================================  ======  =========  ==========================
Puma  human joint                           sign    offset     why
====  ===================================  ======  =========  ==========================
J1    shoulder_X (abduction)               -1 (*)  0          swings the arm sideways;
                                                              with the arm raised it is yaw
J2    shoulder_Z (flexion)                 +1      -pi/2      arm hanging = J2 -90 deg
J3    elbow_Z (flexion)                    +1      -pi/2      straight arm = J3 -90 deg
J4    elbow_Y (forearm rotation)           +1 (*)  0          both roll the forearm
J5    wrist_Z (wrist flexion)              +1      0          both bend the wrist
J6    wrist_X (wrist deviation)            +1 (*)  0          the remaining wrist DOF
====  ===================================  ======  =========  ==========================

(*) lateral joints: their sign flips when mirroring, and again for a left arm (whose angles
already describe the mirror image). Humeral rotation (shoulder_Y) has no Puma counterpart and is
dropped; :meth:`Retargeter.human_from_robot` sets it to zero.

*cartesian* - the hand-centre pose relative to the shoulder is mirrored and placed in the
robot's workspace (a robot of :func:`load_robot`: the operator's reach, relative to their arm's
length, mapped direction by direction into the robot's reach above its table,
:class:`~studio.kinematics._workspace.Workspace`; the Puma560's analytic model: scaled by the
ratio of its reach to the arm's, times ``reach_fraction``, at its shoulder), and solved by the
robot's IK, warm-started from the previous solution; when the full pose is out of
reach of the wrist, the position alone is solved. While the arm moves, no joint turns more than
``max_joint_step`` a frame: a pose within that step that reaches the target (1 cm and 5 deg,
:meth:`RetargetConfig.within_reach`) is looked for first, and only when there is none does the
IK look on other branches, whose answer is then walked to over several frames.

On a robot standing on a table the target is kept above the table, out of the column around
the first axis that an arm with a sideways shoulder offset cannot enter (``RobotSpec.hollow``,
the UR arms': their workspace's centre sits in front of it) and within the arm's reach, each
softly (:class:`RetargetConfig`); the workspace already keeps a human arm's targets there.

The hand's target is placed in the robot's base frame turned by ``RobotArm.base_rotation``,
so an arm whose URDF faces elsewhere than +x (the SO-100's faces -y) faces the operator, as the
scene draws it. Any robot of :func:`load_robot` (a :class:`RobotArm`) is driven in cartesian mode, the only one
that means something for an arm whose joints are not the human arm's; on a redundant arm (Panda,
xArm7) the IK's null-space task keeps the robot's elbow at the operator's elbow, mirrored and
scaled like the hand. Joint mode is the Puma560's alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from ._checks import KinematicsError, instance_of, positive_number, whole_number
from ._clearance import ClearanceGuard
from ._puma import IKConfig, IKResult, Puma560
from ._robot_load import load_robot
from ._robots import IK_DAMPING, RobotArm, RobotIK, tool_errors
from ._workspace import (
    Workspace,
    into_hollow,
    out_of_hollow,
    soft_ceiling,
    soft_floor,
    unbent,
    unfloored,
)
from .human._hand_ik import fit_hand_pose
from .human._human import SAGITTAL_MIRROR, HumanArm, _as_q

Mode = Literal["joint", "cartesian"]

JOINT_MAP = (
    # (human joint index, sign, robot offset rad, lateral: flips with mirroring)
    (1, -1.0, 0.0, True),
    (0, 1.0, -math.pi / 2, False),
    (3, 1.0, -math.pi / 2, False),
    (4, 1.0, 0.0, True),
    (5, 1.0, 0.0, False),
    (6, 1.0, 0.0, True),
)
"""Joint-mode mapping, Puma joint by Puma joint (see the module docstring)."""

DROPPED_HUMAN_JOINT = 2
"""shoulder_Y (humeral rotation): no Puma counterpart."""

URDF_LATERAL_MIRROR = np.diag([1.0, 1.0, -1.0])
"""Reflection of ``human.urdf``'s local frames (their z is lateral), used to mirror hand frames."""

HAND_TO_TOOL = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
"""Tool axes in the hand frame: tool z (approach) along the fingers (hand -y), tool x = hand x."""


@dataclass(frozen=True)
class RetargetConfig:
    """Defaults of the retargeting, documented once.

    Attributes:
        reach_fraction: the arm's full reach maps to this fraction of the robot's, keeping
            cartesian targets off the Puma's outstretched singularity; for a robot of
            :func:`load_robot`, the ball the soft ceiling keeps targets within (its radius
            ``reach_fraction`` of the usable reach, :attr:`RobotSpec.usable_reach`).
        reach_share: ... and the operator's outstretched arm reaches this share of that radius
            (:class:`Workspace`: the operator's reach, relative to their arm's length, mapped
            direction by direction into the robot's ball above the table), so a person's natural
            reach is the robot's and no target of a human arm is drawn back. Measured on the
            three samples: every arm's reach is then followed in at least 95% of the frames
            (``benchmarks/bench_retarget.py --samples``).
        ik_iterations: IK iterations per attempt on the live path (warm starts need few).
        restart_iterations: IK iterations of each further attempt, when the warm-started solve
            of a robot of :func:`load_robot` misses the pose.
        floor_height: a robot of :func:`load_robot` stands on a table: hand targets are kept
            this far above its base plane (m), ...
        floor_softness: ... by a soft floor of this width (m), so a hand lowered below it
            slides along the table instead of stopping dead.
        reach_softness: raising such a robot's shoulder above the table carries the far side of
            the scaled hand's sphere beyond the arm's reach; a target further than
            ``reach_fraction`` of the reach from the robot's shoulder is drawn back inside that
            sphere, smoothly over this width (m), and left exactly where it is nearer.
        hollow_softness: a target nearer the first joint's axis than the robot's
            :attr:`RobotSpec.hollow` plus this width (m) is moved out, smoothly, to beyond the
            hollow (the UR's: where the raised arm cannot go), and left exactly where it is
            further.
        max_joint_step: largest change of any joint of the robot from one frame to the next
            (rad): a target that moves the IK's answer further (a wrist flip, a jump back into
            reach, the Puma560's shoulder passing near its first axis) is followed over several
            frames, never in one.
        input_jump: the Puma560's cartesian mode also answers single poses exactly: when the
            operator's arm changes by more than this in one frame (rad, any joint; a human arm
            turns at most about 10 rad/s, 0.09 rad a frame at 110 Hz), the new arm is a new pose
            rather than a motion, and the Puma560 goes straight to its answer. Every other
            robot always keeps to ``max_joint_step``.
        clearance: such a robot's links keep at least this distance from each other and from
            the table it stands on (m, :meth:`RobotArm.contacts`); a pose closer than that is
            not taken (the last one is held). Convex-hull distances
            near contact vary by about a millimetre between evaluations, so the margin keeps
            every pose taken clear of contact for any later check.
        reach_tolerance: a tool further than this from the hand's target is out of reach (m):
            the page says so live, a path counts the frame (:func:`retarget_path`) and an
            export names it.
        reach_angle: ... and a tool turned further than this from the target's orientation
            has not reached it (rad; arms that follow the position only are not held to it).
            With ``reach_tolerance``, what "reached" means (:meth:`within_reach`): the
            retargeting looks further (other IK branches) only for a pose it misses by more.
        restart_starts: when neither the last frame's pose nor its neighbourhood reaches the
            target, the IK starts again from this many fixed poses spread over the joint ranges
            (drawn once per robot, seeded), besides home.
        near_starts: a frame's IK first looks for a pose within ``max_joint_step`` of the last
            frame's, from the last pose and, when that misses, from this many fixed points
            around it (the step's bounds leave local minima a single start can stall in), then
            ``restart_iterations`` more from the nearest answer.
        settle_tries: IK passes on a path's first frame (each warm-started from the last)
            before the path starts, as a live session settles before it moves.
        singular_margin: an arm without joints to spare (no more joints than its tool's
            target has numbers: six, or three for an arm that follows the position only) whose
            last pose has a Jacobian singular value below this (the tool's m/rad and rad/rad) is near a
            singularity (the UR arms' shoulder and wrist), where the exact IK answer swings by
            many degrees for a millimetre of the target: its solves that frame are damped more
            (Chiaverini's damping, ``damping^2 = IK_DAMPING^2 + (1 - (s / margin)^2) *
            singular_damping^2``), trading a little accuracy for a pose that does not flip
            between two answers frame after frame. An arm with joints to spare keeps the plain
            damping: its null space takes up such motion.
        singular_damping: the largest extra damping there (at a singular value of 0).
        limit_room: of the poses the restarts find that reach the target, one with a joint
            nearer its limit than this (rad) counts as further away than it is, by
            ``limit_room_weight`` times the shortfall: a branch that starts at a limit soon
            ends there, and the robot walks to another one again. Measured live on the
            redundant arms, where the restarts find poses on several elbow branches: the Panda
            reaches 93% of the reachable frames of a simulator minute instead of 87%, the
            Kinova 91% instead of 87% of ``bench_retarget``'s motion; the 6-joint arms are
            unchanged.
        limit_room_weight: that weight (rad of distance per rad short of ``limit_room``).
    """

    reach_fraction: float = 0.95
    reach_share: float = 0.85
    ik_iterations: int = 20
    restart_iterations: int = 60
    floor_height: float = 0.05
    floor_softness: float = 0.05
    reach_softness: float = 0.1
    hollow_softness: float = 0.1
    max_joint_step: float = math.radians(4.5)
    input_jump: float = 0.15
    clearance: float = 0.005
    reach_tolerance: float = 0.01
    reach_angle: float = math.radians(5.0)
    restart_starts: int = 16
    near_starts: int = 4
    settle_tries: int = 5
    singular_margin: float = 0.1
    singular_damping: float = 0.08
    limit_room: float = 0.6
    limit_room_weight: float = 8.0

    def __post_init__(self) -> None:
        positive_number(self.reach_fraction, "RetargetConfig.reach_fraction")
        positive_number(self.reach_share, "RetargetConfig.reach_share")
        if self.reach_share > 1.0:
            raise KinematicsError(
                f"RetargetConfig.reach_share must be at most 1 (a share of the robot's reach); "
                f"got {self.reach_share}."
            )
        whole_number(self.ik_iterations, "RetargetConfig.ik_iterations", 1)
        whole_number(self.restart_iterations, "RetargetConfig.restart_iterations", 1)
        positive_number(self.floor_height, "RetargetConfig.floor_height")
        positive_number(self.floor_softness, "RetargetConfig.floor_softness")
        positive_number(self.reach_softness, "RetargetConfig.reach_softness")
        positive_number(self.hollow_softness, "RetargetConfig.hollow_softness")
        positive_number(self.max_joint_step, "RetargetConfig.max_joint_step")
        positive_number(self.input_jump, "RetargetConfig.input_jump")
        positive_number(self.clearance, "RetargetConfig.clearance")
        positive_number(self.reach_tolerance, "RetargetConfig.reach_tolerance")
        positive_number(self.reach_angle, "RetargetConfig.reach_angle")
        whole_number(self.restart_starts, "RetargetConfig.restart_starts", 0)
        whole_number(self.near_starts, "RetargetConfig.near_starts", 0)
        whole_number(self.settle_tries, "RetargetConfig.settle_tries", 1)
        positive_number(self.singular_margin, "RetargetConfig.singular_margin")
        positive_number(self.singular_damping, "RetargetConfig.singular_damping")
        positive_number(self.limit_room, "RetargetConfig.limit_room")
        positive_number(self.limit_room_weight, "RetargetConfig.limit_room_weight")

    def within_reach(self, position_error: float, rotation_error: float) -> bool:
        """Whether a tool this far (m) and this turned (rad) from its target has reached it."""
        return position_error <= self.reach_tolerance and rotation_error <= self.reach_angle


PINNED = 0.01
"""A joint within this share of its range from a limit counts as pinned there."""


RESTART_SEED = 0
"""Seed of the fixed IK starts (:attr:`RetargetConfig.restart_starts` and ``near_starts``)."""


def _forward(robot: RobotArm) -> np.ndarray:
    """The level direction ``robot`` faces (towards the operator) in its URDF's base frame."""
    return robot.base_rotation.T[:2, 0].copy()


def _turned_near(robot: RobotArm, q: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``q`` with each joint turned by whole turns to the angle nearest ``reference`` that its
    limits allow (the same pose: a joint with limits of +-2 pi reaches most angles two ways)."""
    turns = np.round((reference - q) / (2 * math.pi))
    turned = q + 2 * math.pi * turns
    turned = np.where(turned > robot.upper, turned - 2 * math.pi, turned)
    turned = np.where(turned < robot.lower, turned + 2 * math.pi, turned)
    return np.where((turned >= robot.lower) & (turned <= robot.upper), turned, q)


def _unpinned(robot: RobotArm, q: np.ndarray) -> np.ndarray:
    """``q`` with every joint pinned at a limit moved to its home angle."""
    margin = PINNED * (robot.upper - robot.lower)
    pinned = (q <= robot.lower + margin) | (q >= robot.upper - margin)
    return np.where(pinned, robot.home, q)


class Retargeter:
    """Human arm angles to Puma560 angles, in joint or cartesian mode.

    Args:
        mode: ``"joint"`` or ``"cartesian"``; switchable later through ``.mode``. Default:
            joint for the Puma560, cartesian for any other robot.
        mirror: mirror the operator (the paper's choice).
        robot: the Puma560 (default: one whose IK is capped at ``ik_iterations``), or any
            :class:`RobotArm` (then the mode must be cartesian, the default for it).
        arm: the operator's arm (default: the right arm of default size).
        config: defaults.
    """

    def __init__(
        self,
        mode: Mode | None = None,
        mirror: bool = True,
        robot: Puma560 | RobotArm | None = None,
        arm: HumanArm | None = None,
        config: RetargetConfig | None = None,
    ) -> None:
        if robot is not None and not isinstance(robot, Puma560 | RobotArm):
            raise KinematicsError(
                f"Retargeter's robot must be a Puma560 or a RobotArm; got {type(robot).__name__}."
            )
        instance_of(arm, HumanArm, "Retargeter's arm", optional=True)
        instance_of(config, RetargetConfig, "Retargeter's config", optional=True)
        self.config = config or RetargetConfig()
        self.robot = robot or Puma560(ik=IKConfig(max_iterations=self.config.ik_iterations))
        self.arm = arm or HumanArm()
        self.mirror = bool(mirror)
        self.mode = mode or ("joint" if isinstance(self.robot, Puma560) else "cartesian")
        self._q_prev: np.ndarray | None = None
        self._q_human_prev: np.ndarray | None = None
        self.last_ik: IKResult | RobotIK | None = None
        """The last cartesian-mode IK result (``success``, ``error``, ``message``): an
        unreachable hand pose is reported here, while ``robot_from_human`` returns the closest
        configuration within the limits."""
        self._guard: ClearanceGuard | None = None
        self._draws: dict[str, np.ndarray] = {}
        self._workspace: tuple[tuple, Workspace] | None = None
        self.pulled_in = 0.0
        """How far (m) the last cartesian-mode hand target was drawn back into the robot's reach
        (0 while the scaled hand lies within it; see ``RetargetConfig.reach_softness`` and
        ``hollow_softness``)."""
        self.pushed_out = 0.0
        """The part of ``pulled_in`` (m) that moved the target out of the column around the
        robot's first axis where it cannot reach (:attr:`RobotSpec.hollow`)."""
        self.held = False
        """Whether the last cartesian-mode frame held the previous pose, because the new one
        would have brought the robot's links into contact."""

    # ---------------------------------------------------------------------------- settings

    @property
    def mode(self) -> Mode:
        """``"joint"`` or ``"cartesian"``."""
        return self._mode

    @mode.setter
    def mode(self, value: Mode) -> None:
        if value not in ("joint", "cartesian"):  # a caller without a type checker
            raise KinematicsError(f'Retarget mode must be "joint" or "cartesian"; got {value!r}.')
        if value == "joint" and not self.joint_mode_possible:
            raise KinematicsError(
                f"Joint mode maps the human arm onto the Puma560's joints; the "
                f"{self.robot.spec.title} follows the hand in cartesian mode: choose cartesian."
            )
        self._mode = value

    @property
    def joint_mode_possible(self) -> bool:
        """Whether the robot's joints can follow the operator's one by one (joint mode): the
        Puma560's can (:attr:`RobotSpec.joint_mode`), as its analytic model or its registry
        arm."""
        robot = self.robot
        return isinstance(robot, Puma560) or robot.spec.joint_mode

    @property
    def mirror(self) -> bool:
        """Whether the robot mirrors the operator."""
        return self._mirror

    @mirror.setter
    def mirror(self, value: bool) -> None:
        self._mirror = bool(value)
        # Lateral joints flip when mirroring, and again for a left arm (already a mirror image).
        flip = self._mirror != (self.arm.side == "left")
        self._signs = np.array([s * (-1.0 if lat and flip else 1.0) for _, s, _, lat in JOINT_MAP])

    def reset(self) -> None:
        """Forget the previous cartesian solution (the next IK starts cold)."""
        self._q_prev = None
        self._q_human_prev = None

    # ---------------------------------------------------------------------------- mapping

    def robot_from_human(self, q_human: object) -> np.ndarray:
        """Puma joint angles for the operator's arm angles.

        Args:
            q_human: arm angles (rad), shape (7,).

        Returns:
            ``q_robot`` (rad, shape (6,)), within the Puma's limits.

        Raises:
            KinematicsError: wrong shape or non-finite angles.
        """
        q = _as_q(q_human, self.arm.nq, "q_human")
        if q.shape != (self.arm.nq,):
            raise KinematicsError(f"q_human must have shape (7,); got shape {q.shape}.")
        q_robot = self._joint(q) if self._mode == "joint" else self._cartesian(q)
        return q_robot

    def _joint(self, q_human: np.ndarray) -> np.ndarray:
        signs = self._signs
        q_robot = np.array(
            [offset + signs[j] * q_human[i] for j, (i, _, offset, _) in enumerate(JOINT_MAP)]
        )
        return np.minimum(np.maximum(q_robot, self.robot.lower), self.robot.upper)

    def _shoulder(self) -> np.ndarray:
        """Where the operator's shoulder is placed in the robot's base frame.

        The Puma560's shoulder; for a robot on a table, its :attr:`workspace`'s centre, halfway
        up its reach above the table, so the operator's hand at shoulder height (a reach
        forward) lands mid-workspace and a lowered hand near the table, not under it.
        """
        robot = self.robot
        if isinstance(robot, Puma560):
            return np.array([0.0, 0.0, robot.dh[0].d])
        return self.workspace.centre.copy()

    @property
    def workspace(self) -> Workspace:
        """The robot's workspace the operator's reach maps into (a robot of :func:`load_robot`;
        :class:`Workspace`): its ball ``config.reach_share`` of the soft ceiling's, above the
        table's floor."""
        robot = self.robot
        if not isinstance(robot, RobotArm):
            raise KinematicsError("The Puma560's analytic model has no table workspace.")
        config = self.config
        key = (robot.name, config.reach_fraction, config.reach_share, config.floor_height)
        if self._workspace is None or self._workspace[0] != key:
            floor = config.floor_height + config.floor_softness
            radius = config.reach_share * self._ceiling()
            ahead = None  # an arm with a hollow: its centre in front of it, out of the soft band
            if robot.spec.hollow > 0.0:
                out = robot.spec.hollow * robot.reach + 2.0 * config.hollow_softness
                ahead = out * _forward(robot)
            self._workspace = (key, Workspace.of(robot, radius, floor, ahead))
        return self._workspace[1]

    def _ceiling(self) -> float:
        """The radius (m) the soft ceiling keeps targets within, around the robot's shoulder."""
        return self.config.reach_fraction * self._reach()

    def _ceiling_width(self) -> float:
        """The soft ceiling's band (m): ``reach_softness``, narrowed to end at the workspace's
        edge, so a target the workspace placed is never bent."""
        return min(self.config.reach_softness, (1.0 - self.config.reach_share) * self._ceiling())

    def _placed(self, p: np.ndarray) -> np.ndarray:
        """A point of the operator's arm (m, from their shoulder, mirrored and turned into the
        robot's base frame) placed in the robot's base frame: into its :attr:`workspace`
        (the Puma560's analytic model: scaled, at its shoulder)."""
        if not isinstance(self.robot, RobotArm):
            return self._shoulder() + self._scale() * p
        return self.workspace.into(p / self._arm_reach())

    def _reach(self) -> float:
        """How far the robot's tool reaches (m), as the retargeting maps the operator's reach
        onto it (:attr:`RobotSpec.usable_reach`), before ``config.reach_fraction``."""
        robot = self.robot
        return robot.reach * (robot.spec.usable_reach if isinstance(robot, RobotArm) else 1.0)

    def _scale(self) -> float:
        return self.config.reach_fraction * self._reach() / self._arm_reach()

    def _arm_reach(self) -> float:
        """The operator's reach (m): shoulder to hand centre, the arm outstretched."""
        arm = self.arm
        return arm.upper_arm_length + arm.forearm_length + arm.hand_length

    def _mirrored(self, p: np.ndarray) -> np.ndarray:
        return SAGITTAL_MIRROR @ p if self._mirror else p

    def elbow_target(self, q_human: object) -> np.ndarray:
        """Where the robot's elbow should be (m, robot base frame): the operator's, mirrored and
        scaled like the hand."""
        elbow = self._mirrored(self.arm.forward(q_human).elbow[:3, 3])
        if isinstance(self.robot, RobotArm):
            elbow = self.robot.base_rotation.T @ elbow
        return self._placed(elbow)

    def hand_target(self, q_human: object) -> np.ndarray:
        """The robot tool pose (4x4, robot base frame) that cartesian mode aims at.

        Args:
            q_human: arm angles (rad), shape (7,).

        Returns:
            ``oMdes``: the mirrored (if set), scaled hand-centre pose placed at the Puma's
            shoulder, with the tool's approach axis along the fingers. For a robot on a table
            the target is then kept above the table, out of the arm's hollow (if it has one)
            and within its reach, all softly (see :class:`RetargetConfig`).
        """
        return self._target(q_human)[0]

    def _target(self, q_human: object) -> tuple[np.ndarray, float, float]:
        """The hand target, how far it was drawn back into reach (m), and how much of that
        moved it out of the robot's hollow (m)."""
        pose = self.arm.forward(q_human).hand
        p, R = self._mirrored(pose[:3, 3]), pose[:3, :3]
        if self._mirror:
            R = SAGITTAL_MIRROR @ R @ URDF_LATERAL_MIRROR
        R = R @ HAND_TO_TOOL
        robot, config = self.robot, self.config
        if isinstance(robot, RobotArm):
            # into the URDF's base frame, which may face elsewhere than the studio's x (SO-100)
            p, R = robot.base_rotation.T @ p, robot.base_rotation.T @ R @ robot.tool_axes
        oMdes = np.eye(4)
        oMdes[:3, :3] = R
        oMdes[:3, 3] = self._placed(p)
        if not isinstance(robot, RobotArm):
            return oMdes, 0.0, 0.0
        oMdes[2, 3] = soft_floor(float(oMdes[2, 3]), config.floor_height, config.floor_softness)
        pushed = 0.0
        if robot.spec.hollow > 0.0:  # out of the column around the first axis, level
            across = oMdes[:2, 3] - robot.shoulder[:2]
            moved = out_of_hollow(
                across, robot.spec.hollow * robot.reach, config.hollow_softness, _forward(robot)
            )
            oMdes[:2, 3] = robot.shoulder[:2] + moved
            pushed = float(np.linalg.norm(moved - across))
        # Between two points above the table, so the drawn-back target stays above it too.
        offset = oMdes[:3, 3] - robot.shoulder
        distance = float(np.linalg.norm(offset))
        kept = soft_ceiling(distance, self._ceiling(), self._ceiling_width())
        if kept < distance:
            oMdes[:3, 3] = robot.shoulder + offset * (kept / distance)
        return oMdes, pushed + distance - kept, pushed

    def _cartesian(self, q_human: np.ndarray) -> np.ndarray:
        oMdes, self.pulled_in, self.pushed_out = self._target(q_human)
        robot = self.robot
        if isinstance(robot, RobotArm):
            found: IKResult | RobotIK = self._solve_arm(robot, oMdes, q_human)
        else:
            found = self._solve_puma(robot, oMdes, q_human)
        self.last_ik = found
        q = found.q
        if self._q_prev is not None and (isinstance(robot, RobotArm) or self._smooth(q_human)):
            step = self.config.max_joint_step
            q = self._q_prev + np.clip(q - self._q_prev, -step, step)
        self._q_human_prev = q_human.copy()
        if isinstance(robot, RobotArm):
            self.held = bool(self._clearance(robot).collisions(q))
            if self.held:
                # hold the last pose clear of contact (the robot's home before the first)
                q = robot.home if self._q_prev is None else self._q_prev
        self._q_prev = q.copy()
        return q.copy()

    def _smooth(self, q_human: np.ndarray) -> bool:
        """Whether ``q_human`` continues the last frame's arm (no joint turned further than a
        human arm turns in a frame)."""
        last = self._q_human_prev
        return last is not None and float(np.abs(q_human - last).max()) <= self.config.input_jump

    def _clearance(self, robot: RobotArm) -> ClearanceGuard:
        """The contact guard (links and table) for the configured clearance (made again if it
        changed)."""
        if self._guard is None or self._guard.margin != self.config.clearance:
            self._guard = ClearanceGuard(robot, self.config.clearance)
        return self._guard

    def _solve_puma(
        self, puma: Puma560, oMdes: np.ndarray, q_human: np.ndarray
    ) -> IKResult | RobotIK:
        """The Puma560's IK for one frame: while the arm moves, first within the joint motion
        one frame allows (as for any arm, by the compiled IK on its chain); else its own IK
        from the last pose, the pose or else the position."""
        if self._q_prev is not None and self._smooth(q_human):
            chain_arm = load_robot("puma560", geometry=False)  # the same DH model, compiled
            settings = {"iterations": self.config.ik_iterations}
            near = self._within_a_step(chain_arm, self._q_prev, oMdes, settings)
            if near is not None:
                return near
        found = puma.inverse(oMdes, q0=self._q_prev)
        if not found.success:
            start = found.q if self._q_prev is None else self._q_prev
            position = puma.inverse(oMdes[:3, 3], q0=start, position_only=True)
            if position.success or position.error < found.error:
                found = position
        return found

    def _solve_arm(self, robot: RobotArm, oMdes: np.ndarray, q_human: np.ndarray) -> RobotIK:
        """The arm's IK for one frame: the pose, else the position; one elbow step a frame.

        First within the joint motion one frame allows around the last frame's pose: a pose
        there that reaches the target (:meth:`RetargetConfig.within_reach`) is taken, so the
        robot never leaves a branch that still reaches for one that reaches more exactly.
        Otherwise the solve goes on unbounded from the last pose, and then, as a joint is often
        pinned at a limit in a basin that no longer holds the pose, from that answer with its
        pinned joints moved home, from home and from ``config.restart_starts`` fixed poses; of
        the answers that reach the target, the one nearest the last pose is taken (a joint with
        a turn to spare counted the short way round, one cramped at a limit counted further:
        ``config.limit_room``), and the step cap walks the robot there over as many frames as
        it needs. A pose that would bring the robot's links into contact, with each other or
        with the table it stands on, does not count as reaching: another branch's is looked
        for, and only where none is clear does the robot hold its last pose. There the restarts
        also start from the pose the robot walks to, so that pose is followed rather than found
        afresh on whichever branch is nearest each frame (which turned joints back and forth).
        """
        config = self.config
        start = robot.home if self._q_prev is None else self._q_prev
        settings = self._settings(robot, start, q_human)
        touches = self._clearance(robot).collisions
        if self._q_prev is not None:
            near = self._within_a_step(robot, self._q_prev, oMdes, settings)
            if near is not None and not touches(near.q):
                return near
        found = robot.inverse(oMdes, q0=start, **settings)
        settings["iterations"] = config.restart_iterations
        if not self._reached(found):  # the pose may have moved further than a few iterations go
            found = robot.inverse(oMdes, q0=found.q, **settings)
        touching = bool(touches(found.q))
        if not self._reached(found) or touching:
            nearest = math.inf
            seeds = [_unpinned(robot, found.q), robot.home, *self._starts(robot)]
            if isinstance(self.last_ik, RobotIK) and touching:  # the pose walked to
                seeds.insert(0, self.last_ik.q)
            for seed in seeds:
                other = robot.inverse(oMdes, q0=seed, **settings)
                if not self._reached(other):
                    continue
                q = _turned_near(robot, other.q, start)
                distance = float(np.abs(q - start).max()) + self._cramped(robot, q)
                if distance < nearest and not touches(q):
                    found, nearest = replace(other, q=q), distance
            settings["iterations"] = config.ik_iterations
        if not self._reached(found) and robot.spec.orientation:
            position = robot.inverse(oMdes[:3, 3], q0=found.q, **settings)
            if position.success or position.position_error < found.position_error:
                found = position
        return found

    def pose_near(
        self, q: np.ndarray, q_human: np.ndarray, oMdes: np.ndarray | None = None
    ) -> np.ndarray | None:
        """A pose of the robot (a :class:`RobotArm`) within one frame's joint motion of ``q``
        that reaches the target of ``q_human`` (``oMdes``, if already known), clear of
        contact (:meth:`RobotArm.contacts`); or None. The step the live retargeting looks for
        first, taken from any pose (the path planner's)."""
        robot = self.robot
        assert isinstance(robot, RobotArm)
        oMdes = self.hand_target(q_human) if oMdes is None else oMdes
        found = self._within_a_step(robot, q, oMdes, self._settings(robot, q, q_human))
        if found is None or self._clearance(robot).collisions(found.q):
            return None
        return found.q

    def poses_reaching(self, q_human: np.ndarray, apart: float) -> list[np.ndarray]:
        """Poses of the robot (a :class:`RobotArm`) that reach the target of ``q_human``, clear
        of contact (its own links and the table), found by the IK from home and the fixed
        restart poses; no two closer than ``apart`` (rad, any joint)."""
        robot = self.robot
        assert isinstance(robot, RobotArm)
        oMdes, found = self.hand_target(q_human), []
        for seed in (robot.home, *self._starts(robot)):
            settings = self._settings(robot, seed, q_human)
            settings["iterations"] = self.config.restart_iterations
            answer = robot.inverse(oMdes, q0=seed, **settings)
            if not self._reached(answer) or self._clearance(robot).collisions(answer.q):
                continue
            if all(np.abs(answer.q - other).max() >= apart for other in found):
                found.append(answer.q)
        return found

    def _damping(self, robot: RobotArm, q: np.ndarray) -> float:
        """The IK's damping for a frame that starts at ``q`` (see
        :attr:`RetargetConfig.singular_margin`)."""
        config = self.config
        rows = 6 if robot.spec.orientation else 3
        if robot.nq > rows:  # joints to spare
            return IK_DAMPING
        smallest = float(np.linalg.svd(robot.chain.jacobian(q, rows), compute_uv=False)[-1])
        if smallest >= config.singular_margin:
            return IK_DAMPING
        near = 1.0 - (smallest / config.singular_margin) ** 2
        return math.sqrt(IK_DAMPING**2 + near * config.singular_damping**2)

    def _cramped(self, robot: RobotArm, q: np.ndarray) -> float:
        """How much further (rad) a restart's answer ``q`` counts for a joint nearer its limit
        than ``config.limit_room`` (see there)."""
        config = self.config
        room = float(np.min(np.minimum(q - robot.lower, robot.upper - q)))
        return config.limit_room_weight * max(0.0, config.limit_room - room)

    def _reached(self, found: RobotIK) -> bool:
        return self.config.within_reach(found.position_error, found.rotation_error)

    def _settings(self, robot: RobotArm, start: np.ndarray, q_human: np.ndarray) -> dict:
        """The IK's settings for a frame of ``q_human`` that starts at ``start``."""
        return {
            "elbow": self.elbow_target(q_human) if robot.nq > 6 else None,
            "iterations": self.config.ik_iterations,
            "elbow_iterations": 1,
            "damping": self._damping(robot, start),
        }

    def _within_a_step(
        self, arm: RobotArm, q_prev: np.ndarray, oMdes: np.ndarray, settings: dict
    ) -> RobotIK | None:
        """A pose within one frame's joint motion of ``q_prev`` that reaches ``oMdes``, searched
        from ``q_prev`` and from ``config.near_starts`` fixed points around it; or None."""
        step = self.config.max_joint_step
        lower, upper = q_prev - step, q_prev + step
        offsets = self._fixed_draws("near", -np.ones(arm.nq), np.ones(arm.nq))
        best: RobotIK | None = None
        for offset in (np.zeros(arm.nq), *offsets):
            near = arm.inverse(oMdes, q_prev + step * offset, lower=lower, upper=upper, **settings)
            if self._reached(near):
                return near
            if best is None or near.position_error < best.position_error:
                best = near
        assert best is not None
        # the nearest may only need more iterations (a target that moved fast)
        more = {**settings, "iterations": self.config.restart_iterations}
        near = arm.inverse(oMdes, best.q, lower=lower, upper=upper, **more)
        if self._reached(near):
            return near
        # the last pose itself may be within reach of the target, where the solves, aiming at
        # it exactly, stalled against the step's bounds further off
        return self._reached_at(arm, q_prev, oMdes)

    def _reached_at(self, arm: RobotArm, q: np.ndarray, oMdes: np.ndarray) -> RobotIK | None:
        """``q`` as an IK answer if its tool reaches ``oMdes``, else None."""
        errors = tool_errors(arm.chain.forward(q), oMdes, arm.spec.orientation)
        found = RobotIK(q.copy(), False, *errors, 0)
        return found if self._reached(found) else None

    def _starts(self, robot: RobotArm) -> np.ndarray:
        """The fixed restart poses of ``robot`` (drawn once, seeded)."""
        return self._fixed_draws("restart", robot.lower, robot.upper)

    def _fixed_draws(self, what: str, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
        """Points drawn once (seeded) between ``lower`` and ``upper``: ``config.near_starts``
        of them for ``"near"``, ``config.restart_starts`` for ``"restart"``."""
        drawn = self._draws.get(what)
        if drawn is None or drawn.shape[1] != len(lower):
            count = self.config.near_starts if what == "near" else self.config.restart_starts
            drawn = np.random.default_rng(RESTART_SEED).uniform(lower, upper, (count, len(lower)))
            self._draws[what] = drawn
        return drawn

    def human_from_robot(self, q_robot: object) -> np.ndarray:
        """Operator arm angles that joint mode maps onto ``q_robot``: its inverse.

        Exact (``robot_from_human(human_from_robot(q)) == q``) wherever the result lies within the
        human limits; humeral rotation, which joint mode ignores, is zero. The simulator uses it
        to drive the operator's arm towards a robot goal.

        Args:
            q_robot: Puma angles (rad), shape (6,).

        Returns:
            ``q_human`` (rad, shape (7,)), clipped to the arm's limits.

        Raises:
            KinematicsError: wrong shape or non-finite angles.
        """
        q = _as_q(q_robot, 6, "q_robot")
        if q.shape != (6,):
            raise KinematicsError(f"q_robot must have shape (6,); got shape {q.shape}.")
        signs = self._signs
        q_human = np.zeros(self.arm.nq)
        for j, (i, _, offset, _) in enumerate(JOINT_MAP):
            q_human[i] = (q[j] - offset) * signs[j]
        return np.minimum(np.maximum(q_human, self.arm.lower), self.arm.upper)

    def human_reaching(self, q_robot: object, q_seed: object = None) -> np.ndarray:
        """Operator arm angles whose retargeting puts the robot at ``q_robot``, in either mode.

        Joint mode (the Puma560): :meth:`human_from_robot`, exact. Cartesian mode: the hand pose
        whose target (:meth:`hand_target`) is the robot's tool pose at ``q_robot``, undoing the
        soft limits of the reach, the hollow and the table, the placement, the scale, the base's turn and
        the mirror, then
        the arm that holds the hand there (:func:`fit_hand_pose`, within the arm's limits; where
        the arm cannot, the closest it can). The simulator uses it to reach a goal of any robot.

        Args:
            q_robot: the robot's angles (rad), its ``nq``.
            q_seed: where the hand guide's solver starts (rad, (7,)); default: the neutral arm.

        Returns:
            ``q_human`` (rad, shape (7,)), within the arm's limits.

        Raises:
            KinematicsError: wrong shape or non-finite angles.
        """
        robot = self.robot
        if self.mode == "joint" or not isinstance(robot, RobotArm):
            return self.human_from_robot(q_robot)
        tool = robot.forward(robot.check_q(q_robot, "q_robot"))
        turn = robot.base_rotation  # out of the URDF's base frame (the SO-100 faces -y)
        R = turn @ tool[:3, :3] @ robot.tool_axes.T @ HAND_TO_TOOL.T
        # undo the target's soft limits, the reach's (applied last) first, then the table's
        config, t = self.config, tool[:3, 3].copy()
        offset = t - robot.shoulder
        distance = float(np.linalg.norm(offset))
        if distance > 0.0:
            unbent_distance = unbent(distance, self._ceiling(), self._ceiling_width())
            t = robot.shoulder + offset * (unbent_distance / distance)
        if robot.spec.hollow > 0.0:
            hollow = robot.spec.hollow * robot.reach
            across = t[:2] - robot.shoulder[:2]
            found = into_hollow(across, hollow, config.hollow_softness, _forward(robot))
            t[:2] = robot.shoulder[:2] + found
        t[2] = unfloored(float(t[2]), config.floor_height, config.floor_softness)
        p = turn @ self.workspace.out_of(t) * self._arm_reach()
        if self._mirror:  # both mirrors are their own inverses
            R = SAGITTAL_MIRROR @ R @ URDF_LATERAL_MIRROR
        oMhand = np.eye(4)
        oMhand[:3, :3] = R
        oMhand[:3, 3] = self._mirrored(p)
        q = fit_hand_pose(oMhand, self.arm.side, q_seed).q_human
        return np.minimum(np.maximum(q, self.arm.lower), self.arm.upper)
