"""Movement-primitive baseline: a discrete dynamic movement primitive per joint.

The formulation of Ijspeert, Nakanishi, Hoffmann, Pastor & Schaal, "Dynamical movement
primitives: learning attractor models for motor behaviors", Neural Computation 25(2), 2013
(equations 2.1-2.3 and 2.7): for each joint,

    tau * dz/dt = alpha_z * (beta_z * (g - y) - z) + f(x) * (g - y0) / (g_d - y0_d)
    tau * dy/dt = z
    tau * dx/dt = -alpha_x * x
    f(x) = sum_i psi_i(x) w_i / sum_i psi_i(x) * x,   psi_i(x) = exp(-h_i (x - c_i)^2)

a critically damped spring to the goal ``g`` (``beta_z = alpha_z / 4``) driven by a forcing term
that the phase ``x`` fades out, so every rollout converges to its goal. The forcing term is
learned from one demonstration ``y_d(t)`` (start ``y0_d``, end ``g_d``, duration ``tau``) and
scaled by the new movement's amplitude, so the primitive goes from any start to any goal with the
demonstrated shape. Where a joint barely moves in the demonstration (``|g_d - y0_d|`` below
:data:`MIN_SCALED_AMPLITUDE_RAD`) the force is not scaled: dividing by a near-zero amplitude would
blow up its shape.

The weights are fitted where the paper fits them by locally weighted regression on the force a
demonstration needs (its second derivative): here by regularised least squares on the positions
themselves, since the system is linear in its weights. A recorded arm's angles are noisy, and
differentiating them twice turns the noise into forces that make the rollout drift. About a hundred lines of numpy, with no dependency:
the ``movement_primitives`` package does the same and more (Cartesian DMPs, coupling terms), at the
price of a dependency this baseline does not need.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._errors import LearningError

DMP_BASIS = 50
"""Basis functions per joint: enough to follow a few-second human reach sample by sample."""
DMP_ALPHA_Z = 25.0
"""Spring gain of the transformation system (Ijspeert et al. 2013's value)."""
DMP_ALPHA_X = 4.0
"""Decay of the phase: ``x`` falls to ``exp(-4)`` (2%) at the end of the demonstrated duration."""
DMP_RIDGE = 1e-2
"""Tikhonov regularisation of the weight fit, relative to the mean diagonal of its Gram matrix: 1%
smooths the recordings' sample-to-sample jitter instead of following it with huge weights, which
a rollout to a farther goal would amplify (measured on the samples: every one of 60 new starts
settles, against 31 at 0.1%, for 0.0005 rad more DTW)."""
MIN_SCALED_AMPLITUDE_RAD = 0.05
"""A joint whose demonstration moves less than this from start to end keeps its force unscaled."""
DMP_SUBSTEPS = 10
"""Euler steps per output sample of a rollout (the spring's time constant is ``tau / 10``)."""
DMP_SETTLE_RAD = 0.01
"""A rollout goes past the demonstrated duration until every joint is this close to the goal ..."""
DMP_MAX_EXTRA = 2.0
"""... or for at most this many demonstrated durations more."""


@dataclass(frozen=True, eq=False)
class MovementPrimitive:
    """A fitted discrete DMP for a set of joints.

    Attributes:
        weights: float ``(joints, basis)``, the forcing term's weights.
        start: the demonstration's first joint angles ``(joints,)`` (rad).
        goal: the demonstration's last joint angles ``(joints,)`` (rad).
        duration_s: the demonstration's duration, the time constant ``tau`` (s).
        alpha_z: spring gain (``beta_z = alpha_z / 4``).
        alpha_x: phase decay.
    """

    weights: np.ndarray
    start: np.ndarray
    goal: np.ndarray
    duration_s: float
    alpha_z: float = DMP_ALPHA_Z
    alpha_x: float = DMP_ALPHA_X

    @property
    def joints(self) -> int:
        """Joints the primitive moves."""
        return int(self.weights.shape[0])

    @property
    def basis(self) -> int:
        """Basis functions per joint."""
        return int(self.weights.shape[1])

    def features(self, x: np.ndarray) -> np.ndarray:
        """The normalised, phase-gated basis ``psi_i(x) x / sum psi(x)`` for phases ``(N,)``."""
        centres = np.exp(-self.alpha_x * np.linspace(0.0, 1.0, self.basis))
        widths = 1.0 / np.diff(centres, append=centres[-1] / 2) ** 2
        psi = np.exp(-widths * (np.asarray(x)[:, None] - centres) ** 2)
        return psi * np.asarray(x)[:, None] / np.maximum(psi.sum(axis=1, keepdims=True), 1e-300)


def _path(times: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(times, dtype=np.float64).reshape(-1)
    y = np.asarray(q, dtype=np.float64)
    if y.ndim != 2 or y.shape[0] != t.shape[0] or y.shape[0] < 3:
        raise LearningError(
            f"The demonstration has {t.shape[0]} times and joints of shape {y.shape}; give one row of joint angles per time, at least 3."
        )
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))) or np.any(np.diff(t) <= 0):
        raise LearningError(
            "The demonstration holds NaN angles or times that do not increase; re-record it."
        )
    return t - t[0], y


