"""Time-parametrisation: a joint path timed as fast as the robot's limits allow, then sampled.

A policy rollout or a demonstration is a *path* (where the joints go); how fast it is run is set
here with TOPP-RA (``toppra``): the time-optimal timing along the path that keeps every joint's
velocity and acceleration within a fraction of the URDF's limits. The path is first cleared of
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

import numpy as np

from studio.kinematics import RobotArm

from ._errors import ExportError
from ._safety import differences

PATH_TOLERANCE_RAD = np.radians(0.5)
"""How far (rad, per joint) the thinned path may pass from a sample of the original one."""
LIMIT_FRACTION = 0.8
"""The share of each velocity and acceleration limit the timing uses by default: headroom for
the controller's tracking and the spline's sampling, checked afterwards against the full limits."""
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


def time_path(
    robot: RobotArm,
    q: np.ndarray,
    rate_hz: float,
    *,
    fraction: float = LIMIT_FRACTION,
    tolerance: float = PATH_TOLERANCE_RAD,
) -> tuple[np.ndarray, np.ndarray]:
    """The path ``q`` (N, nq) timed by TOPP-RA and sampled at ``rate_hz``.

    Args:
        robot: whose velocity and acceleration limits bound the timing.
        q: the path's joint angles (rad), one row per sample.
        rate_hz: the rate of the returned samples.
        fraction: the share of the limits the timing may use (0-1].
        tolerance: how far the thinned path may pass from the given one (rad).

    Returns:
        ``(times (M,), q (M, nq))``, from t = 0 at rest to the end at rest.

    Raises:
        ExportError: a rate or fraction out of range, or a path TOPP-RA cannot time.
    """
    if not (np.isfinite(rate_hz) and rate_hz > 0):
        raise ExportError(
            f"The rate is {rate_hz!r} Hz; give a positive number of samples a second."
        )
    if not 0 < fraction <= 1:
        raise ExportError(f"The limit fraction is {fraction!r}; give a number in (0, 1].")
    q = np.asarray(q, dtype=float)
    kept = _moving(q, np.arange(len(q)))
    # thinned, a path that comes back within the tolerance can leave a step of zero length
    kept = _moving(q, kept[_thin(q[kept], tolerance)])
    if len(kept) < 2:  # it never leaves its start by more than STILL_RAD: held still there
        return np.zeros(1), q[kept[:1]].copy()
    from ._topp import GRID_TURN_RAD, topp  # imports toppra: seconds, so only when timing

    turn = GRID_TURN_RAD
    times, samples = topp(robot, q[kept], rate_hz, fraction, turn, kept)
    for _ in range(RETIME_TRIES - 1):
        if within_limits(robot, times, samples):
            break
        fraction *= RETIME_FACTOR
        turn /= 4
        times, samples = topp(robot, q[kept], rate_hz, fraction, turn, kept)
    return times, samples


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
    velocity, acceleration = differences(times, q)
    return bool(
        (np.abs(velocity) <= robot.velocity).all()
        and (np.abs(acceleration) <= robot.acceleration).all()
    )
