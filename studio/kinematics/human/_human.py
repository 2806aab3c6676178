"""The 7-DOF human arm from example-robot-data's ``human.urdf``, reduced with Pinocchio.

Gepetto's human model is Y-up with the arms hanging along -Y. We lock every joint except one
arm's seven (shoulder Z/X/Y, elbow Z/Y, wrist Z/X; the paper's arm) and express all poses in the
*arm base frame*: origin at the shoulder, x forward, y to the operator's left, z up.

Joint conventions (from the URDF, anatomical, identical for both sides):

- ``shoulder_Z``: flexion (+ raises the arm forward), ``shoulder_X``: abduction (+ raises it
  sideways, away from the body), ``shoulder_Y``: humeral rotation,
- ``elbow_Z``: flexion (0 is a straight arm), ``elbow_Y``: forearm rotation,
- ``wrist_Z``: wrist flexion, ``wrist_X``: wrist deviation.

The left chain of ``human.urdf`` uses mirrored joint axes, so the same ``q_human`` puts the left
arm in the mirror image (through the sagittal plane, y -> -y) of the right arm's pose; see
:func:`mirror_human_q`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal, NamedTuple

import numpy as np
import pinocchio as pin

from .._checks import KinematicsError, check_side, positive_number, real_array
from .._robot_specs import robots_folder

URDF_IN_ROBOTS = Path("human_description/robots/human.urdf")
"""Where ``human.urdf`` lies in example-robot-data's robots folder (see ``robots_folder``)."""

ARM_JOINTS = ("shoulder_Z", "shoulder_X", "shoulder_Y", "elbow_Z", "elbow_Y", "wrist_Z", "wrist_X")
"""The seven arm joints kept from ``human.urdf`` (prefixed ``right_`` or ``left_``)."""

YUP_TO_ZUP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
"""Rotation taking ``human.urdf`` vectors (x forward, y up, z right) to the arm base frame."""

SAGITTAL_MIRROR = np.diag([1.0, -1.0, 1.0])
"""Reflection through the sagittal plane in the arm base frame (y -> -y)."""


def find_human_urdf() -> Path:
    """Locate ``human.urdf`` from the installed ``example-robot-data`` distribution.

    Returns:
        The path of ``human.urdf``.

    Raises:
        KinematicsError: the package is not installed.
    """
    path = robots_folder() / URDF_IN_ROBOTS
    if not path.is_file():
        raise KinematicsError(
            "The human arm model human.urdf was not found; install it with "
            "`pip install example-robot-data`."
        )
    return path


def _as_q(value: object, size: int, what: str) -> np.ndarray:
    """``value`` as finite joint angles of shape ``(..., size)``, or a KinematicsError."""
    q = real_array(value, what, f"pass {size} angles in radians")
    if q.shape[-1:] != (size,):
        raise KinematicsError(f"{what} must have shape (..., {size}); got shape {q.shape}.")
    if not np.all(np.isfinite(q)):
        raise KinematicsError(f"{what} contains NaN or infinite angles; pass finite radians.")
    return q


def mirror_human_q(q_human: object) -> np.ndarray:
    """The joint angles of the opposite arm that give the mirror-image pose.

    ``human.urdf`` defines the left arm's joint axes as the mirror images of the right arm's
    (anatomical convention: flexion, abduction and rotation are positive the same way on both
    sides), so mirroring a pose from one arm to the other keeps the angles: this returns a copy.
    It exists so that callers say what they mean, and its law (the left arm's pose at
    ``mirror_human_q(q)`` is the right arm's pose at ``q`` mirrored through the sagittal plane;
    twice is the identity) is tested.

    Args:
        q_human: joint angles (rad), shape ``(..., 7)``.

    Returns:
        The mirrored joint angles, shape ``(..., 7)``.

    Raises:
        KinematicsError: wrong shape or non-finite angles.
    """
    return _as_q(q_human, len(ARM_JOINTS), "q_human").copy()


class ArmJoints(NamedTuple):
    """The arm's Pinocchio joint ids by name (``model.getJointId("right_elbow_Z")``), so that
    code reads ``data.oMi[joints.elbow_Z]`` (the elbow) rather than a bare index."""

    shoulder_Z: int
    shoulder_X: int
    shoulder_Y: int
    elbow_Z: int
    elbow_Y: int
    wrist_Z: int
    wrist_X: int


@dataclass(frozen=True)
class ArmPose:
    """Poses of the arm's landmarks in the arm base frame (4x4 each).

    Orientations are the ``human.urdf`` joint frames turned into the Z-up base frame: in each,
    the limb points along local -y (towards the hand).

    Attributes:
        shoulder: the shoulder joint frame after all three shoulder rotations (upper-arm frame).
        elbow: the elbow frame after both elbow rotations (forearm frame).
        wrist: the wrist frame after both wrist rotations (hand frame at the wrist).
        hand: the hand frame moved along the hand to its centre (``HumanArm.hand_length``).
    """

    shoulder: np.ndarray
    elbow: np.ndarray
    wrist: np.ndarray
    hand: np.ndarray


