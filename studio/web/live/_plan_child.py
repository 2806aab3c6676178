"""The child process that plans a recording's path on a robot for the studio
(:func:`studio.web.live._planned_playback.plan_recording`).

``python -m studio.web.live._plan_child RECORDING ROBOT OUT.npz`` writes the recording's
:class:`~studio.kinematics.RetargetedPath` (:func:`studio.export.recording_motion`) to
``OUT.npz`` and exits 0; a recording or robot it cannot plan prints the one sentence saying why
and exits 2. It runs apart from the studio because the planning holds the interpreter for up to
0.2 s at a time, which would stall the live pipeline's frames in a thread of the studio's.
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np

from studio import StudioError
from studio.kinematics import RetargetedPath
from studio.motion import recording_motion

CANNOT = 2
"""The exit code of a recording or robot that cannot be planned (the sentence on stdout)."""


def save_path(path: RetargetedPath, out: Path) -> None:
    """Write ``path``'s arrays to ``out`` (``.npz``)."""
    np.savez(out, **{f.name: getattr(path, f.name) for f in dataclasses.fields(path)})


def load_path(out: Path) -> RetargetedPath:
    """The path :func:`save_path` wrote to ``out``."""
    with np.load(out) as data:
        return RetargetedPath(**{f.name: data[f.name] for f in dataclasses.fields(RetargetedPath)})


def main(argv: list[str]) -> int:
    recording, robot, out = argv
    try:
        motion = recording_motion(Path(recording), robot)
    except (StudioError, OSError) as err:
        print(err, flush=True)
        return CANNOT
    assert motion.path is not None  # a recording is always retargeted
    save_path(motion.path, Path(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
