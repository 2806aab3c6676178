"""Likeness: how much a policy's motion looks like the demonstration it was taught from.

The paper's claim is that a demonstration teaches the *character* of a motion: its smoothness,
how the motion is spread over the joints, its execution time. These are the numbers that judge
it, each computed for the policy and, beside it, for the demonstration itself:

- **DTW** (dynamic time warping) in joint space, per sample: the mean Euclidean joint distance
  (rad) between the two paths along the warping that minimises the total distance; the total is
  divided by the number of aligned pairs, so a long rollout is not penalised for its length.
- **Discrete Fréchet distance** of the tool paths (m; Eiter & Mannila 1994): the shortest leash
  that lets a walker on each path reach its end, neither going back.
- **LDLJ**, the log dimensionless jerk (Balasubramanian, Melendez-Calderon, Roby-Brami & Burdet,
  J NeuroEng Rehabil 2015), in its velocity form, on the *tool's* (the hand's) velocity ``dx/dt``
  (``v_peak`` the peak of its norm), low-passed at :data:`LDLJ_CUTOFF_HZ` first:
  ``-ln((t2 - t1)^3 / v_peak^2 * integral |d^3 x / dt^3|^2 dt)``. Higher (less negative) is
  smoother; it does not depend on the motion's amplitude or duration. Jerk is a third
  derivative: unfiltered, and on the joints, it measured the tape's noise more than the motion
  (:data:`LDLJ_CUTOFF_HZ` gives the figures).
- **SPARC**, the spectral arc length of the tool's speed profile (Balasubramanian et al. 2015,
  the measure they recommend beside LDLJ): the length of its normalised Fourier magnitude
  spectrum up to 10 Hz. Nearer 0 is smoother. The tape's noise barely moves it (a median 0.5%
  over 20 simulated reaches, at most 11%), and it tells a bell-shaped speed profile (a
  minimum-jerk reach: -1.40) from a constant pace that starts and stops abruptly (a learned
  rollout: about -2.5), which LDLJ can score alike.
- **Joint shares**: each joint's travel ``sum |dq_j|`` over the total, compared with the
  demonstration's by the Jensen-Shannon divergence (bits, 0 = same spread, 1 = disjoint).
- **Moving together**: the share of the moving time (any joint faster than
  :data:`MOVING_SPEED_FRACTION` of the path's fastest joint speed) in which two or more joints
  move.
- **Duration** (s).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit

from studio.kinematics import Puma560

from ..._numbers import is_number
from .._errors import LearningError
from ..tasks._reach import tool_positions

MOVING_SPEED_FRACTION = 0.05
"""A joint counts as moving when its speed exceeds this fraction of the path's peak joint speed
(relative, so a slow and a fast motion are judged alike; 5% ignores sensor jitter and the slow
tail of a settling arm)."""

LDLJ_CUTOFF_HZ = 10.0
"""The low-pass cutoff (Hz) :func:`ldlj` applies before it differentiates: a 2nd-order Butterworth
run forward and back (zero lag), the usual treatment of recorded positions before their
derivatives (Winter, Biomechanics and Motor Control of Human Movement, 2009); voluntary reaching
lies well below it. Chosen by measurement on the card's tool path, over 20 simulated reaches each
recorded with and without the tape's sensor noise (the same motion, its physiological tremor
kept): with this cutoff the noise moved the LDLJ by a median 11% (at most 15%); unfiltered by 28%
on the tool path and by 52% on the six joints (the wrist joints carry the fit's noise near the
Puma560's wrist singularity); at 3-6 Hz by up to 22-33% (reaching's own content is cut), at 15 Hz
by 13%. ``python benchmarks/bench_likeness.py --noise`` measures it."""

SPARC_CUTOFF_HZ = 10.0
"""The highest frequency (Hz) of the speed's spectrum :func:`sparc` measures (Balasubramanian et
al. 2015 use 10 Hz for reaching: voluntary movement lies below it)."""
SPARC_THRESHOLD = 0.05
"""... and the share of the spectrum's peak below which its tail is left out (theirs too)."""