class HumanArm:
    """One human arm (7 DOF) with forward kinematics in a Z-up, shoulder-centred frame.

    Args:
        side: ``"right"`` or ``"left"``.
        upper_arm: shoulder-to-elbow length in metres (default: the URDF's 0.276 m).
        forearm: elbow-to-wrist length in metres (default: the URDF's 0.287 m).
        hand: wrist-to-hand-centre length in metres (default: the URDF hand's centre of mass
            depth, 0.153 m).

    Attributes:
        model: the reduced Pinocchio model (immutable after construction); its root placement
            already maps into the arm base frame, so ``data.oMi`` are arm-base poses.
        data: scratch space for :meth:`forward` (not thread-safe).
        joints: the model's joint ids by name (:class:`ArmJoints`).
        side, nq (7), joint_names, lower, upper, neutral (zeros: arm hanging),
        upper_arm_length, forearm_length, hand_length.
    """

    nq = len(ARM_JOINTS)

    def __init__(
        self,
        side: Literal["right", "left"] = "right",
        upper_arm: float | None = None,
        forearm: float | None = None,
        hand: float | None = None,
    ) -> None:
        self.side = check_side(side, "The arm's side")
        self.joint_names = tuple(f"{side}_{name}" for name in ARM_JOINTS)
        full = pin.buildModelFromUrdf(str(find_human_urdf()))
        keep = {full.getJointId(name) for name in self.joint_names}
        lock = [j for j in range(1, full.njoints) if j not in keep]
        model = pin.buildReducedModel(full, lock, pin.neutral(full))
        if model.nq != self.nq:  # pragma: no cover - guards a changed URDF
            raise KinematicsError("human.urdf no longer has the expected arm joints; reinstall it.")
        joints = ArmJoints(*(model.getJointId(name) for name in self.joint_names))
        if list(joints) != list(range(1, self.nq + 1)):  # pragma: no cover
            raise KinematicsError("human.urdf's arm joints are not one chain; reinstall it.")
        self.joints = joints

        # Move the root into the arm base frame: Z-up, shoulder at the origin.
        oMshoulder = model.jointPlacements[1]
        baseMurdf = pin.SE3(YUP_TO_ZUP, -YUP_TO_ZUP @ oMshoulder.translation)
        model.jointPlacements[1] = baseMurdf * oMshoulder

        hand_body = full.inertias[full.getJointId(f"{side}_wrist_X")]
        defaults = {
            "upper_arm": -model.jointPlacements[joints.elbow_Z].translation[1],
            "forearm": -model.jointPlacements[joints.wrist_Z].translation[1],
            "hand": -hand_body.lever[1],
        }
        lengths = {"upper_arm": upper_arm, "forearm": forearm, "hand": hand}
        for key, value in lengths.items():
            if value is None:
                lengths[key] = float(defaults[key])
            else:
                lengths[key] = positive_number(value, f"{key} (a length in metres)")
        self.upper_arm_length = float(lengths["upper_arm"])
        self.forearm_length = float(lengths["forearm"])
        self.hand_length = float(lengths["hand"])
        for joint, length in (
            (joints.elbow_Z, self.upper_arm_length),
            (joints.wrist_Z, self.forearm_length),
        ):
            placement = model.jointPlacements[joint]
            model.jointPlacements[joint] = pin.SE3(
                placement.rotation, np.array([0.0, -length, 0.0])
            )
        self.hand_frame = model.addFrame(
            pin.Frame(
                "hand",
                joints.wrist_X,
                pin.SE3(np.eye(3), np.array([0.0, -self.hand_length, 0.0])),
                pin.FrameType.OP_FRAME,
            )
        )
        self.model = model
        self.data = model.createData()
        self.lower = model.lowerPositionLimit.copy()
        self.upper = model.upperPositionLimit.copy()
        self.neutral = np.zeros(self.nq)
        for arr in (self.lower, self.upper, self.neutral):
            arr.setflags(write=False)

    def forward(self, q_human: object) -> ArmPose:
        """Landmark poses of the arm at ``q_human``.

        Args:
            q_human: joint angles (rad), shape (7,). Angles beyond the limits are accepted.

        Returns:
            An :class:`ArmPose` (new arrays).

        Raises:
            KinematicsError: wrong shape or non-finite angles.
        """
        q = _as_q(q_human, self.nq, "q_human")
        if q.shape != (self.nq,):
            raise KinematicsError(f"q_human must have shape (7,); got shape {q.shape}.")
        pin.forwardKinematics(self.model, self.data, q)
        oMi = self.data.oMi
        joints = self.joints
        hand = oMi[joints.wrist_X] * self.model.frames[self.hand_frame].placement
        return ArmPose(
            shoulder=oMi[joints.shoulder_Y].homogeneous,
            elbow=oMi[joints.elbow_Y].homogeneous,
            wrist=oMi[joints.wrist_X].homogeneous,
            hand=hand.homogeneous,
        )

    def points(self, q_human: object) -> np.ndarray:
        """Shoulder, elbow, wrist and hand positions, shape ``(..., 4, 3)``, vectorised over q.

        Args:
            q_human: joint angles (rad), shape ``(..., 7)``.

        Returns:
            Landmark positions in the arm base frame.
        """
        q = _as_q(q_human, self.nq, "q_human")
        flat = q.reshape(-1, self.nq)
        out = np.empty((flat.shape[0], 4, 3))
        for k, qk in enumerate(flat):
            pose = self.forward(qk)
            for j, m in enumerate((pose.shoulder, pose.elbow, pose.wrist, pose.hand)):
                out[k, j] = m[:3, 3]
        return out.reshape(*q.shape[:-1], 4, 3)
