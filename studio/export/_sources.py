"""What an export starts from: a policy file, a demonstration or a recording, found by path or
name, and turned into a :class:`Motion` of one robot's joints.

A recording and a demonstration are of the *human* arm, so they retarget onto any robot: their
frames go through the capture package's fitters (:func:`studio.capture.fitter_for`, the same fit
the page and the demonstration cutter use) into the human arm's angles, then through
:class:`studio.kinematics.Retargeter` onto the chosen robot (joint mode for the Puma560, the
paper's; cartesian, the hand's pose scaled into the robot's workspace, for any other arm). A
demonstration for the Puma560 keeps the trajectory stored in it. A policy drives the robot it
was learnt on only (its file names it; one written before policies named a robot is the
Puma560's).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Literal

import numpy as np

from studio._layout import POLICIES_DIR, RECORDINGS_DIR, RUNS_DIR
from studio.capture import (
    DEMO_SUFFIX,
    RECORDING_SUFFIXES,
    ObservationRecording,
    Recording,
    RecordingSeries,
    human_angles,
    load_demonstration,
    read_any_recording,
)
from studio.kinematics import (
    RetargetConfig,
    RetargetedPath,
    RobotArm,
    load_robot,
    retarget_path,
)
from studio.learning import POLICY_SUFFIX, DemonstrationPath, LearningError
from studio.learning import check_policy_robot as check_policy_robot_named
from studio.samples import SAMPLES_DIR

from ._errors import ExportError
from ._safety import Finding

SourceKind = Literal["policy", "demonstration", "recording"]
PUMA560 = "puma560"
"""The paper's robot: a demonstration keeps its stored trajectory for it, and joint mode maps the
human arm onto it."""


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

    def retimed(self, rate_hz: float) -> Motion:
        """This motion as a path that :func:`time_path` times within the robot's limits and
        samples at ``rate_hz``, rather than at its own times: a recording to send to a robot
        (at its capture times it starts mid-motion, and an arm moves faster than most robots
        may). Its retargeting findings and notes still name the source's frames."""
        return replace(self, timed=False, rate_hz=rate_hz)


def source_kind(path: Path) -> SourceKind:
    """What the file at ``path`` is, by its name's ending."""
    name = path.name
    if name.endswith(POLICY_SUFFIX) or name.endswith(".npz"):
        return "policy"
    if name.endswith(DEMO_SUFFIX):
        return "demonstration"
    if any(name.endswith(suffix) for suffix in RECORDING_SUFFIXES):
        return "recording"
    raise ExportError(
        f"{path} is neither a policy ({POLICY_SUFFIX}), a demonstration ({DEMO_SUFFIX}) nor a "
        f"recording ({', '.join(RECORDING_SUFFIXES)}); give one of those."
    )


def find_source(given: str | Path, data_dir: str | Path = ".") -> Path:
    """The file ``given`` names: a path, else a name in the data folder or among the samples.

    A name is looked for as a demonstration or a recording in ``<data_dir>/recordings/``, a
    policy in ``<data_dir>/policies/`` or a run ``<data_dir>/runs/<name>/``, then as a shipped
    sample (``sample-reach-1`` is the demonstration; ``sample-reach-1.tape.csv`` the recording).

    Raises:
        ExportError: nothing of that name.
    """
    given = Path(given)
    if given.exists() or len(given.parts) != 1:
        if not given.is_file():
            what = "is a folder, not a file" if given.is_dir() else "does not exist"
            raise ExportError(
                f"{given} {what}; give the path of a policy, demonstration or recording file."
            )
        return given
    root = Path(data_dir)
    endings = (DEMO_SUFFIX, *RECORDING_SUFFIXES)
    candidates = [root / RECORDINGS_DIR / given.name, SAMPLES_DIR / given.name]
    for folder in (root / RECORDINGS_DIR, SAMPLES_DIR):
        candidates += [folder / f"{given.name}{ending}" for ending in endings]
    candidates += [
        root / POLICIES_DIR / f"{given.name}{POLICY_SUFFIX}",
        root / RUNS_DIR / given.name / f"policy{POLICY_SUFFIX}",
    ]
    for candidate in candidates:
        if candidate.is_file() and candidate.name != "__init__.py":
            return candidate
    samples = sorted(p.name.removesuffix(DEMO_SUFFIX) for p in SAMPLES_DIR.glob(f"*{DEMO_SUFFIX}"))
    raise ExportError(
        f"There is no file {given}, nor a recording, demonstration, policy or run named "
        f"{given.name!r} in {root.resolve()} or among the samples ({', '.join(samples)}); check "
        "the name or give a path."
    )


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


