"""Time-parametrisation: a joint path timed as fast as the robot's limits allow, then sampled.

A policy rollout or a demonstration is a *path* (where the joints go); how fast it is run is set
here with TOPP-RA (``toppra``): the time-optimal timing along the path that keeps every joint's
velocity and acceleration within a fraction of the URDF's limits. The path is first cleared of
repeated samples and thinned to the waypoints that matter (no sample of the original path is
further than :data:`PATH_TOLERANCE_RAD` from the thinned one, joint by joint), so the capture
noise of a demonstration does not force the arm to crawl. The path through the waypoints (by
arc length) is a cubic spline; where that overshoots a position limit (it did past the Panda's
joint 6 on a sample demonstration), a shape-preserving cubic (PCHIP), which never goes beyond
two consecutive waypoints, is used instead: slower to run (its second derivative jumps at the
waypoints), but within the limits wherever the waypoints are. The timing starts and ends at
rest.

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
GRID_PER_WAYPOINT = 20
"""TOPP-RA grid points per waypoint: it bounds the limits at its grid points only, and 20 keeps
the samples between them within the limits on the first pass for the sample demonstrations (8
did not, and the retiming below then cost a quarter more time)."""
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
    q = _moving(np.asarray(q, dtype=float))
    if len(q) < 2:
        return np.zeros(1), q[:1].copy()
    # thinning can leave a path that comes back to a waypoint with a step of zero length
    q = _moving(q[_thin(q, tolerance)])
    if len(q) < 2:
        return np.zeros(1), q[:1].copy()
    times, samples = _toppra(robot, q, rate_hz, fraction)
    for _ in range(RETIME_TRIES - 1):
        if within_limits(robot, times, samples):
            break
        fraction *= RETIME_FACTOR
        times, samples = _toppra(robot, q, rate_hz, fraction)
    return times, samples


def _moving(q: np.ndarray) -> np.ndarray:
    """``q`` without the samples that repeat the one before (a path's length must grow)."""
    return q[np.r_[True, np.abs(np.diff(q, axis=0)).max(axis=1) > 1e-9]] if len(q) else q


def within_limits(robot: RobotArm, times: np.ndarray, q: np.ndarray) -> bool:
    """Whether the samples' finite-difference velocities and accelerations are within limits."""
    if len(times) < 3:
        return True
    velocity, acceleration = differences(times, q)
    return bool(
        (np.abs(velocity) <= robot.velocity).all()
        and (np.abs(acceleration) <= robot.acceleration).all()
    )


def _toppra(
    robot: RobotArm, q: np.ndarray, rate_hz: float, fraction: float
) -> tuple[np.ndarray, np.ndarray]:
    import toppra
    import toppra.algorithm
    import toppra.constraint

    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))]
    s /= s[-1]
    toppra.setup_logging("WARNING")
    path = toppra.SplineInterpolator(s, q, bc_type="clamped")
    dense = path(np.linspace(0.0, 1.0, max(400, GRID_PER_WAYPOINT * len(q))))
    if (dense < robot.lower).any() or (dense > robot.upper).any():
        path = _shape_preserving_path(s, q)
    velocity = fraction * robot.velocity
    acceleration = fraction * robot.acceleration
    instance = toppra.algorithm.TOPPRA(
        [
            toppra.constraint.JointVelocityConstraint(np.column_stack([-velocity, velocity])),
            toppra.constraint.JointAccelerationConstraint(
                np.column_stack([-acceleration, acceleration])
            ),
        ],
        path,
        gridpoints=np.linspace(0.0, 1.0, max(400, GRID_PER_WAYPOINT * len(q))),
        parametrizer="ParametrizeConstAccel",
    )
    trajectory = instance.compute_trajectory()
    if trajectory is None:
        raise ExportError(
            f"The path cannot be timed within the {robot.spec.title}'s limits (TOPP-RA found no "
            "feasible timing); export it with --unchecked to inspect it."
        )
    duration = float(trajectory.duration)
    # whole sample periods, the last one held at the end (at rest): the samples stay on the
    # rate's grid, which players and LeRobot's timestamp checks expect
    times = np.arange(int(np.ceil(duration * rate_hz - 1e-9)) + 1) / rate_hz
    return times, np.asarray(trajectory(np.minimum(times, duration)), dtype=float)


def _shape_preserving_path(s: np.ndarray, q: np.ndarray) -> object:  # a toppra path
    """A TOPP-RA geometric path through ``q`` at ``s`` that stays between its waypoints."""
    from scipy.interpolate import PchipInterpolator
    from toppra.interpolator import AbstractGeometricPath

    class ShapePreservingPath(AbstractGeometricPath):  # type: ignore[misc]
        def __init__(self) -> None:
            self.curves = [PchipInterpolator(s, q, axis=0)]
            self.curves += [self.curves[0].derivative(1), self.curves[0].derivative(2)]

        def __call__(self, path_positions: object, order: int = 0) -> np.ndarray:
            return self.curves[order](path_positions)

        @property
        def dof(self) -> int:
            return int(q.shape[1])

        @property
        def path_interval(self) -> np.ndarray:
            return np.array([s[0], s[-1]])

        @property
        def waypoints(self) -> tuple[np.ndarray, np.ndarray]:
            return s, q

    return ShapePreservingPath()
