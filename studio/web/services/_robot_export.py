"""A recording or a demonstration downloaded from the page as the chosen robot's trajectory, and
a policy's watched rollout as its robot's, through :mod:`studio.export` (the same retargeting,
timing, safety checks and formats as ``studio export``)."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path
from typing import Literal, get_args

import numpy as np

from studio.capture import DEMO_SUFFIX, RECORDING_SUFFIXES
from studio.export import (
    FORMAT_SUFFIXES,
    FORMATS,
    check_policy_robot,
    export_motion,
    simulate_motion,
)
from studio.learning import ROLLOUT_RATE_HZ
from studio.motion import Motion, demonstration_motion, recording_motion
from studio.physics import SimulationReport

ExportFormat = Literal["csv", "mcap", "lerobot"]
"""The formats of :data:`studio.export.FORMATS`, as the API's query parameter."""
assert get_args(ExportFormat) == FORMATS, "the API's formats are studio.export's"

MEDIA_TYPES = {
    "csv": "text/csv",
    "mcap": "application/octet-stream",
    "lerobot": "application/zip",
}
"""What each format's download is (a LeRobot dataset, a folder, comes zipped)."""


def _motion(path: Path, robot: str, retime: bool) -> Motion:
    """A recording's or demonstration's motion on ``robot`` as the page exports it."""
    if path.name.endswith(DEMO_SUFFIX):
        return demonstration_motion(path, robot, ROLLOUT_RATE_HZ)
    motion = recording_motion(path, robot)
    return motion.retimed(ROLLOUT_RATE_HZ) if retime else motion


def simulate_for_robot(
    path: Path, robot: str, retime: bool = False, cache: Path | None = None
) -> SimulationReport:
    """The physics report :func:`export_for_robot` would state in its file, before exporting:
    the same samples replayed in MuJoCo (``cache``: where the robot's MuJoCo files are kept).

    Raises:
        PhysicsError, ExportError, KinematicsError: no model can be built, an unknown robot.
    """
    return simulate_motion(_motion(path, robot, retime), cache=cache)


def export_for_robot(
    path: Path, robot: str, fmt: ExportFormat, unchecked: bool = False, retime: bool = False
) -> tuple[Path, str, Path]:
    """Export a recording or demonstration ``path`` for ``robot`` as ``fmt`` into a fresh
    temporary folder (``unchecked``: written despite failed checks, the findings stated in it;
    a demonstration timed within the limits at the rollout rate, a recording at its capture
    times, or timed as a demonstration is with ``retime``).

    Returns:
        ``(file, download name, folder)``: the file to send and the folder to remove after.

    Raises:
        SafetyError: the trajectory fails the safety checks (nothing is written).
        ExportError, KinematicsError: the file cannot be written, an unknown robot.
    """
    stem = path.name
    for ending in (DEMO_SUFFIX, *RECORDING_SUFFIXES):
        stem = stem.removesuffix(ending)
    motion = _motion(path, robot, retime)
    folder = Path(tempfile.mkdtemp(prefix="studio-export-"))
    try:
        out = folder / f"{stem}.{robot}{FORMAT_SUFFIXES[fmt]}"
        export_motion(motion, fmt, out, unchecked=unchecked)
        if fmt == "lerobot":
            out = Path(shutil.make_archive(str(out), "zip", root_dir=out))
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
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
    folder = Path(tempfile.mkdtemp(prefix="studio-export-"))
    try:
        out = folder / f"{name}.rollout{FORMAT_SUFFIXES['mcap']}"
        export_motion(motion, "mcap", out, unchecked=unchecked)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return out, out.name, folder
