"""Landmark filters: the One Euro filter, and a constant-velocity Kalman filter and smoother.

The One Euro filter: low jitter when still, low lag when moving.

Casiez, Roussel and Vogel, "1 Euro Filter: A Simple Speed-based Low-pass Filter for Noisy Input
in Interactive Systems", CHI 2012. A first-order low-pass filter whose cutoff rises with the
signal's (filtered) speed: ``cutoff = min_cutoff + beta * |speed|``. Its lag on a steady motion
is the low-pass filter's time constant, ``1 / (2 pi cutoff)``: largest for slow motion, where it
is ``1 / (2 pi min_cutoff)`` whatever the frame rate, and smaller the faster the motion.
"""

from __future__ import annotations

import math

import numpy as np

from .._checks import KinematicsError, positive_number, real_array


def _alpha(cutoff: np.ndarray | float, dt: float) -> np.ndarray | float:
    """Smoothing factor of a first-order low-pass filter at ``cutoff`` (Hz) over ``dt`` (s)."""
    tau = 1.0 / (2.0 * math.pi * cutoff)
    return 1.0 / (1.0 + tau / dt)


class OneEuroFilter:
    """A One Euro filter over arrays of any fixed shape, element by element.

    Args:
        min_cutoff: cutoff frequency (Hz) for a still signal; a number, or an array that
            broadcasts against the samples (a lower cutoff for noisier elements).
        beta: how much the cutoff rises with speed (Hz per unit of the signal per second).
        d_cutoff: cutoff (Hz) of the speed estimate.

    Raises:
        KinematicsError: a non-positive cutoff or a negative beta.
    """

    def __init__(
        self, min_cutoff: float | np.ndarray = 1.0, beta: float = 0.0, d_cutoff: float = 1.0
    ) -> None:
        cutoff = real_array(min_cutoff, "OneEuroFilter's min_cutoff", "pass frequencies in Hz")
        if not (np.all(np.isfinite(cutoff)) and np.all(cutoff > 0)):
            raise KinematicsError(
                f"OneEuroFilter's min_cutoff must be positive frequencies in Hz; got {min_cutoff!r}."
            )
        if not (isinstance(beta, int | float) and math.isfinite(beta) and beta >= 0):
            raise KinematicsError(f"OneEuroFilter's beta must be a number >= 0; got {beta!r}.")
        self.min_cutoff = cutoff
        self.beta = float(beta)
        self.d_cutoff = positive_number(d_cutoff, "OneEuroFilter's d_cutoff")
        self.reset()

    def reset(self) -> None:
        """Forget the past: the next sample passes unfiltered."""
        self._t: float | None = None
        self._x: np.ndarray | None = None
        self._dx: np.ndarray | None = None

    def lag_s(self, speed: float = 0.0) -> float:
        """The filter's lag (s) on a steady motion of ``speed`` (signal units per second).

        The largest element lag: with an array ``min_cutoff``, the lowest cutoff's. At speed 0
        (slow motion) it is ``1 / (2 pi min_cutoff)``, independent of the frame rate.
        """
        cutoff = float(np.min(self.min_cutoff)) + self.beta * abs(float(speed))
        return 1.0 / (2.0 * math.pi * cutoff)

    def __call__(self, t: float, x: object) -> np.ndarray:
        """Filter one sample.

        Args:
            t: its time (s); must increase from sample to sample.
            x: the sample (an array of the filter's fixed shape).

        Returns:
            The filtered sample (a new array).

        Raises:
            KinematicsError: a time that does not increase, or a sample of another shape.
        """
        value = real_array(x, "The filtered sample", "pass numbers")
        if self._x is None or self._t is None:
            self._t, self._x, self._dx = float(t), value.copy(), np.zeros_like(value)
            return value.copy()
        if value.shape != self._x.shape:
            raise KinematicsError(
                f"OneEuroFilter got a sample of shape {value.shape} after {self._x.shape}; "
                "reset it before filtering another signal."
            )
        dt = float(t) - self._t
        if not dt > 0.0:
            raise KinematicsError(
                f"OneEuroFilter got time {float(t)!r} s after {self._t!r} s; give increasing times."
            )
        dx = (value - self._x) / dt
        self._dx = self._dx + _alpha(self.d_cutoff, dt) * (dx - self._dx)
        cutoff = self.min_cutoff + self.beta * np.abs(self._dx)
        self._x = self._x + _alpha(cutoff, dt) * (value - self._x)
        self._t = float(t)
        return self._x.copy()


