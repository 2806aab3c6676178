"""Time-parametrisation: a joint path timed at its source's pace where the robot's limits allow,
slower only where they do not, from rest to rest (:func:`pace_path`); or as fast as the limits
allow (:func:`time_path`).

A policy rollout or a demonstration is a *path* (where the joints go) with the times its source
took; how it is run is set here with TOPP-RA (``toppra``): the fastest timing along the path that
keeps every joint's velocity and acceleration within a fraction of the URDF's limits and, at the
person's pace, never goes faster than the source did (``_topp.PaceBound``), so it runs at the
person's pace wherever the robot can, and :class:`Slowdown` says where it could not. The path is first cleared of
steps shorter than :data:`STILL_RAD` and thinned to the waypoints that matter (no sample of the
original path is further than :data:`PATH_TOLERANCE_RAD` from the thinned one, joint by joint),
so the capture noise of a demonstration does not force the arm to crawl. The curve through the
waypoints and how TOPP-RA is set up to time every such path are ``_topp.py``'s. The timing
starts and ends at rest, and ends where the path does.

Why TOPP-RA rather than Ruckig: Ruckig's open-source edition plans from one state to one target
and does not pass through intermediate waypoints, so a path of many waypoints would stop at each
(``benchmarks/bench_export.py``: on the same thinned waypoints and limits, Ruckig stopping at
each takes 1.05-1.16x TOPP-RA's duration on the sample demonstrations, whose jittery wrists
nearly stop anyway, and 2.3x on a smooth arc); TOPP-RA times a given path, which is this job.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ._choices import LIMIT_FRACTION
from ._errors import ExportError

if TYPE_CHECKING:
    from studio.kinematics import RobotArm

PATH_TOLERANCE_RAD = np.radians(0.5)
"""How far (rad, per joint) the thinned path may pass from a sample of the original one."""
STILL_RAD = 1e-6
"""A step of the path shorter than this on every joint (rad) is no motion: a sixth of a 20-bit
encoder's count (6e-6 rad), and TOPP-RA's LP solver, whose tolerances are absolute, fails on
steps of a ten-millionth of a radian. A path that never leaves its first sample by this much is
held still there."""
RETIME_FACTOR = 0.8
"""TOPP-RA bounds the limits at its grid points only; when the sampled trajectory still exceeds
a limit between them, the timing is run again with the limits scaled by this factor."""
RETIME_TRIES = 4
"""How many times the timing is run before the samples go to the checks as they are."""


PACE_WINDOW_S = 0.1
"""The source's pace at a place is its rate over the arc around it that it covers in this long at
its typical (median) speed (s)."""
PACE_PLACES = 2000
"""Places along the path at which the source's pace is given to the timing."""
SLOWEST_PACE = 0.002
"""The slowest the source's pace is taken to be, as a share of its median: where the source
paused, the robot moves on slowly rather than stopping for good."""
SLOWED_SECONDS = 0.01
"""A stretch of the source taking this much longer (s) is slowed down; less is rounding."""


@dataclass(frozen=True)
class Slowdown:
    """A stretch of the source the robot runs slower than the source did.

    Attributes:
        t0, t1: the stretch, in the source's own time (s from its first sample).
        added: how much longer the robot takes over it (s).
        start, end: whether it is where the robot starts from rest or comes to rest (the source
            was moving there).
    """

    t0: float
    t1: float
    added: float
    start: bool = False
    end: bool = False

    @property
    def sentence(self) -> str:
        """The stretch in words, for a file's notes and the page."""
        why = (
            "to start from rest"
            if self.start
            else "to come to rest"
            if self.end
            else "to stay within the joints' velocity and acceleration limits"
        )
        return (
            f"slowed from {self.t0:.2f} s to {self.t1:.2f} s of the source by "
            f"{self.added:.2f} s, {why}"
        )


@dataclass(frozen=True)
class PacedPath:
    """A path timed at its source's pace where the robot's limits allow.

    Attributes:
        times, q: the samples (s from 0; rad), at rest at both ends.
        source_seconds: how long the source took.
        slowdowns: where the robot runs slower than the source, in the source's time.
    """

    times: np.ndarray
    q: np.ndarray
    source_seconds: float
    slowdowns: tuple[Slowdown, ...]


