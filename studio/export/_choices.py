"""What a person chooses for an export, and the defaults: the file formats and the share of the
robot's limits the timing uses.

A light module (no numpy, TOPP-RA or robot model): ``studio export --help`` and a mistyped flag
read these at once, while :mod:`._formats` and :mod:`._timing`, which use them, load only when
an export runs.
"""

from __future__ import annotations

from typing import Literal

Format = Literal["csv", "mcap", "lerobot"]
FORMATS: tuple[Format, ...] = ("csv", "mcap", "lerobot")
"""The trajectory formats ``studio export --format`` writes."""
FORMAT_SUFFIXES: dict[Format, str] = {"csv": ".csv", "mcap": ".mcap", "lerobot": ".lerobot"}
"""Each format's default ending after the source's name (a LeRobot dataset is a folder)."""
LIMIT_FRACTION = 0.8
"""The share of each velocity and acceleration limit the timing uses by default: headroom for
the controller's tracking and the spline's sampling, checked afterwards against the full limits."""