def _spring(
    inputs: np.ndarray, e0: np.ndarray, tau: float, alpha_z: float, dt: float
) -> np.ndarray:
    """The transformation system's error ``y - g`` for forcing ``inputs`` ``(S * DMP_SUBSTEPS,
    M)`` from ``e0`` ``(M,)`` at rest, by explicit Euler steps of ``dt``: ``(S + 1, M)``, one row
    per output sample. Linear in ``inputs`` and ``e0``, which the fit relies on."""
    e, z = e0.astype(np.float64).copy(), np.zeros_like(e0, dtype=np.float64)
    out = np.empty((inputs.shape[0] // DMP_SUBSTEPS + 1, e.shape[0]))
    out[0] = e
    for i in range(inputs.shape[0]):
        dz = (alpha_z * (-alpha_z / 4 * e - z) + inputs[i]) / tau
        e = e + z / tau * dt
        z = z + dz * dt
        if (i + 1) % DMP_SUBSTEPS == 0:
            out[(i + 1) // DMP_SUBSTEPS] = e
    return out


def _phase_features(primitive: MovementPrimitive, samples: int, rate_hz: float) -> np.ndarray:
    """The basis at every Euler step of ``samples`` output samples at ``rate_hz``."""
    dt = 1.0 / rate_hz / DMP_SUBSTEPS
    t = np.arange(samples * DMP_SUBSTEPS) * dt
    return primitive.features(np.exp(-primitive.alpha_x * t / primitive.duration_s))


def fit_movement_primitive(
    times: np.ndarray, q: np.ndarray, basis: int = DMP_BASIS
) -> MovementPrimitive:
    """Fit a DMP per joint to a demonstrated joint path.

    The system is linear in its weights, so the weights are those whose rollout (from the
    demonstration's start to its end, at its mean sample rate) is closest to the demonstrated
    positions in least squares; this needs no second derivative of a noisy recording.

    Args:
        times: sample times ``(N,)`` (s, increasing).
        q: joint angles ``(N, joints)`` (rad), for example a demonstration's ``q_robot``.
        basis: basis functions per joint.

    Raises:
        LearningError: fewer than 3 samples, NaN, times that do not increase, or a bad basis.
    """
    if not isinstance(basis, int) or isinstance(basis, bool) or basis < 2:
        raise LearningError(f"basis is {basis!r}; give a whole number of at least 2.")
    t, y = _path(times, q)
    tau = float(t[-1])
    samples = t.shape[0] - 1
    rate_hz = samples / tau
    uniform = np.arange(samples + 1) / rate_hz
    y = np.column_stack([np.interp(uniform, t, column) for column in y.T])
    start, goal = y[0].copy(), y[-1].copy()
    primitive = MovementPrimitive(np.zeros((y.shape[1], basis)), start, goal, tau)
    dt = 1.0 / rate_hz / DMP_SUBSTEPS
    responses = _spring(
        _phase_features(primitive, samples, rate_hz), np.zeros(basis), tau, primitive.alpha_z, dt
    )
    free = _spring(
        np.zeros((samples * DMP_SUBSTEPS, y.shape[1])), start - goal, tau, primitive.alpha_z, dt
    )
    gram = responses.T @ responses
    gram += DMP_RIDGE * np.trace(gram) / basis * np.eye(basis)
    weights = np.linalg.solve(gram, responses.T @ (y - goal - free)).T
    return MovementPrimitive(weights, start, goal, tau, primitive.alpha_z, primitive.alpha_x)


def roll_out_primitive(
    primitive: MovementPrimitive,
    start: np.ndarray | None = None,
    goal: np.ndarray | None = None,
    rate_hz: float = 50.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The primitive's motion from ``start`` to ``goal`` (default: the demonstration's own).

    It runs for the demonstrated duration, then on until every joint is within
    :data:`DMP_SETTLE_RAD` of the goal (at most :data:`DMP_MAX_EXTRA` durations more).

    Returns:
        ``(times (N,), q (N, joints))`` in seconds and radians, from t = 0.

    Raises:
        LearningError: a start or goal of the wrong size or not finite, or a bad rate.
    """
    if not isinstance(rate_hz, int | float) or not np.isfinite(rate_hz) or rate_hz <= 0:
        raise LearningError(f"rate_hz is {rate_hz!r}; give a positive number.")
    ends = []
    for label, value, default in (
        ("start", start, primitive.start),
        ("goal", goal, primitive.goal),
    ):
        v = default if value is None else np.asarray(value, dtype=np.float64).reshape(-1)
        if v.shape != (primitive.joints,) or not np.all(np.isfinite(v)):
            raise LearningError(
                f"The {label} has {v.size} angles; give {primitive.joints} finite joint angles in radians."
            )
        ends.append(v)
    y0, g = ends
    demo_amplitude = primitive.goal - primitive.start
    scaled = np.abs(demo_amplitude) >= MIN_SCALED_AMPLITUDE_RAD
    scale = np.where(scaled, (g - y0) / np.where(scaled, demo_amplitude, 1.0), 1.0)
    tau = primitive.duration_s
    samples = int(np.ceil(tau * (1.0 + DMP_MAX_EXTRA) * rate_hz))
    force = _phase_features(primitive, samples, rate_hz) @ primitive.weights.T * scale
    e = _spring(force, y0 - g, tau, primitive.alpha_z, 1.0 / rate_hz / DMP_SUBSTEPS)
    settled = np.all(np.abs(e) <= DMP_SETTLE_RAD, axis=1)
    settled[: int(np.ceil(tau * rate_hz - 1e-9))] = False
    end = int(np.argmax(settled)) if settled.any() else samples
    q = g + e[: end + 1]
    return np.arange(q.shape[0]) / rate_hz, q
