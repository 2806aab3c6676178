"""Movement-primitive policy files: a DMP fitted to a demonstration, on disk and rolled out.

Format ``teach-studio-dmp-policy``, version 1: a ``.policy.npz`` archive (no pickles) beside the
tabular and tile-coded formats, holding

- ``header``: a 0-d unicode array with a JSON object::

      {"format": "teach-studio-dmp-policy", "version": 1,
       "robot": "panda",               (the robot whose joints it moves; absent: the Puma560)
       "primitive": {"joints": 7, "basis": 50, "duration_s": 2.49, "alpha_z": 25.0,
                     "alpha_x": 4.0, "start": [...nq rad...], "goal": [...nq rad...]},
       "goal": [...nq rad...],         (where rollouts go; the demonstration's end by default)
       "learned_joints": 3,            (the joints the likeness card compares)
       "likeness": {...},              (LikenessCard.to_dict() from the demonstration's start)
       "created": "...", "notes": ""}

- ``weights``: float64 ``(joints, basis)``, the forcing terms (see :mod:`._dmp`);
- ``demo_times``: float64 ``(N,)`` and ``demo_q``: float64 ``(N, nq)``, the demonstration it was
  fitted to, so its likeness card can be computed from the file alone.

``joints`` is the robot's joint count (``nq``: six for the Puma560, seven for the Panda): a
primitive is fitted in its robot's joint space, to a demonstration retargeted onto that robot
(``studio.motion.training_demonstration``, the path a training run replays).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from .._errors import ConfigError, LearningError, PolicyFileError
from ..likeness._likeness import LikenessCard, likeness_card, robot_tool_positions
from ..tabular._policy import MAX_NPZ_BYTES, ROLLOUT_RATE_HZ, BoundedNpz, read_header
from ..tasks._robot import PUMA560, check_robot, robot_title, task_arm
from ._dmp import (
    DMP_BASIS,
    DMP_SETTLE_RAD,
    MovementPrimitive,
    fit_movement_primitive,
    roll_out_primitive,
)

FORMAT_NAME = "teach-studio-dmp-policy"
FORMAT_VERSION = 1
MAX_DEMO_SAMPLES = 1_000_000
"""Most demonstration samples a DMP policy file may hold."""


@dataclass(frozen=True, eq=False)
class DmpPolicyFile:
    """A movement-primitive baseline policy: a DMP and the demonstration it was fitted to.

    Attributes:
        primitive: the fitted DMP over the robot's joints.
        goal: where rollouts go ``(nq,)`` (rad).
        demo_times: the demonstration's sample times ``(N,)`` (s).
        demo_q: the demonstration's joints on the robot ``(N, nq)`` (rad).
        learned_joints: joints the likeness card compares (the demonstration's task joints).
        created: ISO 8601 time of writing.
        notes: free text.
        mean_steps: empty (a primitive has no learning curve; kept so listings read all kinds alike).
        experiments: 1.
        robot: the robot it drives (a registry name; the Puma560 for a file that names none).
    """

    primitive: MovementPrimitive
    goal: np.ndarray
    demo_times: np.ndarray
    demo_q: np.ndarray
    learned_joints: int = 6
    created: str = ""
    notes: str = ""
    mean_steps: np.ndarray = field(default_factory=lambda: np.zeros(0))
    experiments: int = 1
    robot: str = PUMA560

    def header(self, likeness: LikenessCard | None = None) -> dict[str, object]:
        """The JSON header written to the file."""
        p = self.primitive
        return {
            "format": FORMAT_NAME,
            "version": FORMAT_VERSION,
            "robot": self.robot,
            "primitive": {
                "joints": p.joints,
                "basis": p.basis,
                "duration_s": p.duration_s,
                "alpha_z": p.alpha_z,
                "alpha_x": p.alpha_x,
                "start": p.start.tolist(),
                "goal": p.goal.tolist(),
            },
            "goal": self.goal.tolist(),
            "learned_joints": self.learned_joints,
            "likeness": None if likeness is None else likeness.to_dict(),
            "created": self.created,
            "notes": self.notes,
        }


def fit_dmp_policy(
    times: np.ndarray,
    q_robot: np.ndarray,
    *,
    goal: np.ndarray | None = None,
    learned_joints: int | None = None,
    basis: int = DMP_BASIS,
    notes: str = "",
    robot: str = PUMA560,
) -> DmpPolicyFile:
    """Fit the movement-primitive baseline to a demonstration's joint path on ``robot``.

    Args:
        times: the demonstration's sample times ``(N,)`` (s).
        q_robot: its joints on the robot ``(N, nq)`` (rad): a demonstration's ``q_robot`` for
            the Puma560; for another robot, the demonstration retargeted onto it
            (``studio.motion.training_demonstration(path, robot, label).q_robot``).
        goal: where rollouts go (default: where the demonstration ends).
        learned_joints: the joints its likeness card compares (a demonstration's grid joints;
            default: all the robot's).
        basis: basis functions per joint.
        notes: free text.
        robot: the robot whose joints these are (``studio robots``; the Puma560 by default).

    Raises:
        LearningError: an unknown robot, a path that is not ``(N, nq)`` finite angles of it, or
            a bad goal or count.
    """
    try:
        arm = task_arm(check_robot(robot))
    except ConfigError as err:
        raise LearningError(str(err)) from None
    width, title = arm.nq, robot_title(arm.name)
    q = np.asarray(q_robot, dtype=np.float64)
    if q.ndim != 2 or q.shape[1] != width:
        raise LearningError(
            f"The demonstration's joints have shape {q.shape}; give (N, {width}) {title} angles in radians (a demonstration retargeted onto it)."
        )
    learned = width if learned_joints is None else learned_joints
    if not isinstance(learned, int) or not 1 <= learned <= width:
        raise LearningError(f"learned_joints is {learned_joints!r}; give 1 to {width}.")
    primitive = fit_movement_primitive(times, q, basis)
    target = primitive.goal if goal is None else np.asarray(goal, dtype=np.float64).reshape(-1)
    if target.shape != (width,) or not np.all(np.isfinite(target)):
        raise LearningError(
            f"The goal has {target.size} angles; give {width} in radians, one per {title} joint."
        )
    return DmpPolicyFile(
        primitive=primitive,
        goal=target.copy(),
        demo_times=np.asarray(times, dtype=np.float64).reshape(-1).copy(),
        demo_q=q.copy(),
        learned_joints=learned,
        created=datetime.now(UTC).isoformat(timespec="seconds"),
        notes=notes,
        robot=arm.name,
    )


def rollout_dmp_policy(
    policy: DmpPolicyFile, start_q: np.ndarray | None = None, rate_hz: float = ROLLOUT_RATE_HZ
) -> tuple[np.ndarray, np.ndarray, bool]:
    """The primitive from ``start_q`` (default: the demonstration's start) to the policy's goal.

    The primitive knows nothing of the robot's joint limits: a demonstration that runs along a
    limit (the Panda's fourth joint near -4 degrees) comes back a hair beyond it, so the rollout
    is kept within the robot's limits, as every motion the studio plays or exports is.

    Returns:
        ``(times (N,), q (N, nq), reached)``: ``reached`` when every joint ends within
        :data:`._dmp.DMP_SETTLE_RAD` of the goal.
    """
    times, q = roll_out_primitive(policy.primitive, start_q, policy.goal, rate_hz)
    arm = task_arm(policy.robot)
    width = q.shape[1]
    q = np.clip(q, arm.lower[:width], arm.upper[:width])
    reached = bool(np.all(np.abs(q[-1] - policy.goal) <= DMP_SETTLE_RAD))
    return times, q, reached


def dmp_likeness_card(policy: DmpPolicyFile, rate_hz: float = ROLLOUT_RATE_HZ) -> LikenessCard:
    """The likeness card of the primitive's rollout from the demonstration's own start."""
    times, q, _ = rollout_dmp_policy(policy, policy.demo_q[0], rate_hz)
    k = policy.learned_joints

    def tool(q: np.ndarray) -> np.ndarray:
        return robot_tool_positions(policy.robot, q)

    return likeness_card(times, q, policy.demo_times, policy.demo_q, tool, joints=k)


def save_dmp_policy(
    path: str | Path, policy: DmpPolicyFile, *, compress: bool = True
) -> LikenessCard:
    """Write a DMP policy file (format above), its likeness card in the header; return the card."""
    card = dmp_likeness_card(policy)
    with Path(path).open("wb") as stream:
        (np.savez_compressed if compress else np.savez)(
            stream,
            header=np.array(json.dumps(policy.header(card))),
            weights=policy.primitive.weights,
            demo_times=policy.demo_times,
            demo_q=policy.demo_q,
        )
    return card


def _vector(value: object, size: int, what: str) -> np.ndarray:
    v = np.asarray(value, dtype=np.float64).reshape(-1)
    if v.shape != (size,) or not np.all(np.isfinite(v)):
        raise ValueError(f"its {what} is not {size} finite numbers")
    return v


def load_dmp_policy(path: str | Path) -> DmpPolicyFile:
    """Read a DMP policy file, checking its format, version, header and shapes.

    Raises:
        PolicyFileError: missing, corrupt, not a DMP policy, or from a newer version.
    """
    path = Path(path)
    name = path.name
    if not path.is_file():
        raise PolicyFileError(
            f"Policy file {name} does not exist; give the path of a .policy.npz file."
        )
    with BoundedNpz(path, name, MAX_NPZ_BYTES) as archive:
        header = read_header(archive, name)
        if not isinstance(header, dict) or header.get("format") != FORMAT_NAME:
            raise PolicyFileError(f"{name} is not a DMP policy file; export the policy again.")
        version = header.get("version")
        if not isinstance(version, int) or isinstance(version, bool) or version > FORMAT_VERSION:
            raise PolicyFileError(
                f"{name} uses DMP policy format version {version!r}, not one this studio reads ({FORMAT_VERSION}); upgrade Teach Studio to read it."
            )
        robot = _robot_of(header, name)
        try:
            spec = header["primitive"]
            joints, basis = int(spec["joints"]), int(spec["basis"])
            width = task_arm(robot).nq
            if joints != width:
                raise ValueError(
                    f"it moves {joints} joints where the {robot_title(robot)} has {width}"
                )
            if basis < 2:
                raise ValueError(f"it has {basis} basis functions")
            weights = archive.read("weights", (joints, basis), "f").astype(np.float64)
            demo_times = archive.read("demo_times", None, "f").astype(np.float64)
            demo_q = archive.read("demo_q", (demo_times.shape[0], joints), "f").astype(np.float64)
            if demo_times.ndim != 1 or not 3 <= demo_times.shape[0] <= MAX_DEMO_SAMPLES:
                raise ValueError("its demonstration is not 3 or more samples")
            primitive = MovementPrimitive(
                weights=weights,
                start=_vector(spec["start"], joints, "start"),
                goal=_vector(spec["goal"], joints, "demonstrated goal"),
                duration_s=float(spec["duration_s"]),
                alpha_z=float(spec["alpha_z"]),
                alpha_x=float(spec["alpha_x"]),
            )
            goal = _vector(header["goal"], joints, "goal")
            learned = header.get("learned_joints", joints)
            if not isinstance(learned, int) or not 1 <= learned <= joints:
                raise ValueError(f"learned_joints is {learned!r}")
            if not (np.all(np.isfinite(weights)) and np.all(np.isfinite(demo_q))):
                raise ValueError("it holds NaN values")
            if not primitive.duration_s > 0:
                raise ValueError("its duration is not positive")
        except (KeyError, TypeError, ValueError, AttributeError, OverflowError) as err:
            raise PolicyFileError(
                f"{name} has a damaged header ({err}); export the policy again."
            ) from None
    return DmpPolicyFile(
        primitive=primitive,
        goal=goal,
        demo_times=demo_times,
        demo_q=demo_q,
        learned_joints=learned,
        created=str(header.get("created", "")),
        notes=str(header.get("notes", "")),
        robot=robot,
    )


def _robot_of(header: dict[str, object], name: str) -> str:
    """The robot a DMP file names (the Puma560 when it names none), or a PolicyFileError."""
    robot = header.get("robot", PUMA560)
    try:
        if isinstance(robot, str):
            return check_robot(robot)
    except ConfigError:
        pass
    raise PolicyFileError(
        f"{name} names the robot {robot!r}, which this studio does not offer; fit the primitive again for a robot `studio robots` lists."
    )
