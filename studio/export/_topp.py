"""TOPP-RA (``toppra``) on a path through waypoints, set up so that its LP solver stays exact.

:func:`studio.export.time_path` thins a path to its waypoints; this times the curve through
them. Imported only when a path is timed: ``toppra`` takes seconds to import.

What makes TOPP-RA time every path within the limits, where a plain call failed on one random
path in a hundred (found by ``tests/export/test_safety.py``'s property test):

- **The path parameter is the joint-space arc length** (rad), not a share of the path in [0, 1]:
  on a path of a fraction of a degree, the share's derivatives are tiny and the path speed's
  square runs into the millions, beyond what the solver resolves.
- **Each LP starts from the bounds the limits imply.** TOPP-RA's solver (Seidel's 2-D LP) starts
  every grid point's LP from a path acceleration of 1e8 unless a constraint bounds it; a joint
  whose slope along the path is small there (near a waypoint where it turns back, where a
  shape-preserving curve makes it exactly zero) then gives a constraint row that loses every
  digit, and the solver reports the path uncontrollable. :class:`ImpliedBounds` hands it the
  path speed and acceleration bounds that the joint limits already imply: the feasible set is
  unchanged, only the LPs' starting box is of the right scale.
- **The grid follows the path's bends.** TOPP-RA bounds the limits at its grid points only; it
  puts a point on every waypoint (where a shape-preserving curve's second derivative jumps) and
  halves its steps where the path turns sharply, so the samples between grid points stay within
  the limits too.
- **The curve's range is found exactly** (:func:`curve_range`), so a spline that bulges past a
  position limit between waypoints is always replaced by one that cannot.
- **A last resort:** where TOPP-RA still finds no timing, the path is timed in parts that stop at
  its slowest waypoint (:func:`topp`); no random path has needed it since the above.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import toppra
import toppra.algorithm
import toppra.constraint
from scipy.interpolate import CubicSpline, PchipInterpolator, PPoly
from toppra.interpolator import AbstractGeometricPath

from studio.kinematics import RobotArm

from ._errors import ExportError

GRID_PER_WAYPOINT = 20
"""TOPP-RA grid points per step between waypoints: it bounds the limits at its grid points only,
and 20 keeps the samples between them within the limits on the first pass for the sample
demonstrations (8 did not, and the retiming then cost a quarter more time)."""
MIN_GRIDPOINTS = 400
"""TOPP-RA grid points along a path of few waypoints."""
GRID_TURN_RAD = 0.1
"""The most a joint's slope along the path (rad per rad of arc length) may change across one
step of the grid: where the path bends sharply, its steps are halved until it changes no more.
Without it, one random path in 300 came out over an acceleration limit between grid points
after every retiming; at 0.1 none in 5,000, for a third more computing time on the sample
demonstrations."""
MAX_GRID_HALVINGS = 16
"""How many times a grid step may be halved where the path bends."""
NEGLIGIBLE_SLOPE = 1e-9
"""A path derivative (rad per rad of arc length, first or second) below this is zero: rounding
noise of the curve, which would only hand the solver rows of no meaning."""
BOUND_CEILING = 1e8
"""The path speed squared and the path acceleration are never bounded above this (the solver's
own default), where no joint limit bounds them (a joint that does not move)."""


class PiecewiseCubicPath(AbstractGeometricPath):  # type: ignore[misc]
    """A TOPP-RA geometric path: a piecewise cubic ``curve`` through the waypoints ``q`` (N, nq)
    at arc lengths ``s`` (N,)."""

    def __init__(self, s: np.ndarray, q: np.ndarray, curve: PPoly) -> None:
        self._s, self._q = s, q
        self.curves = [curve, curve.derivative(1), curve.derivative(2)]

    def __call__(self, path_positions: Any, order: int = 0) -> np.ndarray:
        value = np.asarray(self.curves[order](path_positions))
        if order:
            value = np.where(np.abs(value) < NEGLIGIBLE_SLOPE, 0.0, value)
        return value

    @property
    def dof(self) -> int:
        return int(self._q.shape[1])

    @property
    def path_interval(self) -> np.ndarray:
        return np.array([self._s[0], self._s[-1]])

    @property
    def waypoints(self) -> tuple[np.ndarray, np.ndarray]:
        return self._s, self._q


class ImpliedBounds(toppra.constraint.LinearConstraint):  # type: ignore[misc]
    """The bounds on the path speed squared ``x`` and the path acceleration ``u`` that joint
    velocity and acceleration limits imply at each grid point; a constraint that changes nothing
    but the scale the solver's LPs start from.

    A joint that moves along the path (slope ``d1 != 0``) bounds ``x <= (v / d1)^2``; one that
    only curves there (``d1 = 0``, ``d2 != 0``) bounds ``x <= a / d2``. Then ``|d1 u + d2 x| <= a``
    gives ``|u| <= (a + |d2| x) / |d1|`` for every joint that moves.
    """

    def __init__(self, velocity: np.ndarray, acceleration: np.ndarray) -> None:
        super().__init__()
        self._velocity, self._acceleration = velocity, acceleration

    def compute_constraint_params(
        self, path: AbstractGeometricPath, gridpoints: np.ndarray, *args: Any, **kwargs: Any
    ) -> tuple[None, None, None, None, None, np.ndarray, np.ndarray]:
        d1, d2 = np.abs(path(gridpoints, 1)), np.abs(path(gridpoints, 2))
        moving = d1 > 0
        with np.errstate(divide="ignore", invalid="ignore"):
            x_joint = np.where(
                moving,
                (self._velocity / d1) ** 2,
                np.where(d2 > 0, self._acceleration / d2, np.inf),
            )
            x_high = np.minimum(x_joint.min(axis=1), BOUND_CEILING)
            u_joint = np.where(moving, (self._acceleration + d2 * x_high[:, None]) / d1, np.inf)
        u_high = np.minimum(u_joint.min(axis=1), BOUND_CEILING)
        zero = np.zeros(len(gridpoints))
        return (
            None,
            None,
            None,
            None,
            None,
            np.column_stack([-u_high, u_high]),
            np.column_stack([zero, x_high]),
        )


Pace = tuple[np.ndarray, np.ndarray]
"""The source's own pace along a path: places on it (arc length, rad, increasing) and the path
speed there (rad/s)."""


class PaceBound(toppra.constraint.LinearConstraint):  # type: ignore[misc]
    """The path speed never above the source's own there: ``x <= pace(s)^2`` (the person's pace,
    :data:`Pace`). TOPP-RA's fastest timing under it runs at the source's pace wherever the limits
    allow it, and slower only where they do not."""

    def __init__(self, pace: Pace) -> None:
        super().__init__()
        self._s, self._speed = pace

    def compute_constraint_params(
        self, path: AbstractGeometricPath, gridpoints: np.ndarray, *args: Any, **kwargs: Any
    ) -> tuple[None, None, None, None, None, None, np.ndarray]:
        speed = np.interp(gridpoints, self._s, self._speed)
        x_high = np.minimum(speed**2, BOUND_CEILING)
        return None, None, None, None, None, None, np.column_stack([np.zeros_like(x_high), x_high])


def arc_length(q: np.ndarray) -> np.ndarray:
    """The path parameter at each waypoint: the joint-space distance travelled (rad)."""
    return np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))]


def curve_range(curve: PPoly) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest value each joint takes along a piecewise cubic, exactly: each
    piece's ends and the roots of its derivative."""
    c = curve.c  # (4, pieces, joints), in powers of (s - the piece's start)
    width = np.diff(curve.x)[:, None] * np.ones(c.shape[2])
    a, b, d = 3 * c[0], 2 * c[1], c[2]  # the derivative: a x^2 + b x + d
    with np.errstate(divide="ignore", invalid="ignore"):
        root = np.sqrt(np.maximum(b * b - 4 * a * d, 0.0))
        candidates = [(-b + root) / (2 * a), (-b - root) / (2 * a), -d / b]
    at = np.stack([np.zeros_like(width), width, *candidates])
    at = np.clip(np.nan_to_num(at, nan=0.0, posinf=0.0, neginf=0.0), 0.0, width)
    value = ((c[0] * at + c[1]) * at + c[2]) * at + c[3]
    return value.min(axis=(0, 1)), value.max(axis=(0, 1))


