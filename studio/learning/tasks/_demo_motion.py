"""One demonstration contract for learning: a demonstration's motion, and what each task makes of it.

A demonstration file (``studio.capture``) holds its trajectory (sample times and Puma560 joints)
and its own goal. Learning alone turns that trajectory into what a task needs:

- the arm grid: a grid state path, cut at the run's goal (:func:`demonstration_grid_path`);
- the continuous task: its joint path from its start (the run record keeps it);
- the likeness card: the motion itself, times included (:class:`DemonstrationMotion`, kept in a
  run's ``config.json`` so ``likeness.json`` is written without the demonstration files).

Every check that can refuse a demonstration lives here (:func:`motion_problem`), so the page, the
run queue, ``studio train`` and ``studio export`` refuse the same input with the same sentence.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._errors import LearningError
from ._arm import ArmGrid
from ._reach import MAX_CHAIN

MOTION_DECIMALS = 6
"""Seconds and radians are kept to a micro-unit, as the demonstration files store them."""


def motion_problem(label: str, times: object, q_robot: object) -> str | None:
    """The one sentence refusing a demonstration's motion, or None when it is usable.

    Refused: not one row of joint angles per sample (up to the seven of the largest arm), NaN or
    infinite samples, a cut of zero length (fewer than two samples, or no time between its ends),
    and times that do not increase.
    """
    q = np.asarray(q_robot, dtype=np.float64)
    t = np.asarray(times, dtype=np.float64).reshape(-1)
    if q.ndim != 2 or not 1 <= q.shape[1] <= MAX_CHAIN:
        width = q.shape[1] if q.ndim == 2 else "no"
        return f"{label} holds {width} joint angles per sample, not one row of a robot's joints; cut it again from its recording."
    if q.shape[0] < 2 or t.shape[0] != q.shape[0] or (t.size and t[-1] - t[0] <= 0):
        return f"{label} is a cut of zero length ({q.shape[0]} samples); cut a longer segment of its recording."
    bad = ~np.isfinite(q).all(axis=1) | ~np.isfinite(t)
    if bad.any():
        i = int(np.argmax(bad))
        return f"{label} holds NaN or infinite samples (sample {i + 1} of {q.shape[0]}); cut it again from its recording."
    if np.any(np.diff(t) <= 0):
        return f"{label} has times that do not increase; cut it again from its recording."
    return None


@dataclass(frozen=True, eq=False)
class DemonstrationMotion:
    """A demonstration's motion as learning keeps it: its name, sample times and joints.

    Attributes:
        name: the name the page lists it by (or its file's name).
        times: sample times ``(N,)`` (s).
        q_robot: the run's robot's joints ``(N, nq)`` (rad; the Puma560's six by default).
    """

    name: str
    times: np.ndarray
    q_robot: np.ndarray

    @classmethod
    def checked(
        cls, name: str, times: object, q_robot: object, label: str = ""
    ) -> DemonstrationMotion:
        """A motion, refused with :func:`motion_problem`'s sentence (a :class:`LearningError`)."""
        problem = motion_problem(label or f"Demonstration {name!r}", times, q_robot)
        if problem is not None:
            raise LearningError(problem)
        return cls(
            name,
            np.asarray(times, dtype=np.float64).reshape(-1),
            np.asarray(q_robot, dtype=np.float64),
        )

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: ``{"name", "t", "q_robot"}``."""
        return {
            "name": self.name,
            "t": np.round(self.times, MOTION_DECIMALS).tolist(),
            "q_robot": np.round(self.q_robot, MOTION_DECIMALS).tolist(),
        }

    @classmethod
    def from_dict(cls, data: object) -> DemonstrationMotion:
        """The motion :meth:`to_dict` wrote (a :class:`LearningError` for anything else)."""
        if not isinstance(data, dict):
            raise LearningError("A stored demonstration motion is not a table; delete the run.")
        try:
            return cls.checked(str(data.get("name", "")), data["t"], data["q_robot"])
        except (KeyError, TypeError, ValueError):
            raise LearningError(
                "A stored demonstration motion lacks its times or joints; delete the run."
            ) from None


def demonstration_grid_path(label: str, q_robot: np.ndarray, grid: ArmGrid) -> list[int]:
    """The grid state path a demonstration replays on ``grid``: :meth:`ArmGrid.path_from_joints`
    cut at the grid's goal.

    Raises:
        LearningError: one sentence when the motion never reaches the grid's goal bins (naming
            where it ends and the fix), or is unusable (:func:`motion_problem`).
    """
    q = np.asarray(q_robot, dtype=np.float64)
    try:
        path = grid.path_from_joints(q, stop_at_goal=True)
    except LearningError as err:
        raise LearningError(f"{label} has no usable trajectory: {err}") from None
    if path[-1] != grid.goal_state:
        end = np.degrees(q[-1, :3])
        raise LearningError(
            f"{label} ends at joints ({end[0]:.0f}, {end[1]:.0f}, {end[2]:.0f}) degrees, not in the goal bin (not in this run's goal bins {tuple(grid.goal)}); choose demonstrations that reach this run's goal or set the goal where they end."
        )
    return list(path)
