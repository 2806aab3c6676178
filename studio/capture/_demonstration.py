"""Demonstrations as capture stores them: a recording segment's Puma560 trajectory and the grid
path the cutter gave, in a ``*.demo.json`` file next to its recording.

A segment ``[t0, t1]`` of a recording runs through the kinematics (reconstruct + fit the human
arm, retarget onto the Puma560) in :func:`track_segment`: a segment that is too short, drives the
robot into a joint limit, or fits the arm badly is refused with the reason. What a learning task
makes of the trajectory (the grid path to the goal, cut at its first visit) is computed by
:func:`studio.motion.extract_demonstration`, the cutter, through :mod:`studio.learning`; this
module stores it and reads it back.

File (``*.demo.json``, next to its recording), version 2: the trajectory and its own goal;
``grid_path`` is what learning's one path function gave when it was cut (for readers outside the
studio)::

    {"format": "teach-studio-demonstration", "version": 2, "robot": "puma560",
     "recording": "reach.tape.csv", "segment": [t0, t1], "mode": "joint",
     "grid": {"joints": 3, "bins": 11, "low_deg": -180, "high_deg": 180, "goal": [5, 6, 2]},
     "goal": [5, 6, 2], "grid_path": [state, ...], "reached_at": t,
     "fit": {"residual_max": m, "residual_mean": m},
     "trajectory": {"t": [...], "q_robot": [[6 angles], ...]}, "name": "...", "created": "..."}

:func:`load_demonstration` reads the file as it is: a file is refused with one sentence when it is
not a demonstration, a field is missing or of the wrong kind, or its joints are for another robot
or another number of joints. Whether its trajectory is usable by a task (NaN samples, a cut of
zero length) and the grid path a task replays (traced again from the trajectory) are learning's
to say: :func:`studio.motion.checked_demonstration` reads a file so, for every task. Version 1
files also stored ``mirror`` and ``fit.max_allowed``, which nothing read; they load as before.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import TypedDict, TypeVar, cast

import numpy as np

from studio import StudioError, read_json
from studio.kinematics import ArmTracker, Puma560, robot_spec

from ._errors import DemonstrationError
from ._fitters import TapeFitter, fit_frames, fitter_for
from ._observation_recording import ObservationRecording, read_any_recording
from ._recording_edit import DEMO_SUFFIX, atomic_write_text
from ._recording_format import RECORDING_SUFFIX, kind_of_name
from ._recording_reader import Recording

DEMO_FORMAT = "teach-studio-demonstration"
"""The ``format`` value of demonstration files."""
DEMO_VERSION = 2
"""The version this code writes and the newest it reads (2 adds ``robot``)."""
DEMO_ROBOT = Puma560.name
"""The robot a demonstration's ``q_robot`` is for: the one the capture chain
(:class:`studio.kinematics.ArmTracker`) mirrors the arm onto, whose path a recording's series holds
too. A motion on this robot uses that stored path; on any other it is retargeted."""
MAX_FIT_RESIDUAL_M = 0.03
"""Largest RMS landmark residual (m) of any frame's arm fit before a segment counts as a bad fit:
3 cm is well above the fit of a well-placed tape with sensor noise, and well below a misplaced
tape or a tape that is not on an arm."""
LIMIT_TOLERANCE_RAD = 1e-6
"""A retargeted joint this close to a Puma560 limit was clamped: the segment left the range."""
MIN_SEGMENT_FRAMES = 2
"""Fewest frames a segment needs."""
TRAJECTORY_DECIMALS = 6
"""Radians, seconds and metres are stored to a micro-unit: small files, far below the grid's
resolution and the fit's accuracy."""

T = TypeVar("T")


class GridSpec(TypedDict, total=False):
    """The grid a demonstration's path lives on, as ``ArmGrid.to_dict()`` writes it (a key left
    out takes ``ArmGrid``'s default)."""

    joints: int
    bins: int
    low_deg: float
    high_deg: float
    goal: list[int]


