"""A recording or a demonstration downloaded from the page as the chosen robot's trajectory, and
a policy's watched rollout as its robot's, through :mod:`studio.export` (the same retargeting,
timing, safety checks and formats as ``studio export``)."""

from __future__ import annotations

import errno
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Literal, get_args

import numpy as np

from studio.capture import DEMO_SUFFIX, RECORDING_SUFFIXES
from studio.export import (
    FORMAT_SUFFIXES,
    FORMATS,
    Exported,
    ExportError,
    check_policy_robot,
    export_motion,
    fit_timing,
    simulate_motion,
)
from studio.kinematics import Obstacle
from studio.learning import ROLLOUT_RATE_HZ
from studio.motion import Finding, Motion, demonstration_motion, recording_motion
from studio.physics import SimulationReport

from .._errors import STORAGE_PROBLEMS, StorageError, findings_public

ExportFormat = Literal["csv", "mcap", "lerobot"]
"""The formats of :data:`studio.export.FORMATS`, as the API's query parameter."""
assert get_args(ExportFormat) == FORMATS, "the API's formats are studio.export's"

MEDIA_TYPES = {
    "csv": "text/csv",
    "mcap": "application/octet-stream",
    "lerobot": "application/zip",
}
"""What each format's download is (a LeRobot dataset, a folder, comes zipped)."""


@dataclass(frozen=True)
class Download:
    """An export written for the page to download.

    Attributes:
        file: the file to send.
        name: its download name.
        folder: the temporary folder to remove after sending it.
        about: what the export did, in words (:func:`_about`), for the page to show beside its
            buttons: the timing, why it is slower than its source, the findings written in it,
            and the physics report the file states.
    """

    file: Path
    name: str
    folder: Path
    about: dict[str, object]


EXPORT_HEADER = "X-Studio-Export"
"""The download's header that says in words what the export did (:attr:`Download.about`)."""
MOST_FINDINGS = 20
"""The most findings :attr:`Download.about` lists (the file states every one)."""


def _motion(
    path: Path, robot: str, retime: bool, fit: bool, limit_margin: float | None = None
) -> tuple[Motion, tuple[Finding, ...]]:
    """A recording's or demonstration's motion on ``robot`` as the page exports it, keeping
    ``limit_margin`` (rad; None: the default) from every joint's hard limit, and the findings of
    its own times that made it slower (``fit``: :func:`studio.export.fit_timing`)."""
    if path.name.endswith(DEMO_SUFFIX):
        return demonstration_motion(path, robot, ROLLOUT_RATE_HZ, limit_margin), ()
    motion = recording_motion(path, robot, limit_margin=limit_margin)
    if retime:
        return motion.retimed(ROLLOUT_RATE_HZ), ()
    return fit_timing(motion, ROLLOUT_RATE_HZ) if fit else (motion, ())


def _about(motion: Motion, done: Exported, too_fast: tuple[Finding, ...]) -> dict[str, object]:
    """What an export did, said in words with no command-line flag, for the page."""
    title = motion.robot.spec.title
    if too_fast:
        said = (
            f"At its own times the {motion.kind} moves faster than the {title} may "
            f"({too_fast[0].sentence}), so it was exported at the person's pace, slowed only "
            "where the robot needs it, from rest to rest."
        )
    elif done.timed_by == "pace":
        slowed = ", slowed only where the robot needs it," if done.slowdowns else ""
        said = f"Exported at the person's pace{slowed} from rest to rest."
    elif done.timed_by == "source":
        said = "Exported at its own times."
    else:
        said = f"Exported as fast as the {title}'s limits allow, from rest to rest."
    if done.findings:
        said += (
            f" Not safe for the {title} as it is: {len(done.findings)} finding(s), each stated "
            "in the file."
        )
    return {
        "said": said,
        "timed_by": done.timed_by,
        "slowed_because": findings_public(too_fast[:MOST_FINDINGS]),
        "slowdowns": [s.sentence for s in done.slowdowns],
        "findings": findings_public(done.findings[:MOST_FINDINGS]),
        "physics": done.physics.sentences() if done.physics is not None else [],
    }


def simulate_for_robot(
    path: Path,
    robot: str,
    retime: bool = False,
    cache: Path | None = None,
    limit_margin: float | None = None,
    *,
    fit: bool = False,
) -> SimulationReport:
    """The physics report :func:`export_for_robot` would state in its file, before exporting:
    the same samples replayed in MuJoCo (``cache``: where the robot's MuJoCo files are kept).

    Raises:
        PhysicsError, ExportError, KinematicsError: no model can be built, an unknown robot.
    """
    return simulate_motion(_motion(path, robot, retime, fit, limit_margin)[0], cache=cache)


def simulated_motion(
    path: Path, robot: str, cache: Path | None = None, limit_margin: float | None = None
) -> Motion:
    """The motion the robot makes in physics for the samples the page's export writes
    (:func:`simulate_for_robot` with ``fit``): the simulated joints at each sample, to play in
    the scene.

    Raises:
        ExportError: the simulation went unstable (no motion to play).
        PhysicsError, KinematicsError: no model can be built, an unknown robot.
    """
    motion = _motion(path, robot, False, True, limit_margin)[0]
    report = simulate_motion(motion, cache=cache)
    if report.q_simulated is None or not np.all(np.isfinite(report.q_simulated)):
        raise ExportError(
            f"The {motion.robot.spec.title} went unstable in the simulation, so there is no "
            "simulated motion to play; check it in physics for the report."
        )
    return replace(motion, times=report.times, q=report.q_simulated, timed=True)


