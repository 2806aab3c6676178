"""Arm motion on a robot: a recorded human arm's motion (a recording, its timeline, a
demonstration) retargeted onto any robot, and a demonstration turned into a learning task's input.

It sits above :mod:`studio.kinematics`, :mod:`studio.capture` and :mod:`studio.learning` (it
composes them) and below :mod:`studio.export`, the web layer and the commands (they call it):
capture stores observations and joints and knows no learning task; learning knows no recording.
See ``docs/architecture.md`` for the public names::

    from studio.motion import checked_demonstration, recording_motion, training_demonstration

    motion = recording_motion(Path("recordings/reach.tape.csv"), "ur5")  # motion.q: (N, 6) rad
    demo = checked_demonstration("recordings/reach.0.50-2.10.demo.json")  # demo.grid_path
"""

from ._demonstrations import checked_demonstration as checked_demonstration
from ._demonstrations import demonstration_grid as demonstration_grid
from ._demonstrations import extract_demonstration as extract_demonstration
from ._errors import MotionError as MotionError
from ._robot_motion import Finding as Finding
from ._robot_motion import Motion as Motion
from ._robot_motion import SourceKind as SourceKind
from ._robot_motion import demonstration_motion as demonstration_motion
from ._robot_motion import recording_motion as recording_motion
from ._robot_motion import series_motion as series_motion
from ._robot_motion import training_demonstration as training_demonstration