class DemonstrationSummary(TypedDict):
    """A demonstration's JSON-ready facts for listings (no trajectory)."""

    name: str
    recording: str
    segment: list[float]
    mode: str
    goal: list[int]
    steps: int
    grid_path: list[int]
    reached_at: float | None
    residual_max: float
    created: str


@dataclass(eq=False)
class Demonstration:
    """One demonstration.

    Attributes:
        recording: the recording's path.
        t0: segment start (s after the recording's first frame).
        t1: segment end (s after the first frame).
        times: the recording's times of the trajectory samples ``(N,)``.
        q_robot: the Puma560 joint trajectory ``(N, 6)`` (rad).
        grid_path: states of the grid, one action apart, ending at the goal.
        grid: the grid spec (``ArmGrid.to_dict()``), with the goal used.
        goal: the goal's bins.
        mode: retargeting mode (``"joint"`` or ``"cartesian"``).
        reached_at: time the path first reached the goal.
        residual_max: worst fit residual (m).
        residual_mean: mean fit residual (m).
        name: display name.
        created: ISO time of extraction.
    """

    recording: Path
    t0: float
    t1: float
    times: np.ndarray
    q_robot: np.ndarray
    grid_path: list[int]
    grid: GridSpec
    goal: tuple[int, ...]
    mode: str = "joint"
    reached_at: float | None = None
    residual_max: float = 0.0
    residual_mean: float = 0.0
    name: str = ""
    created: str = field(default_factory=lambda: datetime.now(UTC).isoformat(timespec="seconds"))

    def default_path(self) -> Path:
        """Where :meth:`save` writes by default: ``<recording stem>.<t0>-<t1>.demo.json``."""
        kind = kind_of_name(self.recording.name)
        stem = self.recording.name.removesuffix(kind.suffix if kind else RECORDING_SUFFIX)
        return self.recording.with_name(f"{stem}.{self.t0:.2f}-{self.t1:.2f}{DEMO_SUFFIX}")

    def to_dict(self) -> dict[str, object]:
        """The JSON file's contents."""
        return {
            "format": DEMO_FORMAT,
            "version": DEMO_VERSION,
            "robot": DEMO_ROBOT,
            "name": self.name,
            "created": self.created,
            "recording": self.recording.name,
            "segment": [self.t0, self.t1],
            "mode": self.mode,
            # the goal and the robot are stored once, at the top
            "grid": {k: v for k, v in self.grid.items() if k not in ("goal", "robot")},
            "goal": list(self.goal),
            "grid_path": list(self.grid_path),
            "reached_at": self.reached_at,
            "fit": {
                "residual_max": round(self.residual_max, TRAJECTORY_DECIMALS),
                "residual_mean": round(self.residual_mean, TRAJECTORY_DECIMALS),
            },
            "trajectory": {
                "t": np.round(self.times, TRAJECTORY_DECIMALS).tolist(),
                "q_robot": np.round(self.q_robot, TRAJECTORY_DECIMALS).tolist(),
            },
        }

    def summary(self) -> DemonstrationSummary:
        """JSON-ready facts for listings (no trajectory)."""
        return {
            "name": self.name,
            "recording": self.recording.name,
            "segment": [self.t0, self.t1],
            "mode": self.mode,
            "goal": list(self.goal),
            "steps": max(0, len(self.grid_path) - 1),
            "grid_path": list(self.grid_path),
            "reached_at": self.reached_at,
            "residual_max": self.residual_max,
            "created": self.created,
        }

    def save(self, path: str | os.PathLike[str] | None = None) -> Path:
        """Write the ``*.demo.json`` file (atomic replace); default :meth:`default_path`."""
        path = Path(path) if path is not None else self.default_path()
        return atomic_write_text(path, json.dumps(self.to_dict(), separators=(",", ":")) + "\n")


