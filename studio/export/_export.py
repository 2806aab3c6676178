"""One export: time a motion (unless its times are final), check it, then write it.

The checks run on the very samples that are written and before a byte is written; a refusal is
a :class:`SafetyError` and leaves any earlier file at ``out`` untouched. ``unchecked=True`` writes
anyway, with every finding stated in the file (CSV comment lines, the MCAP ``teach_studio``
metadata, ``info.json``'s ``teach_studio`` key). A motion's notes (the hand went beyond the
robot's reach while retargeting) are stated in every file, checked or not, and a CSV's comment
lines always name the robot, the joint order, the units and the source.

``simulate=True`` (what ``studio export`` asks) also replays the written samples in MuJoCo
(:func:`~._simulate.simulate_trajectory`) and states the report in the file: the CSV's comment
lines, the MCAP metadata's ``physics`` and ``physics_json``, and
``info.json``'s ``teach_studio.physics``. The report never refuses an export; a model MuJoCo
cannot build is stated as not simulated.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from studio._files import now_iso
from studio.motion import Finding, Motion
from studio.physics import PhysicsError, SimulationReport

from ._choices import LIMIT_FRACTION, Format
from ._errors import ExportError
from ._formats import write_csv, write_mcap
from ._lerobot import lerobot_conventions, write_lerobot
from ._safety import COLLISION_MARGIN_M, check_trajectory, limit_findings, refuse, timing_findings
from ._simulate import simulate_trajectory
from ._tf import link_transforms
from ._timing import PacedPath, Slowdown, pace_path, time_path

TASKS = {
    "demonstration": "Reach the goal the way the person showed it.",
    "recording": "Move the arm the way the person moved theirs.",
    "policy": "Reach the goal.",
}
"""A LeRobot episode's task text by what the motion came from, as a person would write it."""


@dataclass(frozen=True)
class Exported:
    """What an export wrote.

    Attributes:
        path: the file or folder.
        times: the samples' times (s).
        q: the samples' joints (rad).
        findings: the safety findings (empty when checked and passed).
        timed_by: ``"pace"`` (the source's pace, slower only where the limits need it),
            ``"toppra"`` (as fast as the limits allow) or ``"source"`` (the source's own times).
        physics: the samples replayed in MuJoCo (None: not simulated).
        slowdowns: where a timing at the source's pace runs slower than the source did.
    """

    path: Path
    times: np.ndarray
    q: np.ndarray
    findings: tuple[Finding, ...]
    timed_by: str
    physics: SimulationReport | None = None
    slowdowns: tuple[Slowdown, ...] = ()


@dataclass(frozen=True)
class _Samples:
    """The samples an export writes, how they were timed, and what the timing did."""

    times: np.ndarray
    q: np.ndarray
    timed_by: str
    paced: PacedPath | None = None


def _samples(motion: Motion, fraction: float, fastest: bool = False) -> _Samples:
    """The samples an export writes: the motion's own; or its path at the person's pace where
    the limits allow (a demonstration, a retimed recording); or as fast as they allow."""
    if motion.timed:
        return _Samples(motion.times, motion.q, "source")
    if fastest or not _has_pace(motion):
        times, q = time_path(motion.robot, motion.q, motion.rate_hz, fraction=fraction)
        return _Samples(times, q, "toppra")
    paced = pace_path(motion.robot, motion.times, motion.q, motion.rate_hz, fraction=fraction)
    return _Samples(paced.times, paced.q, "pace", paced)


def _has_pace(motion: Motion) -> bool:
    """Whether the motion's times are a person's own pace, sample by sample (a demonstration's
    or a recording's; a policy's rollout has no pace of its own to keep)."""
    times = np.asarray(motion.times, dtype=float)
    return (
        motion.kind != "policy"
        and times.shape == (len(motion.q),)
        and len(times) > 1
        and bool((np.diff(times) > 0).all())
    )