def _thin(q: np.ndarray, tolerance: float) -> np.ndarray:
    """Indices of the waypoints kept (Ramer-Douglas-Peucker in joint space, max-norm)."""
    keep = np.zeros(len(q), dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, len(q) - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        s = np.linspace(0.0, 1.0, b - a + 1)[1:-1, None]
        line = q[a] + s * (q[b] - q[a])
        error = np.abs(q[a + 1 : b] - line).max(axis=1)
        k = int(np.argmax(error))
        if error[k] > tolerance:
            mid = a + 1 + k
            keep[mid] = True
            stack += [(a, mid), (mid, b)]
    return np.flatnonzero(keep)


def _checked(rate_hz: float, fraction: float) -> None:
    if not (np.isfinite(rate_hz) and rate_hz > 0):
        raise ExportError(
            f"The rate is {rate_hz!r} Hz; give a positive number of samples a second."
        )
    if not 0 < fraction <= 1:
        raise ExportError(f"The limit fraction is {fraction!r}; give a number in (0, 1].")


def _waypoints(q: np.ndarray, tolerance: float) -> np.ndarray:
    """The rows of ``q`` the timing passes through: moving on, thinned within ``tolerance``."""
    kept = _moving(q, np.arange(len(q)))
    # thinned, a path that comes back within the tolerance can leave a step of zero length
    return _moving(q, kept[_thin(q[kept], tolerance)])


def _timed(
    robot: RobotArm,
    q: np.ndarray,
    kept: np.ndarray,
    rate_hz: float,
    fraction: float,
    pace: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """TOPP-RA through the waypoints ``q[kept]``, timed again with a smaller share of the limits
    while the samples still exceed them between its grid points; then held at rest one sample
    period at each end, so the samples themselves start and end at zero velocity."""
    from ._topp import GRID_TURN_RAD, topp  # imports toppra: seconds, so only when timing

    turn = GRID_TURN_RAD
    times, samples, at = topp(robot, q[kept], rate_hz, fraction, turn, kept, pace)
    for _ in range(RETIME_TRIES - 1):
        if within_limits(robot, times, samples):
            break
        fraction *= RETIME_FACTOR
        turn /= 4
        times, samples, at = topp(robot, q[kept], rate_hz, fraction, turn, kept, pace)
    period = 1.0 / rate_hz
    times = np.r_[0.0, times + period, times[-1] + 2 * period]
    samples = np.vstack([samples[:1], samples, samples[-1:]])
    return times, samples, at + period


def time_path(
    robot: RobotArm,
    q: np.ndarray,
    rate_hz: float,
    *,
    fraction: float = LIMIT_FRACTION,
    tolerance: float = PATH_TOLERANCE_RAD,
) -> tuple[np.ndarray, np.ndarray]:
    """The path ``q`` (N, nq) timed by TOPP-RA as fast as the limits allow, sampled at
    ``rate_hz``.

    Args:
        robot: whose velocity and acceleration limits bound the timing.
        q: the path's joint angles (rad), one row per sample.
        rate_hz: the rate of the returned samples.
        fraction: the share of the limits the timing may use (0-1].
        tolerance: how far the thinned path may pass from the given one (rad).

    Returns:
        ``(times (M,), q (M, nq))``, from t = 0 at rest to the end at rest (the first and last
        samples held one period).

    Raises:
        ExportError: a rate or fraction out of range, or a path TOPP-RA cannot time.
    """
    _checked(rate_hz, fraction)
    q = np.asarray(q, dtype=float)
    kept = _waypoints(q, tolerance)
    if len(kept) < 2:  # it never leaves its start by more than STILL_RAD: held still there
        return np.zeros(1), q[kept[:1]].copy()
    times, samples, _ = _timed(robot, q, kept, rate_hz, fraction, None)
    return times, samples


def pace_path(
    robot: RobotArm,
    times: np.ndarray,
    q: np.ndarray,
    rate_hz: float,
    *,
    fraction: float = LIMIT_FRACTION,
    tolerance: float = PATH_TOLERANCE_RAD,
) -> PacedPath:
    """The path ``q`` (N, nq) at the pace its source took (``times``), slower only where the
    robot's limits need it, from rest to rest, sampled at ``rate_hz``.

    Args:
        robot: whose velocity and acceleration limits bound the timing.
        times: when the source was at each row of ``q`` (s, increasing).
        q: the path's joint angles (rad), one row per sample.
        rate_hz: the rate of the returned samples.
        fraction: the share of the limits the timing may use (0-1].
        tolerance: how far the thinned path may pass from the given one (rad).

    Raises:
        ExportError: a rate or fraction out of range, times that do not increase, or a path
            TOPP-RA cannot time.
    """
    _checked(rate_hz, fraction)
    q = np.asarray(q, dtype=float)
    times = np.asarray(times, dtype=float) - float(times[0])
    if times.shape != (len(q),) or not (np.diff(times) > 0).all():
        raise ExportError(
            "The path's times do not increase sample by sample, so its pace is unknown; export "
            "it as fast as the robot's limits allow instead."
        )
    kept = _waypoints(q, tolerance)
    if len(kept) < 2:
        return PacedPath(np.zeros(1), q[kept[:1]].copy(), float(times[-1]), ())
    timed, samples, at = _timed(robot, q, kept, rate_hz, fraction, _pace(times, q, kept))
    return PacedPath(timed, samples, float(times[-1]), _slowdowns(times[kept], at))


def _pace(times: np.ndarray, q: np.ndarray, kept: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The source's pace along the thinned path's arc length, such that the timing spends the
    time the source did on every stretch of it, pauses included.

    Each sample is placed on the thinned path in proportion to the distance it had come between
    two waypoints. The arc is cut in :data:`PACE_PLACES` equal pieces and each is given the time
    the source spent on it: a pause (the person held still, or moved only in ways the robot does
    not follow) counts on the piece where it happened, so it becomes a crawl as long as it, not
    an instant. Each piece's time is spread evenly over the arc the source covers in
    :data:`PACE_WINDOW_S` at its median speed around it (a pace, not one noisy step; the total
    is kept). The pace is never below :data:`SLOWEST_PACE` of the median, so that the timing
    does not stop for good. Returns places (the pieces' middles, rad) and the pace (rad/s)."""
    from ._topp import arc_length

    along = arc_length(q)
    s = np.maximum.accumulate(np.interp(along, along[kept], arc_length(q[kept])))
    total = float(s[-1])
    edges = np.linspace(0.0, total, PACE_PLACES + 1)
    # when the source first reached each edge; the last piece ends with the source
    reached = np.r_[_first_at(s, times, edges[:-1]), times[-1]]
    spent = np.diff(reached)
    piece = total / PACE_PLACES
    moving = spent[spent > 0]
    typical = piece / float(np.median(moving)) if len(moving) else total / float(times[-1])
    width = min(int(PACE_WINDOW_S * typical / piece) // 2, PACE_PLACES // 2 - 1)  # either side
    if width:  # each piece's time spread over its neighbours within the arc, none lost
        index = np.arange(PACE_PLACES)
        share = np.minimum(index + width, PACE_PLACES - 1) - np.maximum(index - width, 0) + 1
        spent = np.convolve(spent / share, np.ones(2 * width + 1), mode="same")
    pace = piece / np.maximum(spent, 1e-12)
    return edges[:-1] + piece / 2, np.maximum(pace, SLOWEST_PACE * typical)


def _first_at(s: np.ndarray, times: np.ndarray, at: np.ndarray) -> np.ndarray:
    """When the source (at places ``s``, non-decreasing, at ``times``) first reached each of
    ``at``: where it stood still at a place, the time it arrived there."""
    i = np.clip(np.searchsorted(s, at, side="left"), 1, len(s) - 1)
    s0, s1, t0, t1 = s[i - 1], s[i], times[i - 1], times[i]
    rise = s1 - s0
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(rise > 0, (at - s0) / rise, 0.0)
    return t0 + np.clip(share, 0.0, 1.0) * (t1 - t0)


def _slowdowns(source: np.ndarray, robot: np.ndarray) -> tuple[Slowdown, ...]:
    """The runs of steps between waypoints the robot takes longer over than the source did."""
    added = np.diff(robot) - np.diff(source)
    added[0] += robot[0] - source[0]  # the held first sample: part of starting from rest
    slow = added > SLOWED_SECONDS / 4
    found = []
    k = 0
    while k < len(slow):
        if not slow[k]:
            k += 1
            continue
        end = k
        while end + 1 < len(slow) and slow[end + 1]:
            end += 1
        total = float(added[k : end + 1].sum())
        if total >= SLOWED_SECONDS:
            first, last = k == 0, end == len(slow) - 1
            found.append(
                Slowdown(float(source[k]), float(source[end + 1]), total, first, last and not first)
            )
        k = end + 1
    return tuple(found)


def _moving(q: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The ``rows`` of ``q`` that move on from the last one kept by more than
    :data:`STILL_RAD` (a path's length must grow by a step TOPP-RA can time). The last row
    stays (in place of the one kept before it, when that is nearer): the path ends where given."""
    if len(rows) == 0:
        return rows
    kept = [rows[0]]
    for row in rows[1:]:
        if np.abs(q[row] - q[kept[-1]]).max() > STILL_RAD:
            kept.append(row)
    if len(kept) > 1 and kept[-1] != rows[-1]:  # end where given, not a step short of it
        kept[-1] = rows[-1]
        while len(kept) > 2 and np.abs(q[kept[-1]] - q[kept[-2]]).max() <= STILL_RAD:
            del kept[-2]
    return np.asarray(kept)


def within_limits(robot: RobotArm, times: np.ndarray, q: np.ndarray) -> bool:
    """Whether the samples' finite-difference velocities and accelerations are within limits."""
    if len(times) < 3:
        return True
    from ._safety import differences  # imports studio.motion: only when checking

    velocity, acceleration = differences(times, q)
    return bool(
        (np.abs(velocity) <= robot.velocity).all()
        and (np.abs(acceleration) <= robot.acceleration).all()
    )