def load_demonstration(path: str | os.PathLike[str]) -> Demonstration:
    """Read a ``*.demo.json`` file.

    Raises:
        DemonstrationError: the file is missing, not a demonstration, or of an unknown version.
    """
    path = Path(path)
    try:
        data = read_json(path)  # bounded: size, nesting depth, regular files only
    except StudioError as err:
        raise DemonstrationError(str(err), "bad_file") from None
    if not isinstance(data, dict) or data.get("format") != DEMO_FORMAT:
        raise DemonstrationError(
            f"{path} is not a demonstration (no format '{DEMO_FORMAT}'); give a *.demo.json file.",
            "bad_file",
        )
    if not isinstance(data.get("version"), int) or not 1 <= data["version"] <= DEMO_VERSION:
        raise DemonstrationError(
            f"{path} has demonstration version {data.get('version')!r}; this studio reads 1 to {DEMO_VERSION}, update Teach Studio.",
            "bad_file",
        )
    robot = data.get("robot", DEMO_ROBOT)
    if robot != DEMO_ROBOT:
        raise DemonstrationError(
            f"{path} is a demonstration for the robot {robot!r}, not the {DEMO_ROBOT} the learning tasks use; cut it again from its recording.",
            "bad_file",
        )
    fit = data.get("fit", {})
    if not isinstance(fit, dict):
        raise DemonstrationError(
            f"{path}: fit is not a table of residuals; re-extract the demonstration.", "bad_file"
        )

    def read(key: str, what: str, convert: Callable[[object], T], value: object = None) -> T:
        """``convert`` of field ``key`` (or of ``value``, a part of it); numbers must be finite
        (the trajectory's samples are judged by learning, through
        :func:`studio.motion.checked_demonstration`)."""
        try:
            out = convert(data[key] if value is None else value)
            numeric = convert not in (_table, _text, _joint_rows) and key != "trajectory"
            finite = not numeric or np.isfinite(np.asarray(out, dtype=np.float64)).all()
        except (KeyError, IndexError, TypeError, ValueError, OverflowError):
            finite = None
        if not finite:
            problem = (
                "is missing or is not" if finite is None else "holds NaN or infinite values in"
            )
            raise DemonstrationError(
                f"{path}: {key} {problem} {what}; re-extract the demonstration.", "bad_file"
            )
        return out

    trajectory = read("trajectory", "a table of t and q_robot", _table)
    times = read("trajectory", "a list of times in seconds (t)", _floats, trajectory.get("t"))
    q_robot = read(
        "trajectory", "rows of robot joint angles (q_robot)", _joint_rows, trajectory.get("q_robot")
    )
    width = robot_spec(DEMO_ROBOT).arm_joints
    if len(q_robot) and q_robot.shape[1] != width:
        raise DemonstrationError(
            f"The demonstration {path} holds {q_robot.shape[1]} joint angles per sample, not the "
            f"{DEMO_ROBOT}'s {width}: it is for another robot; cut it again from its recording.",
            "bad_file",
        )
    reached_at = data.get("reached_at")
    try:
        demo = Demonstration(
            recording=path.with_name(read("recording", "a recording's file name", _text)),
            t0=float(read("segment", "two times in seconds", _floats)[0]),
            t1=float(read("segment", "two times in seconds", _floats)[1]),
            times=times,
            q_robot=q_robot,
            # as stored: a task traces it again from the trajectory (a path stored by older
            # code, or edited by hand, never replays)
            grid_path=read("grid_path", "a list of whole grid states", _whole_numbers),
            # the grid's values are checked by learning's grid when a task reads it
            grid=cast(GridSpec, read("grid", "a table of grid settings", _table)),
            goal=tuple(read("goal", "whole grid bins, one per joint", _whole_numbers)),
            mode=str(data.get("mode", "joint")),
            reached_at=None if reached_at is None else read("reached_at", "a time", _number),
            residual_max=read("fit", "residuals in metres", _number, fit.get("residual_max", 0)),
            residual_mean=read("fit", "residuals in metres", _number, fit.get("residual_mean", 0)),
            name=str(data.get("name", "")),
            created=str(data.get("created", "")),
        )
    except IndexError:  # a segment of fewer than two times
        raise DemonstrationError(
            f"{path}: segment is missing or is not two times in seconds; re-extract the demonstration.",
            "bad_file",
        ) from None
    return demo


def _table(value: object) -> dict[str, object]:
    if not isinstance(value, dict):
        raise TypeError("not a table")
    return dict(value)


