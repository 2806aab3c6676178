"""What the scene shows, apart from viser: its layout, the default camera's projection, and the
robot's pose at an instant (:func:`pose_at`, a pure function of the inputs and the clock).

What the robot shows is one of three modes: ``live`` (following the fitted pose), ``playback``
(performing a trajectory) and ``hold`` (keeping a finished playback's last pose a moment, then
back to live).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field, replace

import numpy as np

from studio.kinematics import SLEEVE_LIFT_M, MeshConfig


@dataclass(frozen=True)
class SceneLayout:
    """Where things stand, how the camera looks at them and how fast the scene is refreshed.

    Attributes:
        operator_position: floor point (x, y) under the middle of the operator's body (m).
        operator_yaw: the operator's heading about +Z (rad); pi faces the robot at the origin.
        rate_hz: most scene pushes per second (latest values win in between).
        slow_live_s: a live stream whose poses come this far apart or more on average (pose
            estimation without a GPU) is slow: viser's page redraws for a quarter of a second
            after each push, so each of its poses would cost the browser a burst of redraws in
            the very process that runs the pose model, slowing it by a third.
        slow_live_rate_hz: most pushes per second of a slow live stream (latest wins).
        unviewed_rate_hz: most pushes per second while no browser shows the scene (latest
            wins); the first browser to connect wakes the scene at once. Posing the operator's
            meshes and sending them at ``rate_hz`` to nobody took half of an idle studio's CPU.
        floor_half_size: the floor plate reaches this far from its centre (m).
        floor_cell: spacing of the floor's grid lines (m).
        playback_hold_s: how long the robot keeps the last pose of a finished playback before
            following the live pose again.
        camera_position: default camera position (m): beside the pair, a little above.
        camera_look_at: default camera target (m): between the two bodies.
        camera_fov_deg: default vertical field of view (degrees).
        ghost_opacity: opacity of the goal's ghost robot.
        fill_light: intensity of the sky/ground fill light.
        tape_lift_m: how far the tape is drawn from the upper arm's and the forearm's axis
            (m): on the sleeve (:func:`studio.kinematics.tape_on_sleeve`).
        mesh: mesh simplification (see :class:`~studio.kinematics.MeshConfig`).
        colors: named colours (0-255 rgb).
    """

    operator_position: tuple[float, float] = (1.75, 0.0)
    operator_yaw: float = float(np.pi)
    rate_hz: float = 60.0
    slow_live_s: float = 0.2
    slow_live_rate_hz: float = 1.0
    unviewed_rate_hz: float = 5.0
    floor_half_size: float = 1.6
    floor_cell: float = 0.25
    playback_hold_s: float = 5.0
    camera_position: tuple[float, float, float] = (1.2, -3.9, 1.85)
    camera_look_at: tuple[float, float, float] = (0.85, 0.0, 0.95)
    camera_fov_deg: float = 50.0
    ghost_opacity: float = 0.22
    fill_light: float = 1.6
    tape_lift_m: tuple[float, float] = SLEEVE_LIFT_M
    mesh: MeshConfig = field(default_factory=MeshConfig)
    colors: dict[str, tuple[int, int, int]] = field(
        default_factory=lambda: {
            "tape": (20, 190, 120),
            "goal": (230, 60, 60),
            "path": (40, 120, 230),
            "path_start": (40, 170, 90),
            "trace": (240, 150, 20),
            "floor": (236, 238, 241),
            "floor_lines": (196, 200, 206),
        }
    )


class Mode(enum.Enum):
    """What the robot shows: the live pose, a playback, or a finished playback's last pose."""

    LIVE = "live"
    PLAYBACK = "playback"
    HOLD = "hold"


@dataclass(frozen=True, eq=False)
class Playback:
    """A trajectory being performed: sample times from 0 (s), joints, tool points, bin marks.

    Attributes:
        times: ``(N,)`` s, non-decreasing, from 0.
        q: ``(N, nq)`` rad.
        tool: ``(N, 3)`` world tool positions (m).
        marks: sample indices where a grid bin is marked.
        started: clock time (``time.perf_counter``) at which the trajectory stood at ``offset``.
        offset: trajectory time (s) at ``started``: 0 for a playback from the start, the scrub
            position after a seek, a step or a change of speed.
        speed: trajectory seconds per clock second (1 is real time).
        paused: the trajectory stands still at ``offset`` (and is shown, not released to the
            live pose, however long it stands).
        robot: the robot whose joints ``q`` are (``puma560``, ``panda``, ...): the scene moves
            only that robot with it.
    """

    times: np.ndarray
    q: np.ndarray
    tool: np.ndarray
    marks: np.ndarray
    started: float
    offset: float = 0.0
    speed: float = 1.0
    paused: bool = False
    robot: str = "puma560"

    @property
    def duration(self) -> float:
        """Length of the trajectory (s)."""
        return float(self.times[-1])