ToolPositions = Callable[[np.ndarray], np.ndarray]
"""Joint angles ``(N, joints)`` to tool positions ``(N, 3)`` in metres (forward kinematics)."""


@njit(cache=True, nogil=True)
def _dtw(a: np.ndarray, b: np.ndarray) -> tuple[float, int]:  # pragma: no cover - numba
    """Total cost of the optimal warping and the number of pairs on it (two rows of memory)."""
    n, m = a.shape[0], b.shape[0]
    cost, prev_cost = np.full(m + 1, np.inf), np.full(m + 1, np.inf)
    length, prev_length = np.zeros(m + 1, np.int64), np.zeros(m + 1, np.int64)
    prev_cost[0] = 0.0
    for i in range(1, n + 1):
        cost[0] = np.inf
        for j in range(1, m + 1):
            d = 0.0
            for k in range(a.shape[1]):
                d += (a[i - 1, k] - b[j - 1, k]) ** 2
            best, steps = prev_cost[j - 1], prev_length[j - 1]
            if prev_cost[j] < best:
                best, steps = prev_cost[j], prev_length[j]
            if cost[j - 1] < best:
                best, steps = cost[j - 1], length[j - 1]
            cost[j] = best + math.sqrt(d)
            length[j] = steps + 1
        cost, prev_cost = prev_cost, cost
        length, prev_length = prev_length, length
    return prev_cost[m], prev_length[m]


@njit(cache=True, nogil=True)
def _frechet(a: np.ndarray, b: np.ndarray) -> float:  # pragma: no cover - numba
    """Eiter & Mannila's coupling recursion, two rows of memory."""
    n, m = a.shape[0], b.shape[0]
    row, prev = np.empty(m), np.empty(m)
    for i in range(n):
        for j in range(m):
            d = 0.0
            for k in range(a.shape[1]):
                d += (a[i, k] - b[j, k]) ** 2
            d = math.sqrt(d)
            if i == 0 and j == 0:
                row[j] = d
            elif i == 0:
                row[j] = max(row[j - 1], d)
            elif j == 0:
                row[j] = max(prev[j], d)
            else:
                row[j] = max(min(prev[j], prev[j - 1], row[j - 1]), d)
        row, prev = prev, row
    return prev[m - 1]