def waypoint_curve(robot: RobotArm, s: np.ndarray, q: np.ndarray) -> PPoly:
    """The curve through the waypoints: a cubic spline, or where that would pass a position
    limit (it did past the Panda's joint 6 on a sample demonstration), a shape-preserving cubic
    (PCHIP), which never goes beyond two consecutive waypoints: slower to run (its second
    derivative jumps at the waypoints), but within the limits wherever the waypoints are."""
    curve: PPoly = CubicSpline(s, q, axis=0, bc_type="clamped")
    low, high = curve_range(curve)
    if (low < robot.lower).any() or (high > robot.upper).any():
        curve = PchipInterpolator(s, q, axis=0)
    return curve


def gridpoints(path: PiecewiseCubicPath, s: np.ndarray, turn: float) -> np.ndarray:
    """TOPP-RA's grid: every waypoint, each step between them cut in :data:`GRID_PER_WAYPOINT`
    (at least :data:`MIN_GRIDPOINTS` in all), then steps halved until no joint's slope along the
    path changes by more than ``turn`` across one."""
    per_step = max(GRID_PER_WAYPOINT, int(np.ceil(MIN_GRIDPOINTS / (len(s) - 1))))
    fractions = np.linspace(0.0, 1.0, per_step, endpoint=False)
    grid = np.r_[(s[:-1, None] + np.diff(s)[:, None] * fractions).ravel(), s[-1]]
    for _ in range(MAX_GRID_HALVINGS):
        step = np.diff(grid)
        middle = grid[:-1] + step / 2
        bent = np.abs(path(middle, 2)).max(axis=1) * step > turn
        if not bent.any():
            break
        grid = np.sort(np.r_[grid, middle[bent]])
    return grid