def recording_motion(
    path: Path,
    robot_name: str,
    t0: float | None = None,
    t1: float | None = None,
    most_frames: int | None = None,
) -> Motion:
    """A recording (its ``[t0, t1]`` s, the whole by default) retargeted onto ``robot_name`` at
    its capture times, from 0.

    Args:
        most_frames: take every k-th frame when the segment holds more than this (a preview of
            a long take); the retargeting's step cap then grows k-fold, so the robot follows
            as it would frame by frame. None: every frame, as an export needs.
    """
    robot = load_robot(robot_name).scratch_copy()  # its own scratch data: any thread
    rec = read_any_recording(path)
    rows = rec.segment(0.0 if t0 is None else t0, rec.duration if t1 is None else t1)
    start, stop, _ = rows.indices(len(rec))
    if stop - start < 2:
        raise ExportError(
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
    return Motion(
        "recording", path.name, robot, times, found.q, True, rate, tuple(findings), notes, found
    )


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
    if robot.name == PUMA560 or not len(times):
        q = series.q_robot if robot.name == PUMA560 else np.zeros((0, robot.nq))
        return Motion("recording", name, robot, times, q, True, rate)
    gaps = np.diff(np.asarray(series.frames))
    stride = int(gaps.max()) if len(gaps) else 1
    found, findings, notes = retarget(robot, times, series.q_human, series.side, _strided(stride))
    return Motion(
        "recording", name, robot, times, found.q, True, rate, tuple(findings), notes, found
    )


def demonstration_motion(path: Path, robot_name: str, rate_hz: float) -> Motion:
    """A demonstration's path on ``robot_name`` (its stored Puma560 trajectory, or its
    recording's segment retargeted onto another robot), to be timed."""
    robot = load_robot(robot_name).scratch_copy()  # its own scratch data: any thread
    demo = load_demonstration(path)
    if robot.name == PUMA560:
        times = demo.times - demo.times[0]
        return Motion("demonstration", path.name, robot, times, demo.q_robot, False, rate_hz)
    recording = demo.recording  # the file name it was cut from, next to the demonstration
    if not recording.is_file():
        raise ExportError(
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
    """A demonstration file as a training run replays it on ``robot_name``: its stored Puma560
    trajectory, or for another robot its recording's segment retargeted onto that robot (the
    path :func:`demonstration_motion` exports), with its sample times.

    Args:
        path: the ``*.demo.json`` file.
        robot_name: the robot the run trains.
        label: how messages name it (``Demonstration 'reach-1'``).
        name: the name the page lists it by, or "".

    Raises:
        ExportError: an unknown robot, or the recording it was cut from is missing.
    """
    if robot_name == PUMA560:
        demo = load_demonstration(path)
        return DemonstrationPath(label, demo.q_robot, name, demo.times)
    times, q = _retargeted(path, path.stat().st_mtime_ns, robot_name)
    return DemonstrationPath(label, q, name, times, robot_name)


@functools.lru_cache(maxsize=32)
def _retargeted(path: Path, mtime_ns: int, robot_name: str) -> tuple[np.ndarray, np.ndarray]:
    """``(times, q)`` of a demonstration retargeted onto ``robot_name``, kept while the file is
    unchanged (``mtime_ns``): a run form checked as it is filled in asks again and again."""
    motion = demonstration_motion(path, robot_name, 1.0)
    return motion.times, motion.q


def check_policy_robot(path: Path, policy_robot: str | None, robot_name: str) -> RobotArm:
    """The robot a policy file drives, or an ExportError when another one is asked for.

    Args:
        path: the policy file (for the sentence).
        policy_robot: the robot its file names (None: not an arm's policy, refused when rolled
            out).
        robot_name: the robot asked for.
    """
    robot = load_robot(robot_name).scratch_copy()  # its own scratch data: any thread
    if policy_robot is not None:
        try:
            check_policy_robot_named(
                policy_robot,
                robot.name,
                f"The policy {path.name}",
                f"export it with --robot {policy_robot}, or export a recording or demonstration "
                f"for the {robot.spec.title}",
            )
        except LearningError as err:
            raise ExportError(str(err)) from None
    return robot
