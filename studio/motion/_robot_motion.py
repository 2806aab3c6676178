"""A recorded arm motion on a robot: a recording, a recording's timeline or a demonstration
retargeted onto any robot, as one :class:`Motion` of that robot's joints.

A recording and a demonstration are of the *human* arm, so they retarget onto any robot: their
frames go through the capture package's fitters (:func:`studio.capture.human_angles`, the same fit
the page and the demonstration cutter use) into the human arm's angles, then through
:func:`studio.kinematics.retarget_path` onto the chosen robot, with its IK branches planned over
the whole motion. A demonstration for the Puma560 keeps the trajectory stored in it. What a
retargeting met on the way (a target out of reach) is a :class:`Finding`, as an export's safety
checks' are.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from datetime import datetime
from pathlib import Path
from typing import Literal

import numpy as np

from studio.capture import (
    DEMO_ROBOT,
    ObservationRecording,
    Recording,
    RecordingSeries,
    human_angles,
    read_any_recording,
)
from studio.kinematics import (
    KinematicsError,
    Obstacle,
    RetargetConfig,
    RetargetedPath,
    RobotArm,
    load_robot,
    retarget_path,
)
from studio.learning import DemonstrationPath

from ._demonstrations import checked_demonstration
from ._errors import MotionError

SourceKind = Literal["policy", "demonstration", "recording"]


@dataclass(frozen=True)
class Finding:
    """One problem at one sample of a robot's motion (a target out of reach when retargeting,
    a limit or a collision in an export's safety checks).

    Attributes:
        sample: the sample's index (0-based row of the file).
        time: its time (s).
        what: ``"position"``, ``"velocity"``, ``"acceleration"``, ``"collision"`` or ``"reach"``.
        where: the joint's name, or the link pair ``"a/b"``.
        sentence: the problem in words, with the margin.
    """

    sample: int
    time: float
    what: str
    where: str
    sentence: str


@dataclass(frozen=True)
class Motion:
    """One robot's joint motion, ready to be timed, checked and written.

    Attributes:
        kind: what it came from (policy, demonstration or recording).
        name: the source's name, for messages and file metadata.
        robot: the arm it is for.
        times: sample times (s, from 0).
        q: joint angles (rad), one row per sample, in ``robot.joint_names`` order.
        timed: whether ``times`` are final (a recording's capture times, a policy's fixed pace);
            otherwise ``q`` is a path that :func:`time_path` times.
        rate_hz: the capture rate (recordings) or the wanted sample rate.
        findings: problems met while retargeting (targets out of reach).
        notes: what the retargeting did that is no problem but the file should say (the hand
            went beyond the robot's reach and its target was drawn back into it).
        path: the retargeting's account of each sample (whether the tool reached the hand's
            target, how far it was drawn back; :class:`studio.kinematics.RetargetedPath`), for a
            motion retargeted from a human arm; None for a stored or rolled-out joint path.
        started: when the first sample happened, seconds since the Unix epoch (a recording's
            capture); None: the export's own time stamps the file.
        obstacles: boxes in the robot's base frame the motion must not touch (a policy's task's),
            checked along the motion before it is written.
    """

    kind: SourceKind
    name: str
    robot: RobotArm
    times: np.ndarray
    q: np.ndarray
    timed: bool
    rate_hz: float
    findings: tuple[Finding, ...] = field(default=())
    notes: tuple[str, ...] = field(default=())
    path: RetargetedPath | None = None
    started: float | None = None
    obstacles: tuple[Obstacle, ...] = field(default=())

    def retimed(self, rate_hz: float) -> Motion:
        """This motion as a path that :func:`time_path` times within the robot's limits and
        samples at ``rate_hz``, rather than at its own times: a recording to send to a robot
        (at its capture times it starts mid-motion, and an arm moves faster than most robots
        may). Its retargeting findings and notes still name the source's frames."""
        return replace(self, timed=False, rate_hz=rate_hz)