def export_for_robot(
    path: Path,
    robot: str,
    fmt: ExportFormat,
    unchecked: bool = False,
    retime: bool = False,
    limit_margin: float | None = None,
    *,
    fit: bool = False,
    cache: Path | None = None,
) -> Download:
    """Export a recording or demonstration ``path`` for ``robot`` as ``fmt`` into a fresh
    temporary folder, with the physics report stated in it as ``studio export`` states it.

    Args:
        unchecked: written despite failed checks, the findings stated in it.
        retime: a recording timed as a demonstration is (at the person's pace, slower only
            where the limits need it), not at its capture times.
        fit: a recording at its capture times where they keep the robot's limits, else timed
            as with ``retime`` (:func:`studio.export.fit_timing`): what the page's export asks.
        limit_margin: rad kept from every joint's hard limit by the retargeting, the timing and
            the checks, as ``studio export --limit-margin`` keeps it (None: the default).
        cache: where the robot's MuJoCo files are kept (None: a temporary folder).

    Raises:
        SafetyError: the trajectory fails the safety checks (nothing is written).
        ExportError, KinematicsError: the file cannot be written, an unknown robot.
    """
    stem = path.name
    for ending in (DEMO_SUFFIX, *RECORDING_SUFFIXES):
        stem = stem.removesuffix(ending)
    motion, too_fast = _motion(path, robot, retime, fit, limit_margin)
    done: list[Exported] = []

    def write(folder: Path) -> Path:
        out = folder / f"{stem}.{robot}{FORMAT_SUFFIXES[fmt]}"
        done.append(
            export_motion(motion, fmt, out, unchecked=unchecked, simulate=True, cache=cache)
        )
        if fmt == "lerobot":
            out = Path(shutil.make_archive(str(out), "zip", root_dir=out))
        return out

    out, folder = _in_a_temporary_folder(write)
    return Download(out, out.name, folder, _about(motion, done[0], too_fast))


def export_rollout(
    policy: Path,
    robot: str,
    name: str,
    times: np.ndarray,
    q: np.ndarray,
    unchecked: bool = False,
    *,
    fit: bool = False,
    cache: Path | None = None,
    obstacles: tuple[Obstacle, ...] = (),
) -> Download:
    """A policy's watched rollout ``(times, q)`` as an MCAP of its robot's
    ``JointTrajectory``, at the rollout's own times (``fit``: unless they break the robot's
    limits, then timed within them), checked for safety first, against the robot's limits, itself,
    the table and ``obstacles`` (its task's boxes) along it (``unchecked``: written despite
    failed checks, the findings stated in it), with the physics report stated in it.

    Raises:
        SafetyError: the rollout fails the safety checks (nothing is written).
        ExportError: the file cannot be written, or ``robot`` is not one offered.
    """
    arm = check_policy_robot(policy, robot, robot)
    motion = Motion(
        "policy", policy.name, arm, times, q, True, ROLLOUT_RATE_HZ, obstacles=tuple(obstacles)
    )
    motion, too_fast = fit_timing(motion, ROLLOUT_RATE_HZ) if fit else (motion, ())
    done: list[Exported] = []

    def write(folder: Path) -> Path:
        out = folder / f"{name}.rollout{FORMAT_SUFFIXES['mcap']}"
        done.append(
            export_motion(motion, "mcap", out, unchecked=unchecked, simulate=True, cache=cache)
        )
        return out

    out, folder = _in_a_temporary_folder(write)
    return Download(out, out.name, folder, _about(motion, done[0], too_fast))


def _in_a_temporary_folder(write: Callable[[Path], Path]) -> tuple[Path, Path]:
    """``(write(folder), folder)`` for a fresh temporary folder, removed if ``write`` fails.

    A download is written in the temporary folder, not the data folder, so a disk that refuses
    it is that folder's: the sentence names it, in the page's words (the export package's own
    sentences speak to the command line, naming ``--out``).

    Raises:
        StorageError: the temporary folder's disk refused the write (full, read-only, ...).
    """
    folder: Path | None = None
    try:
        folder = Path(tempfile.mkdtemp(prefix="studio-export-"))
        return write(folder), folder
    except (OSError, ExportError) as err:
        if folder is not None:
            shutil.rmtree(folder, ignore_errors=True)
        cause = err if isinstance(err, OSError) else err.__context__
        if not isinstance(cause, OSError):
            raise
        what = STORAGE_PROBLEMS.get(cause.errno or 0, (f"failed ({cause.strerror or cause})",))[0]
        room = "free some space there" if cause.errno in _FULL else "fix that folder"
        raise StorageError(
            f"The disk holding the temporary folder {tempfile.gettempdir()} {what}, so the "
            f"export could not be written (your data folder is untouched); {room}, or start the "
            "studio with TMPDIR set to a folder on a disk with room, and export again."
        ) from None
    except BaseException:
        if folder is not None:
            shutil.rmtree(folder, ignore_errors=True)
        raise


_FULL = (errno.ENOSPC, errno.EDQUOT)
"""Disk failures that free space fixes."""