PLAYBACK_SPEEDS = (0.25, 0.5, 1.0, 2.0, 4.0)
"""The playback speeds offered (trajectory seconds per clock second); any speed between the
first and the last is accepted."""


def playback_time(playback: Playback, now: float) -> float:
    """Trajectory time (s) at clock time ``now``: past :attr:`Playback.duration` once finished."""
    if playback.paused:
        return playback.offset
    return playback.offset + (now - playback.started) * playback.speed


def rescheduled(
    playback: Playback,
    now: float,
    *,
    t: float | None = None,
    speed: float | None = None,
    paused: bool | None = None,
    step: int = 0,
) -> Playback:
    """The same trajectory rescheduled at clock time ``now``: a pure function of the inputs.

    Args:
        playback: the playback as it stands.
        now: clock time (s) of the change.
        t: scrub to this trajectory time (s, clipped to the trajectory); None keeps the time
            reached at ``now``.
        speed: the new speed (None keeps it).
        paused: pause or resume (None keeps it). Resuming at the end starts it over.
        step: move this many samples forward (positive) or back (negative) from the time
            reached, landing on a sample, and pause there.

    Returns:
        A new :class:`Playback` that stands at the chosen time at ``now``.
    """
    times = playback.times
    at = playback_time(playback, now) if t is None else float(t)
    at = min(max(at, 0.0), playback.duration)
    if step:
        if step > 0:  # the first sample after the time reached, then on
            k = int(np.searchsorted(times, at, side="right")) - 1 + step
        else:  # the last sample before it, then back
            k = int(np.searchsorted(times, at, side="left")) + step
        at = float(times[min(max(k, 0), len(times) - 1)])
        paused = True
    if paused is False and at >= playback.duration:
        at = 0.0  # resuming at the end plays it again from the start
    paused = playback.paused if paused is None else bool(paused)
    return replace(
        playback,
        started=now,
        offset=at,
        speed=playback.speed if speed is None else float(speed),
        paused=paused,
    )


@dataclass(frozen=True)
class ScenePose:
    """What the robot shows at an instant.

    Attributes:
        mode: the mode in force.
        q_robot: the robot joints (rad), or None when there is nothing to show yet.
        trace_upto: the last playback sample the trace reaches (-1: no trace).
    """

    mode: Mode
    q_robot: np.ndarray | None
    trace_upto: int = -1


def pose_at(
    now: float,
    live_q_robot: np.ndarray | None,
    playback: Playback | None,
    hold_s: float,
) -> ScenePose:
    """The robot pose at clock time ``now``: a pure function of the inputs.

    Args:
        now: clock time (s, same clock as ``playback.started``).
        live_q_robot: the newest live robot joints, or None before the first live pose.
        playback: the trajectory being performed, or None.
        hold_s: how long a finished playback's last pose is held.

    Returns:
        ``playback`` (interpolated between samples) while the trajectory runs or stands paused
        (:func:`playback_time`: scrubbed, at its speed), ``hold`` (its last pose) for ``hold_s``
        after it ends, ``live`` otherwise.
    """
    if playback is not None:
        times = playback.times
        t = playback_time(playback, now)
        end = float(times[-1])
        if playback.paused and t >= end:
            return ScenePose(Mode.PLAYBACK, playback.q[-1], len(times) - 1)
        if t < end:
            k = int(np.searchsorted(times, t, side="right")) - 1
            k = min(max(k, 0), len(times) - 2)
            span = times[k + 1] - times[k]
            w = 0.0 if span <= 0 else min(max((t - times[k]) / span, 0.0), 1.0)
            q = (1 - w) * playback.q[k] + w * playback.q[k + 1]
            return ScenePose(Mode.PLAYBACK, q, k)
        if t < end + hold_s * playback.speed:  # held hold_s of clock time
            return ScenePose(Mode.HOLD, playback.q[-1], len(times) - 1)
    return ScenePose(Mode.LIVE, live_q_robot, -1)


def camera_projection(
    points: np.ndarray, layout: SceneLayout, aspect: float
) -> tuple[np.ndarray, np.ndarray]:
    """Where world points land on the default camera's image.

    Args:
        points: ``(N, 3)`` world points (m).
        layout: gives the camera's position, target and vertical field of view (Z up).
        aspect: image width / height.

    Returns:
        ``(ndc (N, 2), depth (N,))``: normalised image coordinates (inside the image when both
        lie in [-1, 1]) and the distance in front of the camera (m; negative is behind).
    """
    eye = np.asarray(layout.camera_position, dtype=float)
    forward = np.asarray(layout.camera_look_at, dtype=float) - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    d = np.atleast_2d(np.asarray(points, dtype=float)) - eye
    depth = d @ forward
    tan_half = np.tan(np.radians(layout.camera_fov_deg) / 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (d @ right) / (depth * tan_half * aspect)
        y = (d @ up) / (depth * tan_half)
    return np.stack([x, y], axis=1), depth
