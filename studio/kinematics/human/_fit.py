"""Fit the 7-DOF human arm to a reconstructed tape, frame after frame.

The tape lies along the arm from vertex ``shoulder_region`` (at the shoulder) on, cutting the
corners at the elbow and the wrist with straight chords (see :func:`tape_from_arm`). Landmarks
are read from it geometrically, using the operator's limb lengths, so the corner chords do not
bias them:

- shoulder ``S``: vertex ``shoulder_region``;
- elbow ``E = S + upper_arm * u``, with ``u`` the direction of the first arm region (it lies on
  the upper arm whenever the upper arm is longer than one region);
- wrist ``W = E + forearm * f``, with ``f`` the direction from ``E`` to the first vertex past the
  elbow (the elbow-corner chord ends on the forearm);
- hand centre ``H = W + hand * h``, with ``h`` the direction from ``W`` to the first vertex past
  the wrist (or ``f`` when the tape ends before the hand: a straight wrist is assumed).

Then damped least squares (Pinocchio joint Jacobians) moves the arm's elbow, wrist and hand
centre onto ``E, W, H``, warm-started from the previous frame. The first frame, and any frame
whose warm start stalls (the unseen wrist direction running into a joint limit), start from a
closed-form solution instead: shoulder and elbow from the limb directions, the wrist from the
hand's direction given the previous forearm rotation (or, failing that, zero wrist deviation),
on both shoulder branches. The shoulder's two branches, ``(Z, X, Y)`` and ``(Z - pi, pi - X,
Y + pi)``, give the same arm; the fit stays on the previous frame's branch (on a cold start, the
anatomical one, abduction within 90 degrees) unless the other one meets the landmarks better by
more than ``FitConfig.branch_slack``, and among equivalent solutions takes the one nearest the
previous frame (or the neutral arm), so the retargeted robot never jumps between branches.
The tape's landmarks are taken relative to its shoulder vertex, so the arm's angles survive a
tape strapped slightly off; the offset shows in the residual.

Observability: the three directions give six numbers for seven joints. Shoulder flexion,
abduction, humeral rotation and elbow flexion are determined (humeral rotation only when the elbow
is bent beyond the tape's noise: a bend whose sine is below ``FitConfig.straight_sine`` is taken as
straight, the wrist and hand turned about the elbow onto the upper arm's line, so humeral rotation
is held where it was instead of following the noise's direction); forearm rotation and the two wrist joints share one unobservable direction (they all
turn the hand about the forearm), which the damped steps resolve by moving least from the
previous frame. The residual is the RMS distance from the tape's arm vertices to the fitted arm,
so a badly placed or mis-configured tape shows up as a number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numba import njit

from .._checks import KinematicsError, instance_of, positive_number, real_array, whole_number
from ._human import HumanArm
from ._tape import TapeConfig, TapeShape, reconstruct

_DEGENERATE = 1e-12  # m: two tape points closer than this give no direction
_AT_LIMIT = 1e-9  # rad: a closed-form angle this far past a limit is on it (rounding), not beyond


@dataclass(frozen=True)
class FitConfig:
    """Defaults of the arm fit, documented once.

    Attributes:
        warm_iterations: DLS iterations when starting from the previous frame.
        cold_iterations: DLS iterations from the closed-form seed.
        tolerance: stop when the landmark error norm (m, over elbow, wrist, hand) is below this.
        damping: DLS damping lambda (m); bounds steps in the unobservable wrist direction and
            near the straight-elbow singularity.
        max_step: largest joint step per iteration (rad, infinity norm).
        max_residual: a fit whose residual (m) exceeds this is reported as failed: the tape
            does not lie along an arm of these lengths.
        landmark_tolerance: a fit whose IK error (m, elbow/wrist/hand from the tape's shoulder)
            exceeds this is reported as failed.
        branch_slack: the other shoulder branch is taken only when it meets the landmarks
            better than the current one by more than this (m, error norm): near a straight
            elbow or at the elbow's limit, sensor noise makes it fit a few mm better while the
            true pose stays on the current branch.
        equivalent_error: candidates whose landmark error is within this (m) of the best one
            on the chosen branch count as equivalent; the one nearest the previous frame wins.
        branch_jump: a shoulder flexion change (rad) beyond this between frames is a switch
            of branch (a switch turns flexion by pi; continuous motion by little per frame).
        straight_sine: an elbow (or, in the closed-form seed, a wrist) whose landmarks bend by
            an angle with a smaller sine is taken as straight: the rotation about the limb is
            then not observable and is held (the previous frame's, or the neutral arm's)
            instead of following the tape's noise. The default is four standard deviations of
            the bend the ShapeTape's noise puts on a straight elbow with the default tape:
            0.002 rad per region angle (``OperatorConfig.noise_rad``) bends the chord from the
            elbow to the first forearm vertex by ``0.002 * sqrt(0.23**2 + 0.115**2) / 0.069``,
            about 0.0075 rad (one std; measured 0.0064 mean, 0.023 largest over 10 s held).
            A tape with other regions or noise may need another value (below 1).
    """

    warm_iterations: int = 8
    cold_iterations: int = 100
    tolerance: float = 1e-7
    damping: float = 1e-3
    max_step: float = 0.5
    max_residual: float = 0.02
    landmark_tolerance: float = 1e-3
    branch_slack: float = 0.02
    equivalent_error: float = 1e-6
    branch_jump: float = math.pi / 2
    straight_sine: float = 0.03

    def __post_init__(self) -> None:
        whole_number(self.warm_iterations, "FitConfig.warm_iterations", 0)
        whole_number(self.cold_iterations, "FitConfig.cold_iterations", 1)
        for name in (
            "tolerance",
            "damping",
            "max_step",
            "max_residual",
            "landmark_tolerance",
            "branch_slack",
            "equivalent_error",
            "branch_jump",
            "straight_sine",
        ):
            positive_number(getattr(self, name), f"FitConfig.{name}")
        if not self.straight_sine < 1:
            raise KinematicsError(
                f"FitConfig.straight_sine is the sine of a bend and must be below 1; got "
                f"{self.straight_sine!r}."
            )


@dataclass(frozen=True)
class ArmFit:
    """One fitted frame.

    Attributes:
        q_human: fitted joint angles (rad, (7,)), within the arm's limits.
        residual: RMS distance (m) from the tape's arm vertices (shoulder to the first vertex
            past the wrist) to the fitted arm's shoulder-elbow-wrist-hand polyline.
        success: the IK met the landmarks (taken relative to the tape's shoulder vertex) to
            ``landmark_tolerance`` and the residual is below ``max_residual``.
        landmarks: the tape's shoulder, elbow, wrist and hand-centre points, (4, 3) (m).
        landmark_error: RMS distance (m) between those landmarks and the fitted arm's (the
            tape's shoulder vertex against the arm's shoulder at the origin included).
        iterations: DLS iterations used.
    """

    q_human: np.ndarray
    residual: float
    success: bool
    landmarks: np.ndarray
    landmark_error: float
    iterations: int


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


@njit(nogil=True, cache=True)
def _landmarks_kernel(
    positions: np.ndarray,
    shoulder: int,
    first_forearm: int,
    lengths: np.ndarray,
    step: float,
    out: np.ndarray,
) -> int:  # pragma: no cover - compiled
    """Fill ``out (4, 3)`` with S, E, W, H (see the module docstring); return the last vertex.

    Returns -1 (and ``out`` filled with S) when the vertices give no upper-arm or forearm
    direction (coincident points: not a tape's shape).
    """
    regions = positions.shape[0] - 1
    upper, fore, hand = lengths[0], lengths[1], lengths[2]
    S = positions[shoulder]
    for k in range(4):
        out[k] = S
    d = positions[shoulder + 1] - S
    norm = np.sqrt(np.sum(d * d))
    if not norm > _DEGENERATE:
        return -1
    d = d / norm
    E = S + upper * d
    f = positions[first_forearm] - E
    norm = np.sqrt(np.sum(f * f))
    if norm < 1e-9 and first_forearm < regions:
        f = positions[first_forearm + 1] - positions[first_forearm]
        norm = np.sqrt(np.sum(f * f))
    if not norm > _DEGENERATE:
        return -1
    along = np.sum((positions[first_forearm] - E) * f) / norm  # first vertex's distance from E
    f = f / norm
    W = E + fore * f
    # Whole regions follow along the forearm; the first vertex past the wrist ends the chord
    # that cuts the wrist's corner (whatever the hand's angle).
    last = first_forearm + int(np.floor((fore - along) / step + 1e-9)) + 1
    h = f
    if last <= regions:
        h = positions[last] - W
        norm = np.sqrt(np.sum(h * h))
        h = h / norm if norm > _DEGENERATE else f  # vertex on the wrist: take a straight wrist
    else:
        last = regions
    out[1] = E
    out[2] = W
    out[3] = W + hand * h
    return last


@njit(nogil=True, cache=True)
def _rms_polyline_distance(points: np.ndarray, poly: np.ndarray) -> float:  # pragma: no cover
    """RMS distance of ``points`` to the polyline ``poly``, whose last segment is a ray."""
    total = 0.0
    segments = poly.shape[0] - 1
    for i in range(points.shape[0]):
        best = np.inf
        for k in range(segments):
            d = poly[k + 1] - poly[k]
            rel = points[i] - poly[k]
            t = np.sum(rel * d) / np.sum(d * d)
            t = max(t, 0.0)
            if k < segments - 1:
                t = min(t, 1.0)
            gap = rel - t * d
            best = min(best, np.sum(gap * gap))
        total += best
    return np.sqrt(total / points.shape[0])


class ArmFitter:
    """Fits ``arm`` to the tape described by ``config``, one frame at a time.

    Args:
        arm: the operator's arm (its lengths define the landmarks).
        config: the tape and where it lies on the operator.
        fit: solver defaults.

    Raises:
        KinematicsError: the tape's regions cannot see the arm (upper arm shorter than a
            region, or the configured arm regions shorter than the arm).
    """

    def __init__(self, arm: HumanArm, config: TapeConfig, fit: FitConfig | None = None) -> None:
        instance_of(arm, HumanArm, "ArmFitter's arm")
        instance_of(config, TapeConfig, "ArmFitter's config")
        instance_of(fit, FitConfig, "ArmFitter's fit", optional=True)
        self.arm = arm
        self.config = config
        self.settings = fit or FitConfig()
        step = config.region_length
        if arm.upper_arm_length < step:
            raise KinematicsError(
                f"The upper arm ({arm.upper_arm_length:.3f} m) is shorter than one tape region "
                f"({step:.3f} m), so the tape cannot show its direction; use more regions."
            )
        s = config.shoulder_region
        arm_regions = config.wrist_region - s
        if arm_regions * step < arm.upper_arm_length + arm.forearm_length - 1e-9:
            raise KinematicsError(
                f"The tape's arm regions ({s}..{config.wrist_region - 1}, "
                f"{arm_regions * step:.3f} m) are shorter than the arm "
                f"({arm.upper_arm_length + arm.forearm_length:.3f} m shoulder to wrist); "
                "raise wrist_region or lower shoulder_region."
            )
        self._first_forearm = s + int(math.floor(arm.upper_arm_length / step + 1e-9)) + 1
        self.model = arm.model
        self.data = arm.model.createData()
        self._hand = arm.hand_frame
        self._joints = arm.joints
        self._lower = np.asarray(arm.lower)
        self._upper = np.asarray(arm.upper)
        self._damping = np.eye(arm.nq) * self.settings.damping**2
        self._lengths = np.array([arm.upper_arm_length, arm.forearm_length, arm.hand_length])
        self._J = np.empty((9, arm.nq))  # scratch: landmark Jacobian and error
        self._e = np.empty(9)
        self._q: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the previous frame: the next fit starts cold."""
        self._q = None

    # -------------------------------------------------------------------------------- landmarks

    def landmarks(self, positions: np.ndarray) -> tuple[np.ndarray, int]:
        """Shoulder, elbow, wrist and hand centre from one tape's vertices.

        Args:
            positions: ``(regions + 1, 3)`` vertices.

        Returns:
            ``(points (4, 3), last)`` where ``last`` is the index of the last vertex used, or
            -1 when coincident vertices give no limb direction (``points`` are then all the
            shoulder vertex).
        """
        points = np.empty((4, 3))
        last = _landmarks_kernel(
            np.ascontiguousarray(positions, dtype=np.float64),
            self.config.shoulder_region,
            self._first_forearm,
            self._lengths,
            self.config.region_length,
            points,
        )
        return points, int(last)

    def _seed(
        self,
        points: np.ndarray,
        forearm_rotation: float | None = None,
        overhead: bool = False,
        humeral_rotation: float = 0.0,
    ) -> np.ndarray:
        """Closed-form arm angles from the landmark directions.

        Shoulder and elbow angles follow from the upper-arm and forearm directions. The hand's
        direction fixes two of forearm rotation and the two wrist joints: given
        ``forearm_rotation`` (the previous frame's, for continuity) the wrist follows; without
        it, wrist deviation is taken as zero. ``overhead`` picks the other shoulder branch
        (abduction beyond 90 degrees, flexion turned by 180), the one an arm raised sideways
        over the head needs. An elbow straight to ``FitConfig.straight_sine`` leaves humeral
        rotation unseen: it is held at ``humeral_rotation`` (given on the anatomical branch;
        turned by 180 degrees on the overhead one, the same arm).
        """
        S, E, W, H = points
        seen = self.settings.straight_sine
        d = _unit(E - S)
        q = np.zeros(self.arm.nq)
        sign = -1.0 if self.arm.side == "right" else 1.0  # mirrored lateral axes
        # Upper-arm direction in the base frame: (sin q0 cos q1, sign sin q1, -cos q0 cos q1).
        q[1] = math.asin(float(np.clip(sign * d[1], -1.0, 1.0)))
        q[0] = math.atan2(d[0], -d[2])
        if overhead:  # same upper-arm direction: (q0 + pi, pi - q1)
            q[1] = math.pi - q[1]
            q[0] = q[0] - math.copysign(math.pi, q[0])
        f = _unit(W - E)
        q[3] = math.acos(float(np.clip(d @ f, -1.0, 1.0)))
        pin.forwardKinematics(self.model, self.data, q)
        joints = self._joints
        # the forearm in the frame before humeral rotation
        fA = self.data.oMi[joints.shoulder_X].rotation.T @ f
        if math.sin(q[3]) > seen:  # humeral rotation is seen only with a bent elbow
            q[2] = math.atan2(sign * fA[2], fA[0])
        else:
            q[2] = humeral_rotation + math.pi if overhead else humeral_rotation
            q[2] = math.remainder(q[2], 2 * math.pi)
        q = np.minimum(np.maximum(q, self._lower), self._upper)
        lower, upper = self._lower, self._upper
        if forearm_rotation is not None:
            # Hand direction after forearm rotation: (sin q5 cos q6, -cos q5 cos q6, -sign sin q6).
            q[4] = min(max(forearm_rotation, lower[4]), upper[4])
            pin.forwardKinematics(self.model, self.data, q)
            h = self.data.oMi[joints.elbow_Y].rotation.T @ _unit(H - W)
            q[6] = math.asin(float(np.clip(sign * h[2], -1.0, 1.0)))
            q[5] = math.atan2(h[0], -h[1])
            return np.minimum(np.maximum(q, lower), upper)
        # No deviation: the hand's direction in the elbow frame is
        # (cos q4 sin q5, -cos q5, sign sin q4 sin q5).
        pin.forwardKinematics(self.model, self.data, q)
        h = self.data.oMi[joints.elbow_Z].rotation.T @ _unit(H - W)
        q5 = math.acos(float(np.clip(-h[1], -1.0, 1.0)))
        # A straight wrist leaves forearm rotation unseen: keep it at zero then.
        q4 = math.atan2(sign * h[2], h[0]) if math.sin(q5) > seen else 0.0
        lo, hi = lower - _AT_LIMIT, upper + _AT_LIMIT
        for q4_try, q5_try in ((q4, q5), (q4 + math.pi, -q5), (q4 - math.pi, -q5)):
            if lo[4] <= q4_try <= hi[4] and lo[5] <= q5_try <= hi[5]:
                q[4], q[5] = q4_try, q5_try
                break
        return np.minimum(np.maximum(q, lower), upper)

    # -------------------------------------------------------------------------------------- IK

    def _solve(
        self, q: np.ndarray, target: np.ndarray, iterations: int
    ) -> tuple[np.ndarray, float, int]:
        """Projected DLS from ``q``; leaves ``self.data`` at the returned ``q``."""
        model, data, cfg, hand = self.model, self.data, self.settings, self._hand
        frame = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        J, e = self._J, self._e
        lower, upper = self._lower, self._upper
        elbow, wrist = self._joints.elbow_Z, self._joints.wrist_Z
        err = math.inf
        for it in range(iterations + 1):
            pin.computeJointJacobians(model, data, q)
            e[0:3] = target[0:3] - data.oMi[elbow].translation
            e[3:6] = target[3:6] - data.oMi[wrist].translation
            e[6:9] = target[6:9] - pin.updateFramePlacement(model, data, hand).translation
            err = math.sqrt(float(e @ e))
            if err < cfg.tolerance or it == iterations:
                return q, err, it
            J[0:3] = pin.getJointJacobian(model, data, elbow, frame)[:3]
            J[3:6] = pin.getJointJacobian(model, data, wrist, frame)[:3]
            J[6:9] = pin.getFrameJacobian(model, data, hand, frame)[:3]
            dq = np.linalg.solve(J.T @ J + self._damping, J.T @ e)
            largest = max(float(dq.max()), -float(dq.min()))
            if largest > cfg.max_step:
                dq *= cfg.max_step / largest
            q = np.minimum(np.maximum(q + dq, lower), upper)
        return q, err, iterations  # pragma: no cover - loop always returns

    def _reseed(
        self,
        relative: np.ndarray,
        target: np.ndarray,
        warm: tuple[np.ndarray, float] | None,
    ) -> tuple[np.ndarray, float, int]:
        """Solve from every closed-form seed (and the stalled warm start); pick one branch.

        The shoulder has two equivalent branches, ``(Z, X, Y)`` and ``(Z - 180, 180 - X,
        Y + 180)``, which put the arm in the same pose; retargeted, the second drives the Puma's
        joints 1-2 to their limits. Candidates on the reference's branch (the previous frame's, or
        on a cold start the anatomical one, abduction within 90 degrees) are kept unless the other
        branch meets the landmarks better by more than ``branch_slack``: near a straight elbow, or
        at the elbow's limit, sensor noise alone can make the other branch fit a few millimetres
        better. On a cold start the other branch is also taken when it meets the landmarks exactly
        (to ``equivalent_error``) where the anatomical one cannot: an arm raised overhead with a
        slightly bent elbow, which the anatomical branch cannot bend that way within the limits.
        Within the chosen branch, the candidates that meet the landmarks as well as the best one
        (to ``equivalent_error``) are equivalent, and the one nearest the previous frame (or the
        neutral arm) wins, so the unobservable directions move least.

        Args:
            relative: the landmarks relative to the tape's shoulder, (4, 3).
            target: elbow, wrist and hand centre stacked, (9,).
            warm: where the warm start stalled and its error (``None`` on a cold start).

        Returns:
            ``(q, error, iterations)``.
        """
        cfg = self.settings
        previous = self._q
        rotations = [None] if previous is None else [float(previous[4]), None]
        humeral = (
            0.0  # held when the elbow is straight: the previous frame's, on the anatomical branch
        )
        if previous is not None:
            humeral = float(previous[2]) - (
                math.pi if abs(float(previous[1])) > math.pi / 2 else 0.0
            )
        seeds = [
            self._seed(relative, r, overhead, humeral)
            for overhead in (False, True)
            for r in rotations
        ]
        # (q, error, refine): a seed's error as it stands; the stalled warm start is not refined
        # again (it had its iterations), the closed-form seeds may be.
        candidates = [(seed, self._solve(seed, target, 0)[1], True) for seed in seeds]
        if warm is not None:
            candidates.insert(0, (warm[0], warm[1], False))
        same = [c for c in candidates if self._same_branch(c[0], previous)]
        other = [c for c in candidates if not self._same_branch(c[0], previous)]
        reference = self.arm.neutral if previous is None else previous
        iterations = 0

        def distance(c: tuple[np.ndarray, float, bool]) -> float:
            return float(np.linalg.norm(c[0] - reference))

        def settle(pool: list) -> list:
            """Nearest first, refine the seeds until one meets the landmarks exactly."""
            nonlocal iterations
            settled = []
            for q, err, refine in sorted(pool, key=distance):
                if refine and err > cfg.tolerance:
                    q, err, it = self._solve(q, target, cfg.cold_iterations)
                    iterations += it
                settled.append((q, err, False))
                if err <= cfg.tolerance:
                    break
            return settled

        pool = settle(same) if same else []
        best_same = min((c[1] for c in pool), default=math.inf)
        # the other branch may be needed: it must meet the landmarks better by branch_slack,
        # or, on a cold start (no frame to stay continuous with), meet them exactly where this
        # one cannot (noisy landmarks are met exactly by neither)
        cold_miss = previous is None and best_same > cfg.equivalent_error
        if (best_same > cfg.branch_slack or cold_miss) and other:
            other = settle(other)
            best_other = min(c[1] for c in other)
            if best_other < best_same - cfg.branch_slack or (
                cold_miss and best_other <= cfg.equivalent_error
            ):
                pool = other
        best = min(c[1] for c in pool)
        equivalent = [c for c in pool if c[1] <= best + cfg.equivalent_error]
        q, err, _ = min(equivalent, key=distance)
        return q, err, iterations

    def _same_branch(self, q: np.ndarray, previous: np.ndarray | None) -> bool:
        """Whether ``q``'s shoulder lies on the branch of ``previous`` (cold: the anatomical one).

        Switching branch turns shoulder flexion by 180 degrees at once; moving continuously it
        turns little between frames. Without a previous frame, the anatomical branch (abduction
        within 90 degrees, the one a retargeted Puma can follow) is the reference.
        """
        if previous is None:
            return abs(float(q[1])) <= math.pi / 2
        return abs(float(q[0] - previous[0])) <= self.settings.branch_jump

    def fit(self, tape: TapeShape | tuple[object, object]) -> ArmFit:
        """Fit the arm to one tape frame, warm-started from the previous one.

        Args:
            tape: a :class:`TapeShape` of one frame, or its ``(bend, twist)`` (rad, (regions,)).

        Returns:
            An :class:`ArmFit`.

        Raises:
            KinematicsError: wrong shapes or non-finite values.
        """
        regions = self.config.regions
        if isinstance(tape, TapeShape):
            positions = real_array(
                tape.positions, "The tape shape's positions", "pass reconstruct(...)"
            )
            if positions.shape != (regions + 1, 3):
                raise KinematicsError(
                    f"ArmFitter.fit takes one frame: positions of shape ({regions + 1}, 3); "
                    f"got {positions.shape}; fit a batch frame by frame."
                )
            if not np.all(np.isfinite(positions)):
                raise KinematicsError(
                    "The tape shape contains NaN or infinite positions; reconstruct it from "
                    "finite bend and twist."
                )
        else:
            try:
                bend, twist = tape
            except (TypeError, ValueError) as err:
                raise KinematicsError(
                    "ArmFitter.fit takes one frame; pass a TapeShape or a (bend, twist) pair."
                ) from err
            bend_a = real_array(bend, "bend", "pass one angle in radians per region")
            if bend_a.shape != (regions,):
                raise KinematicsError(
                    f"ArmFitter.fit takes one frame: bend of shape ({regions},); got {bend_a.shape}; "
                    "fit a batch frame by frame."
                )
            positions = reconstruct(bend_a, twist, self.config).positions

        points, last = self.landmarks(positions)
        if last < 0:
            return self._no_directions(positions, points)
        relative = points - points[0]  # the arm's shoulder is at the origin
        if self._q is not None:  # a cold start has no rotation to hold: it meets the tape
            relative = self._straighten(relative)
        target = relative[1:].reshape(-1)
        cfg = self.settings
        iterations = 0
        q, err = None, math.inf
        if self._q is not None:
            q, err, iterations = self._solve(self._q, target, cfg.warm_iterations)
        if q is None or err > cfg.tolerance:
            q, err, used = self._reseed(relative, target, None if q is None else (q, err))
            iterations += used
            # Leave the scratch data at the chosen pose for the residual below.
            pin.forwardKinematics(self.model, self.data, q)
            pin.updateFramePlacement(self.model, self.data, self._hand)
        self._q = q

        residual, landmark_error = self._quality(positions, points, last)
        # The IK error is measured from the tape's shoulder; an offset shoulder shows in residual.
        success = err <= cfg.landmark_tolerance and residual <= cfg.max_residual
        return ArmFit(
            q_human=q.copy(),
            residual=residual,
            success=bool(success),
            landmarks=points,
            landmark_error=landmark_error,
            iterations=iterations,
        )

    def _straighten(self, relative: np.ndarray) -> np.ndarray:
        """``relative`` with an elbow bent within the tape's noise made straight.

        When the sine of the angle between the upper arm (shoulder to elbow) and the forearm
        (elbow to wrist) is below ``FitConfig.straight_sine``, the wrist and hand centre are
        turned about the elbow so that the forearm continues the upper arm. The bend's direction
        is then noise, and following it would turn humeral rotation (and forearm rotation with
        it) at random from frame to frame; straight landmarks leave both where they were, the
        damped steps moving them least. The fit's landmark error is still measured against the
        tape's own landmarks. Only warm frames are straightened: a cold start has no rotation
        to hold, and meets the tape's landmarks as they are.
        """
        S, E, W, H = relative
        d, f = E - S, W - E
        d = d / np.linalg.norm(d)
        f = f / np.linalg.norm(f)
        axis = np.cross(f, d)
        sine = float(np.linalg.norm(axis))
        if sine >= self.settings.straight_sine or float(d @ f) <= 0:
            return relative
        out = relative.copy()
        if sine > 0:
            rotation = pin.exp3(axis * (math.asin(sine) / sine))  # turns f onto d
            out[2] = E + rotation @ (W - E)
            out[3] = E + rotation @ (H - E)
        return out

    def _quality(self, positions: np.ndarray, points: np.ndarray, last: int) -> tuple[float, float]:
        """(residual, landmark error) of the arm at ``self.data``'s pose against the tape."""
        arm_points = np.zeros((4, 3))  # shoulder at the origin of the arm base frame
        arm_points[1] = self.data.oMi[self._joints.elbow_Z].translation
        arm_points[2] = self.data.oMi[self._joints.wrist_Z].translation
        arm_points[3] = self.data.oMf[self._hand].translation
        vertices = positions[self.config.shoulder_region : last + 1]
        residual = float(_rms_polyline_distance(vertices, arm_points))
        gap = points - arm_points
        return residual, math.sqrt(float(np.einsum("ij,ij->", gap, gap)) / 4)

    def _no_directions(self, positions: np.ndarray, points: np.ndarray) -> ArmFit:
        """A failed fit for a shape whose arm vertices coincide: no direction to fit to.

        The arm stays where it was (the previous frame, or the neutral arm) and the warm start is
        kept for the next frame. The residual measures the shape against that arm; as vertices
        bunched on one point of the arm lie *on* it, it is at least the landmark error (the
        arm's elbow, wrist and hand against that point), so it shows the failure as a number.
        """
        q = self.arm.neutral if self._q is None else self._q
        pin.forwardKinematics(self.model, self.data, q)
        pin.updateFramePlacement(self.model, self.data, self._hand)
        residual, landmark_error = self._quality(positions, points, self.config.wrist_region)
        return ArmFit(
            q_human=np.array(q, dtype=float),
            residual=max(residual, landmark_error),
            success=False,
            landmarks=points,
            landmark_error=landmark_error,
            iterations=0,
        )
