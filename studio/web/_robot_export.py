"""A recording or a demonstration, downloaded from the page as the chosen robot's trajectory
through :mod:`studio.export` (the same retargeting, timing, safety checks and formats as
``studio export``)."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path
from typing import Literal, get_args

from studio.capture import DEMO_SUFFIX, RECORDING_SUFFIXES
from studio.export import (
    FORMAT_SUFFIXES,
    FORMATS,
    demonstration_motion,
    export_motion,
    recording_motion,
)
from studio.learning import ROLLOUT_RATE_HZ

ExportFormat = Literal["csv", "mcap", "lerobot"]
"""The formats of :data:`studio.export.FORMATS`, as the API's query parameter."""
assert get_args(ExportFormat) == FORMATS, "the API's formats are studio.export's"

MEDIA_TYPES = {
    "csv": "text/csv",
    "mcap": "application/octet-stream",
    "lerobot": "application/zip",
}
"""What each format's download is (a LeRobot dataset, a folder, comes zipped)."""


def export_for_robot(
    path: Path, robot: str, fmt: ExportFormat, unchecked: bool = False
) -> tuple[Path, str, Path]:
    """Export a recording or demonstration ``path`` for ``robot`` as ``fmt`` into a fresh
    temporary folder (``unchecked``: written despite failed checks, the findings stated in it;
    a demonstration at the rollout rate, a recording at its capture rate).

    Returns:
        ``(file, download name, folder)``: the file to send and the folder to remove after.

    Raises:
        SafetyError: the trajectory fails the safety checks (nothing is written).
        ExportError, KinematicsError: the file cannot be written, an unknown robot.
    """
    stem = path.name
    for ending in (DEMO_SUFFIX, *RECORDING_SUFFIXES):
        stem = stem.removesuffix(ending)
    if path.name.endswith(DEMO_SUFFIX):
        motion = demonstration_motion(path, robot, ROLLOUT_RATE_HZ)
    else:
        motion = recording_motion(path, robot)
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