class ConstantVelocityFilter:
    """A Kalman filter of a constant-velocity motion, element by element, over arrays of any shape.

    Each element is a position and a velocity; between samples the velocity changes by white
    acceleration noise of spectral density ``acceleration ** 2``, and each sample measures the
    position with noise of s.d. ``noise``. Unlike a low-pass filter it predicts with the
    velocity, so a steady motion passes without lag; only a change of speed is followed late.

    Args:
        noise: the measurement's s.d. (signal units); a number or an array that broadcasts
            against the samples (larger for noisier elements).
        acceleration: how fast the velocity may change (signal units per s^2 per sqrt(Hz)).

    Raises:
        KinematicsError: a non-positive noise or acceleration.
    """

    def __init__(self, noise: float | np.ndarray, acceleration: float | np.ndarray) -> None:
        values = []
        for value, name in ((noise, "noise"), (acceleration, "acceleration")):
            arr = real_array(value, f"ConstantVelocityFilter's {name}", "pass positive numbers")
            if not (np.all(np.isfinite(arr)) and np.all(arr > 0)):
                raise KinematicsError(
                    f"ConstantVelocityFilter's {name} must be positive numbers; got {value!r}."
                )
            values.append(arr)
        self.noise, self.acceleration = values
        self.reset()

    def reset(self) -> None:
        """Forget the past: the next sample passes unfiltered, still."""
        self._t: float | None = None
        self._x: np.ndarray | None = None

    def lag_s(self, dt: float = 1.0 / 30.0) -> float:
        """The time (s) in which it takes up a change of speed, at samples ``dt`` (s) apart.

        A steady motion passes without delay; an acceleration is followed within the steady
        filter's time constant ``1 / w``, ``w = (acceleration ** 2 / (noise ** 2 dt)) ** 0.25``
        (the slowest element's). Over a smooth motion the output trails far less than this.
        """
        ratio = float(np.max(self.noise**2 * dt / self.acceleration**2))
        return ratio**0.25

    def __call__(self, t: float, x: object) -> np.ndarray:
        """Filter one sample: its time (s, increasing) and value (the filter's fixed shape).

        Returns:
            The filtered position (a new array).

        Raises:
            KinematicsError: a time that does not increase, or a sample of another shape.
        """
        z = real_array(x, "The filtered sample", "pass numbers")
        if self._x is not None and z.shape != self._x.shape:
            raise KinematicsError(
                f"ConstantVelocityFilter got a sample of shape {z.shape} after {self._x.shape}; "
                "reset it before filtering another signal."
            )
        try:
            r = np.broadcast_to(self.noise**2, z.shape)
            np.broadcast_to(self.acceleration, z.shape)
        except ValueError:
            raise KinematicsError(
                f"ConstantVelocityFilter's noise {self.noise.shape} and acceleration "
                f"{self.acceleration.shape} do not fit a sample of shape {z.shape}; give them "
                "the sample's shape or numbers."
            ) from None
        if self._x is None or self._t is None:
            self._t, self._x, self._v = float(t), z.copy(), np.zeros_like(z)
            self._p = [r.copy(), np.zeros_like(z), 1e6 * np.ones_like(z)]
            return z.copy()
        dt = float(t) - self._t
        if not dt > 0.0:
            raise KinematicsError(
                f"ConstantVelocityFilter got time {float(t)!r} s after {self._t!r} s; give "
                "increasing times."
            )
        x, v, cov = _predict(self._x, self._v, self._p, dt, self.acceleration**2)
        self._x, self._v, self._p = _update(x, v, cov, z, r)
        self._t = float(t)
        return self._x.copy()


