"""A demonstration and the learning tasks: the cutter, and a demonstration file as the tasks read it.

The cutter (:func:`extract_demonstration`) takes a recording segment's Puma560 path from capture
(:func:`studio.capture.track_segment`: tracked, checked for its fit and the robot's range), then
puts it on the learning task's :class:`~studio.learning.ArmGrid` with
:meth:`~studio.learning.ArmGrid.trace_joints` (the one demonstration-to-grid-path function, which
the page's run queue and ``studio train`` replay too): valid consecutive actions, cut at the first
visit to the goal (a reach-and-return motion keeps its reach), pauses and loops (bin-boundary
flicker) removed. A segment that never reaches the goal is refused with the reason; with
``goal_from_end=True`` the goal becomes wherever the segment ends, and a ``grid`` with another
goal cuts at that goal. Capture stores what the cutter gave (:class:`studio.capture.Demonstration`).

:func:`checked_demonstration` reads a ``*.demo.json`` file as every task does: learning's
:func:`~studio.learning.motion_problem` judges its trajectory (NaN samples, a cut of zero length,
times that do not increase), and its grid path is traced again from the trajectory toward its own
goal, so a file written by older code, or edited by hand, lists and replays today's path.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from pathlib import Path

from studio.capture import (
    Demonstration,
    DemonstrationError,
    ObservationRecording,
    Recording,
    load_demonstration,
    track_segment,
)
from studio.kinematics import ArmTracker
from studio.learning import ArmGrid, LearningError, motion_problem


def extract_demonstration(
    recording: Recording | ObservationRecording | str | os.PathLike[str],
    t0: float,
    t1: float,
    grid: ArmGrid | None = None,
    mode: str = "joint",
    goal_from_end: bool = False,
    *,
    max_residual: float | None = None,
    tracker: ArmTracker | None = None,
    name: str = "",
) -> Demonstration:
    """Turn the segment ``[t0, t1]`` of a recording into a demonstration.

    Args:
        recording: a recording of any kind (tape, pose landmarks, hand poses) or its path; each
            kind's observations go through their own fitter (:func:`studio.capture.fitter_for`)
            into the human arm, then the one retargeting.
        t0: segment start (s after the recording's first frame, as playback's ``seek``).
        t1: segment end (s after the first frame).
        grid: the :class:`studio.learning.ArmGrid` (default ``ArmGrid()``, the paper's task);
            its goal is where the path is cut (the first visit).
        mode: retargeting mode, ``"joint"`` or ``"cartesian"``.
        goal_from_end: instead of refusing a segment that misses the goal, make its end the goal.
        max_residual: worst allowed fit residual (m) of a tape recording (None: capture's
            default, 3 cm; :func:`studio.capture.track_segment` says why).
        tracker: the :class:`studio.kinematics.ArmTracker` to track the frames with, for this
            recording's tape (default: a mirroring one for the recording's tape); it is reset
            and set to ``mode`` first.
        name: display name.

    Returns:
        The demonstration (call :meth:`~studio.capture.Demonstration.save` to write it).

    Raises:
        DemonstrationError: with ``reason`` ``too_short``, ``bad_fit``, ``leaves_joint_range`` or
            ``never_reaches_goal``, and one sentence saying what to change.
    """
    limits = {} if max_residual is None else {"max_residual": max_residual}
    segment = track_segment(recording, t0, t1, mode, tracker=tracker, **limits)
    grid = grid if grid is not None else ArmGrid()
    q_robot = segment.q_robot
    trace = grid.trace_joints(q_robot, stop_at_goal=True)
    if not trace.reaches_goal:
        end = tuple(int(b) for b in grid.bins_of_angles(q_robot[-1, : grid.joints]))
        if not goal_from_end:
            raise DemonstrationError(
                f"the segment ends in grid bins {end} and never reaches the goal {tuple(grid.goal)}; extend the segment, or set the goal from where it ends.",
                "never_reaches_goal",
            )
        grid = dataclasses.replace(grid, goal=end)
        trace = grid.trace_joints(q_robot, stop_at_goal=True)
    if trace.steps < 1:
        raise DemonstrationError(
            f"the segment [{t0:.2f}, {t1:.2f}] s already starts at the goal; start the segment before the reach.",
            "too_short",
        )
    reached_at = float(segment.times[trace.samples[-1]])
    return segment.demonstration(trace.states, grid.to_dict(), reached_at, name)


def demonstration_grid(demo: Demonstration) -> ArmGrid:
    """The :class:`studio.learning.ArmGrid` a demonstration's path lives on (its stored grid and
    its own goal).

    Raises:
        LearningError: a stored grid setting out of range; TypeError: a setting of the wrong kind.
    """
    make: Callable[..., ArmGrid] = ArmGrid  # it checks each setting read from the file
    return make(**{**demo.grid, "goal": tuple(demo.goal)})


def checked_demonstration(path: str | os.PathLike[str]) -> Demonstration:
    """A ``*.demo.json`` file as the learning tasks read it: the file
    (:func:`studio.capture.load_demonstration`), its trajectory judged by learning
    (:func:`studio.learning.motion_problem`), and its grid path traced again toward its own goal.

    A file written by older code (which erased loops before cutting at the goal) gets today's
    path, so the listing, the page and the CLI replay the same steps. A trajectory that never
    reaches the goal keeps the path to where it ends, and a run refuses it with its sentence (the
    page as the demonstration is picked).

    Raises:
        DemonstrationError: (``reason`` ``bad_file``) one sentence naming what is wrong with the
            file and the fix.
    """
    path = Path(path)
    demo = load_demonstration(path)
    problem = motion_problem(f"The demonstration {path}", demo.times, demo.q_robot)
    if problem is not None:
        raise DemonstrationError(problem, "bad_file")
    try:
        demo.grid_path = (
            demonstration_grid(demo).trace_joints(demo.q_robot, stop_at_goal=True).states
        )
    except (LearningError, TypeError) as err:
        raise DemonstrationError(
            f"{path} has a bad grid or trajectory ({err}); re-extract the demonstration.",
            "bad_file",
        ) from None
    return demo