def _number(value: object) -> float:
    if not isinstance(value, int | float | str):  # what float() reads of JSON values
        raise TypeError("not a number")
    return float(value)


def _floats(value: object) -> np.ndarray:
    if not isinstance(value, list) or any(isinstance(v, str | bool) for v in value):
        raise TypeError("not a list of numbers")
    return np.asarray(value, dtype=np.float64)


def _joint_rows(value: object) -> np.ndarray:
    """Rows of joint angles, all of one width (learning judges the samples)."""
    if not isinstance(value, list) or any(not isinstance(row, list) for row in value):
        raise TypeError("not a list of rows")
    rows = [_floats(row) for row in value]
    if len({len(row) for row in rows}) > 1:
        raise ValueError("rows of different widths")
    width = len(rows[0]) if rows else 6
    return np.asarray(rows, dtype=np.float64).reshape(len(rows), width)


def _whole_numbers(value: object) -> list[int]:
    numbers = _floats(value)
    if not np.isfinite(numbers).all() or (numbers != np.round(numbers)).any():
        raise ValueError("not whole numbers")
    return [int(v) for v in numbers]


def _text(value: object) -> str:
    if not isinstance(value, str):
        raise TypeError("not text")
    return value


@dataclass(frozen=True, eq=False)
class TrackedSegment:
    """A recording segment's Puma560 path: what :func:`track_segment` gives the cutter.

    Attributes:
        recording: the recording it was cut from.
        t0: segment start (s after the recording's first frame).
        t1: segment end (s after the first frame).
        times: the recording's times of the samples ``(N,)``.
        q_robot: the Puma560 joint path ``(N, 6)`` (rad), to the micro-unit a file stores.
        residual: each frame's fit residual ``(N,)`` (m).
        mode: retargeting mode (``"joint"`` or ``"cartesian"``).
    """

    recording: Recording | ObservationRecording
    t0: float
    t1: float
    times: np.ndarray
    q_robot: np.ndarray
    residual: np.ndarray
    mode: str

    def demonstration(
        self, grid_path: list[int], grid: dict[str, object], reached_at: float, name: str = ""
    ) -> Demonstration:
        """The demonstration of this segment, with the grid path the cutter traced on ``grid``
        (``ArmGrid.to_dict()``, its goal included) and when the path first reached the goal."""
        rec = self.recording
        return Demonstration(
            recording=rec.path,
            t0=float(self.t0),
            t1=float(self.t1),
            times=self.times.copy(),
            q_robot=self.q_robot,
            grid_path=list(grid_path),
            grid=cast(GridSpec, grid),
            goal=tuple(int(b) for b in cast(GridSpec, grid)["goal"]),
            mode=self.mode,
            reached_at=reached_at,
            residual_max=float(self.residual.max()),
            residual_mean=float(self.residual.mean()),
            name=name or f"{rec.name} {self.t0:.2f}-{self.t1:.2f} s",
        )