def _predict(
    x: np.ndarray, v: np.ndarray, cov: list[np.ndarray], dt: float, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The constant-velocity model ``dt`` later: position, velocity and covariance
    ``[p00, p01, p11]``, the velocity driven by white acceleration of spectral density ``q``."""
    p00, p01, p11 = cov
    return (
        x + dt * v,
        v,
        [
            p00 + dt * (2.0 * p01 + dt * p11) + q * dt**3 / 3.0,
            p01 + dt * p11 + q * dt**2 / 2.0,
            p11 + q * dt,
        ],
    )


def _update(
    x: np.ndarray, v: np.ndarray, cov: list[np.ndarray], z: np.ndarray, r: np.ndarray
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The prediction corrected by the position ``z`` measured with variance ``r``."""
    p00, p01, p11 = cov
    s = p00 + r
    k0, k1 = p00 / s, p01 / s
    innovation = z - x
    return (
        x + k0 * innovation,
        v + k1 * innovation,
        [(1.0 - k0) * p00, (1.0 - k0) * p01, p11 - k1 * p01],
    )


def smooth_constant_velocity(
    times: object, samples: object, noise: float | np.ndarray, acceleration: float | np.ndarray
) -> np.ndarray:
    """The samples smoothed with the past and the future: :class:`ConstantVelocityFilter`'s
    model run forward, then back (Rauch, Tung and Striebel, AIAA J. 1965).

    Each sample's estimate uses the whole sequence, so unlike the filter it has no lag at all:
    for a recording, where every frame is at hand, not for a live source.

    Args:
        times: increasing times (s), shape (N,).
        samples: the values, shape (N, ...), each element filtered on its own.
        noise, acceleration: as :class:`ConstantVelocityFilter` takes them.

    Returns:
        The smoothed positions, shape (N, ...).

    Raises:
        KinematicsError: times that do not increase, or shapes that do not fit.
    """
    t = real_array(times, "The smoothed times", "pass seconds")
    z = real_array(samples, "The smoothed samples", "pass numbers")
    if t.ndim != 1 or len(z) != len(t):
        raise KinematicsError(
            f"smooth_constant_velocity got {t.shape} times for samples of shape {z.shape}; "
            "give one time per sample."
        )
    if len(t) > 1 and not np.all(np.diff(t) > 0.0):
        raise KinematicsError("smooth_constant_velocity got times that do not increase.")
    filt = ConstantVelocityFilter(noise, acceleration)
    if not len(t):
        return z.copy()
    try:
        r = np.broadcast_to(filt.noise**2, z.shape[1:])
        q = np.broadcast_to(filt.acceleration**2, z.shape[1:])
    except ValueError:
        raise KinematicsError(
            f"smooth_constant_velocity's noise {filt.noise.shape} and acceleration "
            f"{filt.acceleration.shape} do not fit samples of shape {z.shape[1:]}."
        ) from None
    x, v = z[0].copy(), np.zeros_like(z[0])
    cov = [r.copy(), np.zeros_like(z[0]), 1e6 * np.ones_like(z[0])]
    filtered, predicted = [(x, v, cov)], [(x, v, cov)]
    for k in range(1, len(t)):
        ahead = _predict(x, v, cov, float(t[k] - t[k - 1]), q)
        predicted.append(ahead)
        x, v, cov = _update(*ahead, z[k], r)
        filtered.append((x, v, cov))
    out = np.empty_like(z)
    xs, vs = x, v
    out[-1] = xs
    for k in range(len(t) - 2, -1, -1):
        dt = float(t[k + 1] - t[k])
        (xf, vf, (f00, f01, f11)), (xp, vp, (p00, p01, p11)) = filtered[k], predicted[k + 1]
        # gain A = P_f F^T P_p^-1, element by element (2 x 2 each)
        m00, m01, m10, m11 = f00 + dt * f01, f01, f01 + dt * f11, f11
        det = p00 * p11 - p01 * p01
        i00, i01, i11 = p11 / det, -p01 / det, p00 / det
        dx, dv = xs - xp, vs - vp
        xs = xf + (m00 * i00 + m01 * i01) * dx + (m00 * i01 + m01 * i11) * dv
        vs = vf + (m10 * i00 + m11 * i01) * dx + (m10 * i01 + m11 * i11) * dv
        out[k] = xs
    return out


def white_noise(samples: object) -> np.ndarray:
    """The standard deviation of white measurement noise on ``samples`` ``(N, ...)`` taken at a
    steady rate, element by element, estimated from their second differences.

    White noise of deviation s gives second differences of deviation s * sqrt(6); a smooth
    motion sampled fast gives second differences near zero. The median absolute deviation
    (times 1.4826, the normal's) keeps a few jumps from counting. Fewer than 3 samples: zeros.
    """
    z = real_array(samples, "The samples", "pass numbers")
    if len(z) < 3:
        return np.zeros(z.shape[1:])
    d2 = np.diff(z, 2, axis=0)
    spread = np.median(np.abs(d2 - np.median(d2, axis=0)), axis=0)
    return 1.4826 * spread / math.sqrt(6.0)


JITTER_RAD = math.radians(0.5)
"""A joint step this large, followed by one as large the other way, is a turn back
(:func:`turn_backs`): jitter rather than motion."""


def turn_backs(path: object, above: float = JITTER_RAD) -> int:
    """How often a joint of ``path`` ``(N, J)`` turns back between frames: a step larger than
    ``above`` (rad) followed by one as large the other way. A smooth motion has none; a pose
    that jitters or flips between two answers has one a frame."""
    steps = np.diff(real_array(path, "The path", "pass joint angles (N, J)"), axis=0)
    big = np.abs(steps) > above
    return int(((np.sign(steps[1:]) * np.sign(steps[:-1]) < 0) & big[1:] & big[:-1]).sum())