def _paths(a: np.ndarray, b: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Both paths as finite float ``(N, D)`` arrays of the same width, at least one sample each."""
    out = []
    for name, x in (("first", a), ("second", b)):
        x = np.asarray(x, dtype=np.float64)
        if x.ndim == 1:
            x = x[:, None]
        if x.ndim != 2 or x.shape[0] < 1 or not np.all(np.isfinite(x)):
            raise LearningError(
                f"The {name} {what} has shape {x.shape} or non-finite values; give an (N, D) array of finite numbers with N >= 1."
            )
        out.append(np.ascontiguousarray(x))
    if out[0].shape[1] != out[1].shape[1]:
        raise LearningError(
            f"The {what}s have {out[0].shape[1]} and {out[1].shape[1]} columns; compare paths of the same joints."
        )
    return out[0], out[1]


def dtw_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Dynamic-time-warping distance per aligned sample (units of the paths, e.g. rad).

    Args:
        a: path ``(N, D)`` (or ``(N,)``).
        b: path ``(M, D)``.

    Returns:
        The smallest total Euclidean distance over monotone alignments of every sample of both
        paths, divided by the number of aligned pairs.
    """
    a, b = _paths(a, b, "path")
    total, pairs = _dtw(a, b)
    return float(total / pairs)


def frechet_distance(a: np.ndarray, b: np.ndarray) -> float:
    """The discrete Fréchet distance between two polylines ``(N, D)`` and ``(M, D)``."""
    a, b = _paths(a, b, "path")
    return float(_frechet(a, b))


def _times(times: np.ndarray, n: int) -> np.ndarray:
    t = np.asarray(times, dtype=np.float64).reshape(-1)
    if t.shape != (n,) or not np.all(np.isfinite(t)) or (n > 1 and np.any(np.diff(t) <= 0)):
        raise LearningError(
            f"The times have shape {t.shape} for {n} samples; give one increasing time per sample."
        )
    return t


def _samples(times: np.ndarray, path: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A smoothness measure's input: the checked times and the path as an ``(N, D)`` array."""
    x = np.asarray(path, dtype=np.float64)
    x = x[:, None] if x.ndim == 1 else x
    return _times(times, x.shape[0]), x


def _still(x: np.ndarray) -> bool:
    """Fewer than 4 samples, or no motion: no smoothness to measure (NaN)."""
    return x.shape[0] < 4 or not np.any(np.diff(x, axis=0))


def _mean_rate(t: np.ndarray) -> float:
    """Samples per second over ``t``."""
    return (t.shape[0] - 1) / (t[-1] - t[0])


def low_pass(times: np.ndarray, x: np.ndarray, cutoff_hz: float) -> np.ndarray:
    """``x`` ``(N, D)`` through a zero-lag Butterworth (2nd order, forward and back) at
    ``cutoff_hz``, at the samples' mean rate; unchanged when that rate's Nyquist frequency is not
    above the cutoff (nothing to remove)."""
    rate = _mean_rate(times)
    if cutoff_hz >= rate / 2:
        return x
    # imported here: scipy.signal costs every process that imports the learners (a sweep's
    # workers, each studio verb) over a second of CPU, and most never filter a path
    from scipy.signal import butter, sosfiltfilt

    sos = butter(2, cutoff_hz, fs=rate, output="sos")
    return sosfiltfilt(sos, x, axis=0, padlen=min(x.shape[0] - 1, 3 * (2 * sos.shape[0] + 1)))


def ldlj(times: np.ndarray, q: np.ndarray, cutoff_hz: float | None = LDLJ_CUTOFF_HZ) -> float:
    """Log dimensionless jerk of a path's velocity (Balasubramanian et al. 2015).

    ``-ln((t2 - t1)^3 / v_peak^2 * integral |x'''(t)|^2 dt)``, with derivatives taken by
    second-order finite differences on the sample times, after :func:`low_pass` at
    ``cutoff_hz``.

    Args:
        times: sample times ``(N,)`` (s), increasing.
        q: the path ``(N, D)`` (or ``(N,)``): tool positions (the card's), or joint angles.
        cutoff_hz: the low-pass cutoff (:data:`LDLJ_CUTOFF_HZ`), or None for the samples as
            they are.

    Returns:
        The LDLJ (higher is smoother; a minimum-jerk reach scores about -5.3), NaN for a path
        that does not move or has fewer than 4 samples.

    Raises:
        LearningError: bad times, or a cutoff that is not a positive number.
    """
    t, q = _samples(times, q)
    if cutoff_hz is not None and (not is_number(cutoff_hz) or cutoff_hz <= 0):
        raise LearningError(f"cutoff_hz is {cutoff_hz!r}; give a positive frequency or None.")
    if _still(q):
        return math.nan
    if cutoff_hz is not None:
        q = low_pass(t, q, float(cutoff_hz))
    velocity = np.gradient(q, t, axis=0)
    v_peak = float(np.linalg.norm(velocity, axis=1).max())
    if v_peak <= 0.0:
        return math.nan
    jerk = np.gradient(np.gradient(velocity, t, axis=0), t, axis=0)
    squared = (jerk**2).sum(axis=1)
    integral = float(np.sum(0.5 * (squared[1:] + squared[:-1]) * np.diff(t)))
    duration = t[-1] - t[0]
    if integral <= 0.0:
        return math.nan
    return -math.log(duration**3 / v_peak**2 * integral)


def sparc(
    times: np.ndarray,
    path: np.ndarray,
    cutoff_hz: float = SPARC_CUTOFF_HZ,
    threshold: float = SPARC_THRESHOLD,
) -> float:
    """Spectral arc length of a path's speed profile (Balasubramanian et al. 2015).

    The speed ``|dx/dt|`` (finite differences) at the samples' mean rate, zero-padded to
    ``2^(ceil(log2 N) + 4)`` samples, its Fourier magnitude normalised by its largest; from the
    first to the last frequency up to ``cutoff_hz`` where it exceeds ``threshold``, minus the
    length of that curve with the frequency axis scaled to [0, 1].

    Returns:
        The SPARC (higher, nearer 0, is smoother; a minimum-jerk reach scores about -1.4),
        NaN for a path that does not move or has fewer than 4 samples.

    Raises:
        LearningError: bad times, a cutoff that is not a positive frequency, or a threshold
            outside (0, 1).
    """
    if not is_number(cutoff_hz) or cutoff_hz <= 0:
        raise LearningError(f"cutoff_hz is {cutoff_hz!r}; give a positive frequency.")
    if not is_number(threshold) or not 0 < threshold < 1:
        raise LearningError(
            f"threshold is {threshold!r}; give a share of the largest magnitude, between 0 and 1."
        )
    t, x = _samples(times, path)
    if _still(x):
        return math.nan
    speed = np.linalg.norm(np.gradient(x, t, axis=0), axis=1)
    size = 2 ** (math.ceil(math.log2(x.shape[0])) + 4)
    magnitude = np.abs(np.fft.rfft(speed, size))
    if magnitude.max() <= 0.0:
        return math.nan
    frequency = np.fft.rfftfreq(size, 1.0 / _mean_rate(t))
    keep = frequency <= cutoff_hz
    frequency, magnitude = frequency[keep], magnitude[keep] / magnitude.max()
    above = np.nonzero(magnitude >= threshold)[0]
    frequency = frequency[above[0] : above[-1] + 1]
    magnitude = magnitude[above[0] : above[-1] + 1]
    if frequency.size < 2:
        return 0.0
    step = np.diff(frequency) / (frequency[-1] - frequency[0])
    return -float(np.sum(np.sqrt(step**2 + np.diff(magnitude) ** 2)))


def joint_shares(q: np.ndarray) -> np.ndarray:
    """Each joint's share of the total travel ``sum_t |dq_j|`` (sums to 1; zeros for no motion)."""
    q = np.asarray(q, dtype=np.float64)
    travel = np.abs(np.diff(q, axis=0)).sum(axis=0) if q.shape[0] > 1 else np.zeros(q.shape[1])
    total = travel.sum()
    return travel / total if total > 0 else np.zeros_like(travel)


def js_divergence(p: np.ndarray, q: np.ndarray) -> float:
    """Jensen-Shannon divergence in bits between two distributions (normalised first).

    0 for the same distribution, 1 for disjoint ones; NaN when either is all zeros.
    """
    p = np.asarray(p, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    if p.shape != q.shape or np.any(p < 0) or np.any(q < 0):
        raise LearningError(
            f"The distributions have shapes {p.shape} and {q.shape}; give two of the same length with no negative entries."
        )
    if p.sum() <= 0 or q.sum() <= 0:
        return math.nan
    p, q = p / p.sum(), q / q.sum()
    m = 0.5 * (p + q)

    def kl(x: np.ndarray) -> float:
        mask = x > 0
        return float(np.sum(x[mask] * np.log2(x[mask] / m[mask])))

    return max(0.0, 0.5 * kl(p) + 0.5 * kl(q))


def _moving(times: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Per interval between samples: its length (s) and how many joints move in it (faster
    than :data:`MOVING_SPEED_FRACTION` of the path's fastest joint speed); None for a path of
    fewer than 2 samples or one that does not move."""
    q = np.asarray(q, dtype=np.float64)
    t = _times(times, q.shape[0])
    if q.shape[0] < 2:
        return None
    dt = np.diff(t)
    speed = np.abs(np.diff(q, axis=0)) / dt[:, None]
    peak = speed.max()
    if peak <= 0:
        return None
    return dt, (speed > MOVING_SPEED_FRACTION * peak).sum(axis=1)


def moving_together(times: np.ndarray, q: np.ndarray) -> float:
    """Share of the moving time in which two or more joints move (see the module docstring).

    NaN for a path that does not move.
    """
    moving = _moving(times, q)
    if moving is None:
        return math.nan
    dt, count = moving
    return float(dt[count >= 2].sum() / dt[count >= 1].sum())


def moving_span(times: np.ndarray, q: np.ndarray) -> float:
    """Seconds from the first interval in which a joint moves (as :func:`moving_together`
    counts it) to the end of the last: the motion without the stillness a cut holds before and
    after it. 0 for a path that does not move."""
    moving = _moving(times, q)
    if moving is None:
        return 0.0
    dt, count = moving
    inside = np.flatnonzero(count >= 1)
    return float(dt[inside[0] : inside[-1] + 1].sum())


@dataclass(frozen=True)
class MotionFigures:
    """One motion's own figures: the columns of a :class:`LikenessCard`.

    Attributes:
        ldlj: log dimensionless jerk of the tool's velocity, low-passed at
            :data:`LDLJ_CUTOFF_HZ` (higher is smoother).
        sparc: spectral arc length of the tool's speed (:func:`sparc`; nearer 0 is smoother):
            where LDLJ weighs jerk, it sees the speed profile's shape, so a constant pace with
            abrupt starts and stops scores low.
        joint_shares: each joint's share of the total joint travel.
        together: share of the moving time in which two or more joints move.
        duration_s: seconds from the first sample to the last.
        joint_travel_rad: total joint travel ``sum |dq|`` (the scale DTW is read against).
        tool_path_m: length of the tool path (the scale Fréchet is read against).
    """

    ldlj: float
    sparc: float
    joint_shares: tuple[float, ...]
    together: float
    duration_s: float
    joint_travel_rad: float
    tool_path_m: float


def motion_figures(times: np.ndarray, q: np.ndarray, tool: np.ndarray) -> MotionFigures:
    """The :class:`MotionFigures` of joint path ``q`` ``(N, J)`` at ``times`` with tool path
    ``tool`` ``(N, 3)``."""
    q = np.asarray(q, dtype=np.float64)
    t = _times(times, q.shape[0])
    tool = np.asarray(tool, dtype=np.float64)
    return MotionFigures(
        ldlj=ldlj(t, tool),
        sparc=sparc(t, tool),
        joint_shares=tuple(float(x) for x in joint_shares(q)),
        together=moving_together(t, q),
        duration_s=float(t[-1] - t[0]),
        joint_travel_rad=float(np.abs(np.diff(q, axis=0)).sum()),
        tool_path_m=float(np.linalg.norm(np.diff(tool, axis=0), axis=1).sum()),
    )


def _number(x: float) -> float | None:
    """A float for JSON (NaN, which JSON lacks, as null)."""
    return None if not math.isfinite(x) else round(float(x), 6)


@dataclass(frozen=True)
class LikenessCard:
    """A policy's motion compared with the demonstration it was taught from.

    ``dtw_rad``, ``frechet_m`` and ``shares_js`` compare the two (the demonstration's own value
    is 0 by definition; read them against ``demonstration.joint_travel_rad`` and
    ``demonstration.tool_path_m``); ``policy`` and ``demonstration`` hold each motion's own
    figures side by side.

    Attributes:
        dtw_rad: joint-space DTW distance per aligned sample (rad).
        frechet_m: discrete Fréchet distance of the tool paths (m).
        shares_js: Jensen-Shannon divergence of the joint shares (bits).
        policy: the policy rollout's figures.
        demonstration: the demonstration's figures.
    """

    dtw_rad: float
    frechet_m: float
    shares_js: float
    policy: MotionFigures
    demonstration: MotionFigures

    def to_dict(self) -> dict[str, object]:
        """JSON-ready (NaN as null), numbers to a micro-unit."""
        data = asdict(self)
        for key in ("dtw_rad", "frechet_m", "shares_js"):
            data[key] = _number(data[key])
        for side in ("policy", "demonstration"):
            figures = data[side]
            for key, value in figures.items():
                figures[key] = (
                    [_number(x) for x in value] if isinstance(value, tuple) else _number(value)
                )
        return data

    def text(self) -> str:
        """A short table for the terminal: each figure, the policy's value, the demonstration's."""
        p, d = self.policy, self.demonstration

        def f(x: float, digits: int) -> str:
            return "n/a" if not math.isfinite(x) else f"{x:.{digits}f}"

        def shares(m: MotionFigures) -> str:
            return "/".join(f"{100 * s:.0f}" for s in m.joint_shares)

        rows = [
            ("", "policy", "demonstration"),
            (
                "DTW, joints (rad/sample)",
                f(self.dtw_rad, 4),
                f"0 (travel {d.joint_travel_rad:.2f} rad)",
            ),
            ("Frechet, tool (m)", f(self.frechet_m, 4), f"0 (path {d.tool_path_m:.3f} m)"),
            ("smoothness LDLJ", f(p.ldlj, 2), f(d.ldlj, 2)),
            ("smoothness SPARC", f(p.sparc, 2), f(d.sparc, 2)),
            ("joint shares (%)", shares(p), shares(d)),
            ("  JS divergence (bits)", f(self.shares_js, 3), "0"),
            ("joints together (%)", f(100 * p.together, 0), f(100 * d.together, 0)),
            ("duration (s)", f(p.duration_s, 2), f(d.duration_s, 2)),
        ]
        return "\n".join(f"{a:<26}{b:>12}  {c}" for a, b, c in rows)


def likeness_card(
    policy_times: np.ndarray,
    policy_q: np.ndarray,
    demo_times: np.ndarray,
    demo_q: np.ndarray,
    tool_positions: ToolPositions,
    joints: int | None = None,
) -> LikenessCard:
    """Compare a policy's joint trajectory with a demonstration's.

    Args:
        policy_times: the rollout's sample times ``(N,)`` (s).
        policy_q: the rollout's joint angles ``(N, J)`` (rad), started from the demonstration's
            start.
        demo_times: the demonstration's sample times ``(M,)``.
        demo_q: the demonstration's joint angles ``(M, J)``.
        tool_positions: forward kinematics, ``(K, J)`` joints to ``(K, 3)`` tool positions (m);
            for the Puma560 :func:`puma_tool_positions`.
        joints: compare only the first ``joints`` columns (the joints a task learns; the tool
            paths still come from all of them). Default: all.

    Raises:
        LearningError: shapes that do not match, non-finite values, or times that do not increase.
    """
    policy_q, demo_q = _paths(policy_q, demo_q, "joint path")
    k = policy_q.shape[1] if joints is None else joints
    if not isinstance(k, int) or not 1 <= k <= policy_q.shape[1]:
        raise LearningError(f"joints is {joints!r}; give 1 to {policy_q.shape[1]}.")
    policy_tool = np.asarray(tool_positions(policy_q), dtype=np.float64)
    demo_tool = np.asarray(tool_positions(demo_q), dtype=np.float64)
    policy = motion_figures(policy_times, policy_q[:, :k], policy_tool)
    demonstration = motion_figures(demo_times, demo_q[:, :k], demo_tool)
    return LikenessCard(
        dtw_rad=dtw_distance(policy_q[:, :k], demo_q[:, :k]),
        frechet_m=frechet_distance(policy_tool, demo_tool),
        shares_js=js_divergence(
            np.array(policy.joint_shares), np.array(demonstration.joint_shares)
        ),
        policy=policy,
        demonstration=demonstration,
    )


def robot_tool_positions(robot: str, q: np.ndarray) -> np.ndarray:
    """``robot``'s tool positions ``(N, 3)`` (m) for its joint angles ``(N, nq)`` (rad), by the
    tasks' compiled forward kinematics of its registry model (:func:`._reach.tool_positions`,
    held equal to Pinocchio's by a test; the Puma560's equal :func:`puma_tool_positions`)."""
    return tool_positions(robot, q)


def puma_tool_positions(q: np.ndarray) -> np.ndarray:
    """The Puma560's tool positions ``(N, 3)`` (m) for joint angles ``(N, 6)`` (rad)."""
    robot = Puma560()
    q = np.asarray(q, dtype=np.float64)
    return np.array([robot.forward(row)[:3, 3] for row in q]).reshape(-1, 3)