def retarget(
    robot: RobotArm,
    times: np.ndarray,
    q_human: np.ndarray,
    side: str,
    config: RetargetConfig | None = None,
) -> tuple[RetargetedPath, list[Finding], tuple[str, ...]]:
    """The robot's path for the ``side`` arm's angles (N, 7)
    (:func:`studio.kinematics.retarget_path`), the first frame out of reach as a finding, and
    notes where the motion is the robot's own and safe but not the hand's: where the hand went
    beyond the robot's reach (its target drawn back into it, as the page says live), and where
    its tool is off the hand's target though within reach (turning from one IK branch to
    another, or at the end of its wrist's turn)."""
    config = config or RetargetConfig()
    path = retarget_path(robot, q_human, config, side=side)
    tolerance = config.reach_tolerance
    title = robot.spec.title
    cases = (
        (
            path.pulled_in > tolerance,
            f"the hand went beyond the {title}'s reach",
            f"at most {path.pulled_in.max() * 100:.1f} cm",
            "there the robot follows the hand's target drawn back into its reach",
        ),
        (
            ~path.reached & ~path.out_of_reach,
            f"the {title}'s tool is more than {tolerance * 100:.0f} cm or "
            f"{math.degrees(config.reach_angle):.0f} deg off the hand's target",
            None,
            "there it turns from one of its IK branches to another (an elbow or wrist turned "
            f"over, no joint faster than {math.degrees(config.max_joint_step):.1f} deg a "
            "frame), or cannot turn its tool as far as the hand turned",
        ),
    )
    notes: tuple[str, ...] = ()
    for flags, what, extent, why in cases:
        frames = np.flatnonzero(flags)
        if len(frames):
            i = int(frames[0])
            first = f"first at frame {i}, t = {times[i]:.3f} s" + (f"; {extent}" if extent else "")
            notes += (f"{what} in {len(frames)} of {len(times)} frames ({first}): {why}",)
    findings: list[Finding] = []
    for i in np.flatnonzero(path.out_of_reach)[:1]:
        findings.append(
            Finding(
                int(i),
                float(times[i]),
                "reach",
                robot.spec.tool,
                f"frame {i} (t = {times[i]:.3f} s of the source): the hand's target is "
                f"{path.position_error[i] * 100:.1f} cm out of the {robot.spec.title}'s reach "
                f"(tolerance {tolerance * 100:.0f} cm)",
            )
        )
    return path, findings, notes


def _capture_rate(rec: Recording | ObservationRecording, times: np.ndarray) -> float:
    if rec.rate_hz > 0:
        return rec.rate_hz
    return float(1.0 / np.median(np.diff(times))) if len(times) > 1 else 1.0


def _motion_robot(robot_name: str, limit_margin: float | None = None) -> RobotArm:
    """The robot ``robot_name`` a motion is retargeted onto, timed and checked for, with scratch
    data of its own (any thread), planning ``limit_margin`` (rad) from each hard limit (None:
    :data:`studio.kinematics.LIMIT_MARGIN_RAD`).

    Raises:
        MotionError: a margin that is not a finite number of radians, 0 or more.
    """
    robot = load_robot(robot_name)
    if limit_margin is None:
        return robot.scratch_copy()
    try:
        return robot.with_limit_margin(limit_margin)
    except KinematicsError as err:
        raise MotionError(str(err)) from None