def _pace_note(paced: PacedPath) -> str:
    """What a timing at the source's pace did, in one note: the durations and each stretch it
    had to slow down."""
    took = f"at the source's pace: {paced.source_seconds:.2f} s, run in {paced.times[-1]:.2f} s"
    if not paced.slowdowns:
        return f"{took}, from rest to rest"
    return f"{took}, from rest to rest; " + "; ".join(s.sentence for s in paced.slowdowns)


def fit_timing(motion: Motion, rate_hz: float) -> tuple[Motion, tuple[Finding, ...]]:
    """The motion as a person means it exported: at its own times when they keep the robot's
    velocity and acceleration limits, else its path at the person's pace, slowed only where the
    limits need it (:meth:`Motion.retimed` at ``rate_hz``, which :func:`export_motion` times).

    A motion whose times are not final (a demonstration, a path) is returned as it is.

    Returns:
        ``(motion to export, the findings that made it slower)``: the velocity and
        acceleration findings of its own times (empty when it kept them).
    """
    if not motion.timed or len(motion.times) < 2:
        return motion, ()
    too_fast = timing_findings(limit_findings(motion.robot, motion.times, motion.q))
    if not too_fast:
        return motion, ()
    return motion.retimed(rate_hz), tuple(too_fast)


def simulate_motion(
    motion: Motion,
    *,
    fraction: float = LIMIT_FRACTION,
    cache: Path | None = None,
    fastest: bool = False,
) -> SimulationReport:
    """The samples :func:`export_motion` would write for ``motion``, replayed in MuJoCo: the
    report ``studio export`` states in the file, before anything is exported.

    Raises:
        PhysicsError: MuJoCo cannot build the robot's model.
        ExportError: the robot's MuJoCo files cannot be written in ``cache``.
    """
    samples = _samples(motion, fraction, fastest)
    return simulate_trajectory(motion.robot, samples.times, samples.q, cache=cache)


def _physics(
    motion: Motion, times: np.ndarray, q: np.ndarray, cache: Path | None
) -> tuple[SimulationReport | None, list[str]]:
    """The samples replayed in MuJoCo, and the report's lines for the file."""
    try:
        report = simulate_trajectory(
            motion.robot, times, q, cache=cache, obstacles=motion.obstacles
        )
    except (PhysicsError, ExportError) as err:
        return None, [f"physics: not simulated ({err})"]
    return report, report.sentences()


def _notes(motion: Motion, findings: list[Finding], checked: bool) -> list[str]:
    robot = motion.robot
    head = (
        f"Teach Studio export of {motion.kind} {motion.name} for the {robot.spec.title} "
        f"({robot.name}), {now_iso()}"
    )
    notes = [
        f"robot: {robot.name}; joints in order: {', '.join(robot.joint_names)}",
        "units: time in seconds from the first sample, joint angles in radians",
        f"source: the {motion.kind} {motion.name}",
        *(f"note: {note}" for note in motion.notes),
    ]
    if not findings:
        return [head, *notes, "safety checks: passed (joint positions, velocities, "
                f"accelerations, self-collision margin {COLLISION_MARGIN_M * 100:.1f} cm)"]  # fmt: skip
    state = "NOT checked (--unchecked)" if not checked else "failed"
    return [head, *notes, f"safety checks: {state}; {len(findings)} finding(s):"] + [
        f.sentence for f in findings
    ]


