"""A recording or a demonstration downloaded from the page as the chosen robot's trajectory, and
a policy's watched rollout as its robot's, through :mod:`studio.export` (the same retargeting,
timing, safety checks and formats as ``studio export``)."""

from __future__ import annotations

import errno
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Literal, get_args

import numpy as np

from studio.capture import DEMO_SUFFIX, RECORDING_SUFFIXES
from studio.export import (
    FORMAT_SUFFIXES,
    FORMATS,
    ExportError,
    check_policy_robot,
    export_motion,
    simulate_motion,
)
from studio.learning import ROLLOUT_RATE_HZ
from studio.motion import Motion, demonstration_motion, recording_motion
from studio.physics import SimulationReport

from .._errors import STORAGE_PROBLEMS, StorageError

ExportFormat = Literal["csv", "mcap", "lerobot"]
"""The formats of :data:`studio.export.FORMATS`, as the API's query parameter."""
assert get_args(ExportFormat) == FORMATS, "the API's formats are studio.export's"

MEDIA_TYPES = {
    "csv": "text/csv",
    "mcap": "application/octet-stream",
    "lerobot": "application/zip",
}
"""What each format's download is (a LeRobot dataset, a folder, comes zipped)."""


def _motion(path: Path, robot: str, retime: bool, limit_margin: float | None = None) -> Motion:
    """A recording's or demonstration's motion on ``robot`` as the page exports it, keeping
    ``limit_margin`` (rad; None: the default) from every joint's hard limit."""
    if path.name.endswith(DEMO_SUFFIX):
        return demonstration_motion(path, robot, ROLLOUT_RATE_HZ, limit_margin)
    motion = recording_motion(path, robot, limit_margin=limit_margin)
    return motion.retimed(ROLLOUT_RATE_HZ) if retime else motion


def simulate_for_robot(
    path: Path,
    robot: str,
    retime: bool = False,
    cache: Path | None = None,
    limit_margin: float | None = None,
) -> SimulationReport:
    """The physics report :func:`export_for_robot` would state in its file, before exporting:
    the same samples replayed in MuJoCo (``cache``: where the robot's MuJoCo files are kept).

    Raises:
        PhysicsError, ExportError, KinematicsError: no model can be built, an unknown robot.
    """
    return simulate_motion(_motion(path, robot, retime, limit_margin), cache=cache)


def export_for_robot(
    path: Path,
    robot: str,
    fmt: ExportFormat,
    unchecked: bool = False,
    retime: bool = False,
    limit_margin: float | None = None,
) -> tuple[Path, str, Path]:
    """Export a recording or demonstration ``path`` for ``robot`` as ``fmt`` into a fresh
    temporary folder (``unchecked``: written despite failed checks, the findings stated in it;
    a demonstration timed within the limits at the rollout rate, a recording at its capture
    times, or timed as a demonstration is with ``retime``; ``limit_margin``: rad kept from
    every joint's hard limit by the retargeting, the timing and the checks, as ``studio export
    --limit-margin`` keeps it; None: the default).

    Returns:
        ``(file, download name, folder)``: the file to send and the folder to remove after.

    Raises:
        SafetyError: the trajectory fails the safety checks (nothing is written).
        ExportError, KinematicsError: the file cannot be written, an unknown robot.
    """
    stem = path.name
    for ending in (DEMO_SUFFIX, *RECORDING_SUFFIXES):
        stem = stem.removesuffix(ending)
    motion = _motion(path, robot, retime, limit_margin)

    def write(folder: Path) -> Path:
        out = folder / f"{stem}.{robot}{FORMAT_SUFFIXES[fmt]}"
        export_motion(motion, fmt, out, unchecked=unchecked)
        if fmt == "lerobot":
            out = Path(shutil.make_archive(str(out), "zip", root_dir=out))
        return out

    out, folder = _in_a_temporary_folder(write)
    return out, out.name, folder


def export_rollout(
    policy: Path,
    robot: str,
    name: str,
    times: np.ndarray,
    q: np.ndarray,
    unchecked: bool = False,
) -> tuple[Path, str, Path]:
    """A policy's watched rollout ``(times, q)`` as an MCAP of its robot's
    ``JointTrajectory``, at the rollout's own times, checked for safety first (``unchecked``:
    written despite failed checks, the findings stated in it).

    Returns:
        ``(file, download name, folder)``, as :func:`export_for_robot`.

    Raises:
        SafetyError: the rollout fails the safety checks (nothing is written).
        ExportError: the file cannot be written, or ``robot`` is not one offered.
    """
    arm = check_policy_robot(policy, robot, robot)
    motion = Motion("policy", policy.name, arm, times, q, True, ROLLOUT_RATE_HZ)

    def write(folder: Path) -> Path:
        out = folder / f"{name}.rollout{FORMAT_SUFFIXES['mcap']}"
        export_motion(motion, "mcap", out, unchecked=unchecked)
        return out

    out, folder = _in_a_temporary_folder(write)
    return out, out.name, folder


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