def recording_motion(
    path: Path,
    robot_name: str,
    t0: float | None = None,
    t1: float | None = None,
    most_frames: int | None = None,
    limit_margin: float | None = None,
) -> Motion:
    """A recording (its ``[t0, t1]`` s, the whole by default) retargeted onto ``robot_name`` at
    its capture times, from 0.

    Args:
        most_frames: take every k-th frame when the segment holds more than this (a preview of
            a long take); the retargeting's step cap then grows k-fold, so the robot follows
            as it would frame by frame. None: every frame, as an export needs.
        limit_margin: how far (rad) the retargeting keeps every joint from its hard limit
            (None: :data:`studio.kinematics.LIMIT_MARGIN_RAD`); the motion's robot keeps it,
            so its timing and checks do too.
    """
    robot = _motion_robot(robot_name, limit_margin)
    rec = read_any_recording(path)
    rows = rec.segment(0.0 if t0 is None else t0, rec.duration if t1 is None else t1)
    start, stop, _ = rows.indices(len(rec))
    if stop - start < 2:
        raise MotionError(
            f"The recording {path.name} holds {max(stop - start, 0)} frame there; choose a "
            "longer stretch, or record a motion."
        )
    stride = 1 if most_frames is None else max(1, -(-(stop - start) // max(int(most_frames), 2)))
    rows = slice(start, stop, stride)
    times = np.asarray(rec.t[rows] - rec.t[start], dtype=float)
    found, findings, notes = retarget(
        robot, times, human_angles(rec, rows), rec.side, _strided(stride)
    )
    rate = _capture_rate(rec, times) / stride
    started = _captured_at(rec.meta.get("created", ""), float(rec.t[start] - rec.t[0]))
    return Motion(
        "recording",
        path.name,
        robot,
        times,
        found.q,
        True,
        rate,
        tuple(findings),
        notes,
        found,
        started,
    )


def _captured_at(created: str, offset: float) -> float | None:
    """The Unix time of a recording's frame ``offset`` seconds after its first, from the header's
    ISO 8601 ``created`` stamp (None: no readable stamp)."""
    try:
        return datetime.fromisoformat(created).timestamp() + offset
    except (TypeError, ValueError):
        return None


def _strided(stride: int) -> RetargetConfig | None:
    """The retargeting of every ``stride``-th frame: each step may move ``stride`` frames' worth
    (None: every frame, the default config)."""
    if stride <= 1:
        return None
    default = RetargetConfig()
    return replace(default, max_joint_step=default.max_joint_step * stride)


def series_motion(series: RecordingSeries, robot_name: str, name: str = "") -> Motion:
    """A recording's timeline on ``robot_name``: the human arm's angles of
    :func:`studio.capture.recording_series` retargeted onto it as :func:`recording_motion`
    retargets a recording (the step cap grown by the frames between two samples); the Puma560's
    are the series' own ``q_robot``, as a demonstration keeps them.

    Args:
        series: the recording's series (its ``frames`` say how far apart its samples are).
        robot_name: the robot to show it on.
        name: the recording's name, for messages.
    """
    robot = load_robot(robot_name).scratch_copy()  # its own scratch data: any thread
    times = np.asarray(series.times, dtype=float)
    rate = float(1.0 / np.median(np.diff(times))) if len(times) > 1 else 1.0
    if robot.name == DEMO_ROBOT or not len(times):  # the series' own path is this robot's
        q = series.q_robot if robot.name == DEMO_ROBOT else np.zeros((0, robot.nq))
        return Motion("recording", name, robot, times, q, True, rate)
    gaps = np.diff(np.asarray(series.frames))
    stride = int(gaps.max()) if len(gaps) else 1
    found, findings, notes = retarget(robot, times, series.q_human, series.side, _strided(stride))
    return Motion(
        "recording", name, robot, times, found.q, True, rate, tuple(findings), notes, found
    )


def demonstration_motion(
    path: Path, robot_name: str, rate_hz: float, limit_margin: float | None = None
) -> Motion:
    """A demonstration's path on ``robot_name`` (its stored Puma560 trajectory, or its
    recording's segment retargeted onto another robot, keeping ``limit_margin`` as
    :func:`recording_motion` does), to be timed."""
    robot = _motion_robot(robot_name, limit_margin)
    demo = checked_demonstration(path)
    if robot.name == DEMO_ROBOT:  # the path the file stores is this robot's
        times = demo.times - demo.times[0]
        return Motion("demonstration", path.name, robot, times, demo.q_robot, False, rate_hz)
    recording = demo.recording  # the file name it was cut from, next to the demonstration
    if not recording.is_file():
        raise MotionError(
            f"The demonstration {path.name} was cut from {recording.name}, which is not next to "
            f"it; a demonstration retargets to the {robot.spec.title} from its recording: put "
            "the recording back, or export the recording itself."
        )
    rec = read_any_recording(recording)
    rows = rec.segment(demo.t0, demo.t1)
    times = np.asarray(rec.t[rows] - rec.t[rows][0], dtype=float)
    found, findings, notes = retarget(robot, times, human_angles(rec, rows), rec.side)
    return Motion(
        "demonstration",
        path.name,
        robot,
        times,
        found.q,
        False,
        rate_hz,
        tuple(findings),
        notes,
        found,
    )


def training_demonstration(
    path: Path, robot_name: str, label: str, name: str = ""
) -> DemonstrationPath:
    """A demonstration file as a training run replays it on ``robot_name``: the one way from a
    demonstration to learning. Its stored Puma560 trajectory (read as every task reads it,
    :func:`checked_demonstration`), or for another robot its recording's segment retargeted onto
    that robot (the path :func:`demonstration_motion` exports), with its sample times.

    Args:
        path: the ``*.demo.json`` file.
        robot_name: the robot the run trains.
        label: how messages name it (``Demonstration 'reach-1'``).
        name: the name the page lists it by, or "".

    Raises:
        MotionError: the recording it was cut from is missing (another robot than the Puma560).
        DemonstrationError: the file is not a usable demonstration.
        KinematicsError: an unknown robot.
    """
    if robot_name == DEMO_ROBOT:  # the path the file stores is this robot's
        demo = checked_demonstration(path)
        return DemonstrationPath(label, demo.q_robot, name, demo.times)
    times, q = _retargeted(path, path.stat().st_mtime_ns, robot_name)
    return DemonstrationPath(label, q, name, times, robot_name)


@functools.lru_cache(maxsize=32)
def _retargeted(path: Path, mtime_ns: int, robot_name: str) -> tuple[np.ndarray, np.ndarray]:
    """``(times, q)`` of a demonstration retargeted onto ``robot_name``, kept while the file is
    unchanged (``mtime_ns``): a run form checked as it is filled in asks again and again."""
    motion = demonstration_motion(path, robot_name, 1.0)
    return motion.times, motion.q