def export_motion(
    motion: Motion,
    fmt: Format,
    out: Path,
    *,
    unchecked: bool = False,
    fraction: float = LIMIT_FRACTION,
    task: str = "",
    simulate: bool = False,
    cache: Path | None = None,
    fastest: bool = False,
) -> Exported:
    """Time, check and write ``motion`` as ``fmt`` at ``out``.

    Args:
        motion: the robot's motion (:func:`recording_motion`, :func:`demonstration_motion`, or a
            policy rollout).
        fmt: ``"csv"``, ``"mcap"`` or ``"lerobot"``.
        out: the file (a folder for ``lerobot``).
        unchecked: write even when the checks find problems, stating them in the file.
        fraction: the share of the limits the timing may use.
        task: the LeRobot task text (default: a sentence for the source's kind, :data:`TASKS`).
        simulate: replay the samples in MuJoCo and state the report in the file.
        cache: where the robot's MuJoCo files are kept (None: a temporary folder).
        fastest: time a path as fast as the limits allow, not at its source's pace.

    Raises:
        SafetyError: the checks found problems (nothing written).
        ExportError: the file cannot be written.
    """
    robot = motion.robot
    samples = _samples(motion, fraction, fastest)
    times, q, timed_by = samples.times, samples.q, samples.timed_by
    if samples.paced is not None:
        motion = replace(motion, notes=(*motion.notes, _pace_note(samples.paced)))
    # a recording at its capture times is what the arm did (joint states); timed, a trajectory
    as_captured = motion.kind == "recording" and timed_by == "source"
    findings = check_trajectory(
        robot, times, q, extra=list(motion.findings), obstacles=motion.obstacles
    )
    if not unchecked:
        refuse(findings, f"{motion.kind} {motion.name}", robot, own_times=as_captured)
    notes = _notes(motion, findings, checked=not unchecked)
    report, physics = _physics(motion, times, q, cache) if simulate else (None, [])
    written = _Written(motion, times, q, timed_by, findings, report, physics if simulate else None)
    if fmt == "csv":
        write_csv(out, robot.joint_names, times, q, [*notes, *physics])
    elif fmt == "mcap":
        _mcap(written, out, as_captured)
    else:
        _lerobot(written, out, task or TASKS[motion.kind])
    slowdowns = samples.paced.slowdowns if samples.paced is not None else ()
    return Exported(out, times, q, tuple(findings), timed_by, report, slowdowns)


@dataclass(frozen=True)
class _Written:
    """What an export writes into a file beside the samples: its source, timing, checks and
    physics (``physics`` None: not simulated)."""

    motion: Motion
    times: np.ndarray
    q: np.ndarray
    timed_by: str
    findings: list[Finding]
    report: SimulationReport | None
    physics: list[str] | None


def _mcap(written: _Written, out: Path, as_captured: bool) -> None:
    motion, findings, report = written.motion, written.findings, written.report
    robot = motion.robot
    metadata = {
        "source": motion.name,
        "kind": motion.kind,
        "robot": robot.name,
        "timed_by": written.timed_by,
        "checked": "passed" if not findings else "no (--unchecked)",
        "findings": "\n".join(f.sentence for f in findings),
        "notes": "\n".join(motion.notes),
    }
    if written.physics is not None:
        metadata["physics"] = "\n".join(written.physics)
        metadata["physics_json"] = json.dumps(report.as_json() if report else None)
    write_mcap(
        out,
        robot.joint_names,
        written.times,
        written.q,
        states=as_captured,
        metadata=metadata,
        start_ns=int(round((motion.started or time.time()) * 1e9)),
        urdf=robot.urdf_text,
        links=link_transforms(robot.model, written.q),
    )


def _lerobot(written: _Written, out: Path, task: str) -> None:
    motion, findings, report = written.motion, written.findings, written.report
    robot = motion.robot
    layout = lerobot_conventions(robot.name, robot.joint_names, robot.lower, robot.upper)
    about: dict[str, object] = {
        "source": motion.name,
        "kind": motion.kind,
        "robot": robot.name,
        "units": dict(zip(layout.names, layout.units, strict=True)),
        "timed_by": written.timed_by,
        "checked": not findings,
        "findings": [f.sentence for f in findings],
        "notes": list(motion.notes),
    }
    if written.physics is not None:
        about["physics"] = {
            "report": report.as_json() if report else None,
            "sentences": written.physics,
        }
    write_lerobot(
        out,
        layout.names,
        written.times,
        layout.values(written.q),
        fps=int(round(motion.rate_hz)),
        robot_type=layout.robot_type,
        task=task,
        extra={"teach_studio": about},
    )
