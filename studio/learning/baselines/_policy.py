"""Baseline policy files: the teacher (the demonstrations followed) and behaviour cloning.

Formats ``teach-studio-teacher-policy`` and ``teach-studio-cloning-policy``, version 1: a
``.policy.npz`` archive (no pickles) beside the other kinds, holding

- ``header``: a 0-d unicode array with a JSON object::

      {"format": "teach-studio-teacher-policy", "version": 1,
       "task": {...},                  (ArmReach.to_dict(): the teacher's with its followed paths)
       "seconds_per_step": 0.05,       (the pace of a rollout's step)
       "curve": {"mean_steps": [...], "experiments": 1},
       "created": "...", "notes": ""}

- behaviour cloning only: ``states`` and ``moves``, float64 ``(M, joints)``
  (:class:`._cloning.Cloning`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..._files import now_iso
from .._errors import LearningError, PolicyFileError
from ..linear._teacher import teacher_walk
from ..tabular._policy import (
    MAX_NPZ_BYTES,
    BoundedNpz,
    curve_header,
    read_curve_header,
    read_header,
)
from ..tasks._reach import ArmReach
from ._cloning import Cloning, cloning_rollout

TEACHER_FORMAT = "teach-studio-teacher-policy"
CLONING_FORMAT = "teach-studio-cloning-policy"
FORMAT_VERSION = 1
MAX_CLONED_STATES = 1_000_000
"""Most demonstrated states a cloning policy file may hold."""


@dataclass(frozen=True, eq=False)
class BaselinePolicyFile:
    """What the baselines' policies share (each kind is its own subclass).

    Attributes:
        task: the continuous task (the teacher's with the demonstrated paths it follows).
        seconds_per_step: the time one step takes in a rollout (s).
        mean_steps: its run's steps per episode (the curve listings show).
        experiments: how many experiments the curve averages.
        created: ISO 8601 time of writing.
        notes: free text.
    """

    task: ArmReach
    seconds_per_step: float
    mean_steps: np.ndarray = field(default_factory=lambda: np.zeros(0))
    experiments: int = 1
    created: str = ""
    notes: str = ""

    format = ""

    @property
    def robot(self) -> str:
        """The robot it drives (its task's)."""
        return self.task.robot

    def walk(self, start: np.ndarray, max_steps: int) -> tuple[np.ndarray, bool]:
        """Its joint path ``(K + 1, joints)`` from ``start``, and whether it reaches the goal."""
        raise NotImplementedError

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays its file holds beside the header and the curve."""
        return {}


@dataclass(frozen=True, eq=False)
class TeacherPolicyFile(BaselinePolicyFile):
    """The teacher: the follow action pressed at every step, no learning
    (:func:`studio.learning.linear._teacher.teacher_walk`)."""

    format = TEACHER_FORMAT

    def walk(self, start: np.ndarray, max_steps: int) -> tuple[np.ndarray, bool]:
        return teacher_walk(self.task, start, max_steps)


@dataclass(frozen=True, eq=False)
class CloningPolicyFile(BaselinePolicyFile):
    """Behaviour cloning (:mod:`._cloning`): the nearest demonstrated state's move.

    Attributes:
        cloning: the demonstrated states and moves (the other fields as the teacher's).
    """

    cloning: Cloning = field(default_factory=lambda: Cloning(np.zeros((0, 3)), np.zeros((0, 3))))

    format = CLONING_FORMAT

    def walk(self, start: np.ndarray, max_steps: int) -> tuple[np.ndarray, bool]:
        return cloning_rollout(self.task, self.cloning, start, max_steps)

    def arrays(self) -> dict[str, np.ndarray]:
        return {"states": self.cloning.states, "moves": self.cloning.moves}


def save_baseline_policy(
    path: str | Path, policy: BaselinePolicyFile, *, notes: str = "", compress: bool = True
) -> None:
    """Write a teacher or cloning policy file (format above)."""
    header = {
        "format": policy.format,
        "version": FORMAT_VERSION,
        "task": policy.task.to_dict(),
        "seconds_per_step": float(policy.seconds_per_step),
        "curve": curve_header(policy.mean_steps, policy.experiments),
        "created": now_iso(),
        "notes": notes or policy.notes,
    }
    with Path(path).open("wb") as stream:
        (np.savez_compressed if compress else np.savez)(
            stream, header=np.array(json.dumps(header)), **policy.arrays()
        )


def load_baseline_policy(path: str | Path, kind: str) -> BaselinePolicyFile:
    """Read a teacher (``kind`` :data:`TEACHER_FORMAT`) or cloning policy file.

    Raises:
        PolicyFileError: missing, corrupt, of another format, or from a newer version.
    """
    path = Path(path)
    name = path.name
    if not path.is_file():
        raise PolicyFileError(
            f"Policy file {name} does not exist; give the path of a .policy.npz file."
        )
    with BoundedNpz(path, name, MAX_NPZ_BYTES) as archive:
        header = read_header(archive, name)
        if not isinstance(header, dict) or header.get("format") != kind:
            raise PolicyFileError(f"{name} is not a {kind} file; export the policy again.")
        version = header.get("version")
        if not isinstance(version, int) or isinstance(version, bool) or version > FORMAT_VERSION:
            raise PolicyFileError(
                f"{name} uses {kind} version {version!r}, not one this studio reads ({FORMAT_VERSION}); upgrade Teach Studio to read it."
            )
        try:
            task = ArmReach.from_dict(header["task"])
            pace = float(header["seconds_per_step"])
            if not np.isfinite(pace) or pace <= 0:
                raise ValueError(f"its seconds_per_step is {pace}")
            mean_steps, experiments = read_curve_header(header.get("curve") or {})
            common = {
                "task": task,
                "seconds_per_step": pace,
                "mean_steps": mean_steps,
                "experiments": experiments,
                "created": str(header.get("created", "")),
                "notes": str(header.get("notes", "")),
            }
            if kind == TEACHER_FORMAT:
                if not task.paths:
                    raise ValueError("its task follows no demonstrated path")
                return TeacherPolicyFile(**common)
            states = archive.read("states", None, "f").astype(np.float64)
            if states.ndim != 2 or states.shape[1] != task.joints:
                raise ValueError(f"its states have shape {states.shape}")
            if not 1 <= states.shape[0] <= MAX_CLONED_STATES:
                raise ValueError(f"it holds {states.shape[0]} states")
            moves = archive.read("moves", states.shape, "f").astype(np.float64)
            if not (np.all(np.isfinite(states)) and np.all(np.isfinite(moves))):
                raise ValueError("it holds NaN values")
            cloning = Cloning(np.ascontiguousarray(states), np.ascontiguousarray(moves))
            return CloningPolicyFile(**common, cloning=cloning)
        except (KeyError, TypeError, ValueError, AttributeError, LearningError) as err:
            raise PolicyFileError(
                f"{name} has a damaged header ({err}); export the policy again."
            ) from None
