"""The child process that plans a recording's path on a robot for the studio
(:func:`studio.web.live._planned_playback.plan_recording`).

``python -m studio.web.live._plan_child RECORDING ROBOT OUT.npz [ROBOT_CACHE]`` writes the
recording's :class:`~studio.kinematics.RetargetedPath` (:func:`studio.export.recording_motion`) to
``OUT.npz`` and exits 0; a recording or robot it cannot plan prints the one sentence saying why
and exits 2. It runs apart from the studio because the planning holds the interpreter for up to
0.2 s at a time, which would stall the live pipeline's frames in a thread of the studio's. Given
the studio's robot cache folder (:func:`studio.kinematics.robot_cache_folder`), it reads the
robot's collision geometry kept there (the studio built it when the robot was chosen) instead of
building it again; it loads only the modules planning needs, not the studio's app.

The studio holds the child's stdin open while it waits for it. When the studio dies (even by
``kill -9``), the kernel closes that pipe: the child sees the end of its stdin, removes its
temporary folder and quits, so no plan outlives its studio.
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import sys
import threading
from pathlib import Path

import numpy as np

from studio import StudioError
from studio.kinematics import RetargetedPath, keep_robot_geometry
from studio.motion import recording_motion

CANNOT = 2
"""The exit code of a recording or robot that cannot be planned (the sentence on stdout)."""
ORPHANED = 3
"""The exit code of a child whose studio went away (its stdin ended)."""
TEMP_PREFIX = "studio-plan-"
"""The name of a plan's temporary folder begins so (the child removes it if orphaned)."""


def save_path(path: RetargetedPath, out: Path) -> None:
    """Write ``path``'s arrays to ``out`` (``.npz``)."""
    np.savez(out, **{f.name: getattr(path, f.name) for f in dataclasses.fields(path)})


def load_path(out: Path) -> RetargetedPath:
    """The path :func:`save_path` wrote to ``out``."""
    with np.load(out) as data:
        return RetargetedPath(**{f.name: data[f.name] for f in dataclasses.fields(RetargetedPath)})


def quit_with_the_studio(out: Path) -> None:
    """Watch stdin from a thread: at its end (the studio is gone) remove ``out``'s temporary
    folder and quit at once."""

    def watch() -> None:
        try:  # the bare descriptor: a daemon thread in sys.stdin would hold its lock at exit
            while os.read(sys.stdin.fileno(), 4096):
                pass
        except (OSError, ValueError):
            pass
        if out.parent.name.startswith(TEMP_PREFIX):
            shutil.rmtree(out.parent, ignore_errors=True)
        os._exit(ORPHANED)

    threading.Thread(target=watch, name="studio-plan-orphan", daemon=True).start()


def main(argv: list[str]) -> int:
    recording, robot, out, *cache = argv
    quit_with_the_studio(Path(out))
    if cache:
        keep_robot_geometry(Path(cache[0]))  # a robot not kept there is built and kept
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