def topp(
    robot: RobotArm,
    q: np.ndarray,
    rate_hz: float,
    fraction: float,
    turn: float,
    samples: np.ndarray | None = None,
    pace: Pace | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The waypoints ``q`` (N >= 2, no two alike in a row) timed by TOPP-RA within ``fraction``
    of the robot's limits, on a grid of ``turn`` (:func:`gridpoints`), sampled at ``rate_hz``.

    Where TOPP-RA finds no timing for the curve through all of them, the path is cut at the
    waypoint where the curve is slowest (a cusp: every joint turns back there, so the arm stops
    there anyway) and each part is timed from rest to rest, down to single straight steps.

    Args:
        samples: each waypoint's sample in the path given to the export, to name it.
        pace: the source's own pace along the waypoints' arc length (:data:`Pace`): the timing
            is then never faster than the source (:class:`PaceBound`); None: as fast as the
            limits allow.

    Returns:
        ``(times, samples, at)``: the sample times and joints, and when the timing passes each
        waypoint.

    Raises:
        ExportError: TOPP-RA found no timing for one step between two waypoints (never seen on
            a step longer than :data:`studio.export._timing.STILL_RAD`).
    """
    samples = np.arange(len(q)) if samples is None else samples
    velocity = fraction * robot.velocity
    acceleration = fraction * robot.acceleration
    toppra.setup_logging("ERROR")  # a failure is handled here, and said in one sentence
    parts = _timed_parts(robot, q, velocity, acceleration, turn, samples, pace)
    ends = np.cumsum([part.duration for part in parts])
    # whole sample periods, the last one held at the end (at rest): the samples stay on the
    # rate's grid, which players and LeRobot's timestamp checks expect
    times = np.arange(int(np.ceil(ends[-1] * rate_hz - 1e-9)) + 1) / rate_hz
    which = np.minimum(np.searchsorted(ends, times, side="right"), len(parts) - 1)
    starts = np.r_[0.0, ends[:-1]]
    out = np.empty((len(times), q.shape[1]))
    for k, part in enumerate(parts):
        at = which == k
        if at.any():
            out[at] = part(np.clip(times[at] - starts[k], 0.0, part.duration))
    # when each part passes its waypoints (ParametrizeConstAccel keeps its grid's path
    # positions and times); a waypoint where two parts meet is passed when the first ends
    passed = []
    for k, (start, part) in enumerate(zip(starts, parts, strict=True)):
        at = start + np.interp(part._path.waypoints[0], part._ss, part._ts)
        passed.append(at if k == len(parts) - 1 else at[:-1])
    return times, out, np.concatenate(passed)


def _timed_parts(
    robot: RobotArm,
    q: np.ndarray,
    velocity: np.ndarray,
    acceleration: np.ndarray,
    turn: float,
    samples: np.ndarray,
    pace: Pace | None = None,
) -> list[Any]:  # toppra trajectories, each from rest to rest
    """TOPP-RA's trajectories along ``q``, one, or one per part where the whole fails."""
    s = arc_length(q)
    curve = waypoint_curve(robot, s, q)
    path = PiecewiseCubicPath(s, q, curve)
    constraints = [
        toppra.constraint.JointVelocityConstraint(np.column_stack([-velocity, velocity])),
        toppra.constraint.JointAccelerationConstraint(
            np.column_stack([-acceleration, acceleration])
        ),
        ImpliedBounds(velocity, acceleration),
    ]
    if pace is not None:
        constraints.append(PaceBound(pace))
    instance = toppra.algorithm.TOPPRA(
        constraints,
        path,
        gridpoints=gridpoints(path, s, turn),
        parametrizer="ParametrizeConstAccel",
    )
    trajectory = instance.compute_trajectory()
    if trajectory is not None:
        return [trajectory]
    if len(q) == 2:
        raise ExportError(
            f"The path cannot be timed from its sample {samples[0]} to its sample {samples[1]} "
            f"within the {robot.spec.title}'s limits (TOPP-RA found no timing for that step); "
            "smooth the path there and export it again."
        )
    cut = 1 + int(np.argmin(np.abs(curve(s[1:-1], 1)).max(axis=1)))
    first = second = None
    if pace is not None:  # the second part's arc length starts from 0 at the cut
        first, second = pace, (pace[0] - s[cut], pace[1])
    return _timed_parts(
        robot, q[: cut + 1], velocity, acceleration, turn, samples[: cut + 1], first
    ) + _timed_parts(robot, q[cut:], velocity, acceleration, turn, samples[cut:], second)