def track_segment(
    recording: Recording | ObservationRecording | str | os.PathLike[str],
    t0: float,
    t1: float,
    mode: str = "joint",
    *,
    max_residual: float = MAX_FIT_RESIDUAL_M,
    tracker: ArmTracker | None = None,
) -> TrackedSegment:
    """The Puma560 path of the segment ``[t0, t1]`` of a recording, checked for a demonstration.

    Args:
        recording: a recording of any kind (tape, pose landmarks, hand poses) or its path; each
            kind's observations go through their own fitter (:func:`fitter_for`) into the human
            arm, then the one retargeting.
        t0: segment start (s after the recording's first frame, as playback's ``seek``).
        t1: segment end (s after the first frame).
        mode: retargeting mode, ``"joint"`` or ``"cartesian"``.
        max_residual: worst allowed fit residual (m) of a tape recording (a camera's fit holds
            what it cannot see and a hand guide's arm stops at its nearest pose, so those are
            judged by where the robot goes).
        tracker: the :class:`studio.kinematics.ArmTracker` to track the frames with, for this
            recording's tape (default: a mirroring one for the recording's tape); it is reset
            and set to ``mode`` first.

    Raises:
        DemonstrationError: with ``reason`` ``too_short``, ``bad_fit`` or
            ``leaves_joint_range``, and one sentence saying what to change.
    """
    rec = (
        recording
        if isinstance(recording, Recording | ObservationRecording)
        else read_any_recording(recording)
    )
    rows = rec.segment(t0, t1)
    times = rec.t[rows]
    if times.shape[0] < MIN_SEGMENT_FRAMES:
        raise DemonstrationError(
            f"the segment [{t0:.2f}, {t1:.2f}] s of {rec.path.name} holds {times.shape[0]} frames; choose a longer segment inside 0-{rec.duration:.2f} s.",
            "too_short",
        )
    q_robot, residual = _track_segment(rec, rows, mode, tracker)
    worst = int(np.argmax(residual))
    if isinstance(rec, Recording) and not residual[worst] <= max_residual:
        raise DemonstrationError(
            f"the arm fits the tape badly at {times[worst]:.2f} s (residual {residual[worst] * 100:.1f} cm > {max_residual * 100:.1f} cm); check the tape config's shoulder and wrist regions or choose another segment.",
            "bad_fit",
        )
    _check_joint_range(q_robot, times)
    # the demonstration holds what its file holds, so a path traced again from the saved
    # trajectory (the page's run queue does) is the cutter's very path
    q_robot = np.round(q_robot, TRAJECTORY_DECIMALS)
    return TrackedSegment(rec, float(t0), float(t1), times, q_robot, residual, mode)


def _check_joint_range(q_robot: np.ndarray, times: np.ndarray) -> None:
    """Refuse a path that drives a Puma560 joint to its limit (retargeting clamped it there)."""
    robot = Puma560()
    at_limit = (q_robot <= robot.lower + LIMIT_TOLERANCE_RAD) | (
        q_robot >= robot.upper - LIMIT_TOLERANCE_RAD
    )
    if at_limit.any():
        i, j = np.argwhere(at_limit)[0]
        raise DemonstrationError(
            f"the motion drives Puma560 joint {j + 1} to its limit at {times[i]:.2f} s; choose a segment that stays inside the robot's range.",
            "leaves_joint_range",
        )


def _track_segment(
    rec: Recording | ObservationRecording, rows: slice, mode: str, tracker: ArmTracker | None
) -> tuple[np.ndarray, np.ndarray]:
    """The Puma560 path ``(N, 6)`` and fit residuals ``(N,)`` of a recording's rows, fitted as
    a recording's frames are (:func:`fit_frames`: smoothed with the past and the future)."""
    observations = [rec.frame_at(i) for i in range(*rows.indices(len(rec)))]
    q_robot = np.empty((len(observations), 6))
    residual = np.empty(len(observations))
    if not observations:
        return q_robot, residual
    fitter = fitter_for(observations[0], tape=getattr(rec, "config", None), side=rec.side)
    if isinstance(fitter, TapeFitter) and tracker is not None:
        if tracker.tape != fitter.tracker.tape:
            raise DemonstrationError(
                f"the tracker follows another tape than {rec.path.name}'s; pass a tracker built for the recording's tape config, or none.",
                "bad_fit",
            )
        tracker.reset()
        fitter.tracker = tracker
    fitter.mode = mode
    for i, fitted in enumerate(fit_frames(fitter, observations)):
        q_robot[i] = fitted.q_robot
        # the residual (tape against the fitted arm) is the fit's quality; ``success`` also
        # asks for millimetre landmark agreement, which sensor noise alone can exceed
        residual[i] = fitted.residual if np.isfinite(fitted.residual) else np.inf
    return q_robot, residual


def demonstrations_for(recording_path: str | os.PathLike[str]) -> list[Path]:
    """The ``*.demo.json`` files next to a recording that reference it."""
    recording_path = Path(recording_path)
    out = []
    for demo in sorted(recording_path.parent.glob("*" + DEMO_SUFFIX)):
        try:
            data = read_json(demo)
        except StudioError:
            continue
        if isinstance(data, dict) and data.get("recording") == recording_path.name:
            out.append(demo)
    return out
