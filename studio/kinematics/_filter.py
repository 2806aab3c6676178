"""Landmark filters: the One Euro filter, and a constant-velocity Kalman filter.

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

from ._checks import positive_number, real_array
from ._errors import KinematicsError


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
        q = self.acceleration**2
        p00, p01, p11 = self._p
        x = self._x + dt * self._v
        p00 = p00 + dt * (2.0 * p01 + dt * p11) + q * dt**3 / 3.0
        p01 = p01 + dt * p11 + q * dt**2 / 2.0
        p11 = p11 + q * dt
        s = p00 + r
        k0, k1 = p00 / s, p01 / s
        innovation = z - x
        self._x = x + k0 * innovation
        self._v = self._v + k1 * innovation
        self._p = [(1.0 - k0) * p00, (1.0 - k0) * p01, p11 - k1 * p01]
        self._t = float(t)
        return self._x.copy()


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
