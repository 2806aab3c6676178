"""The One Euro filter: low jitter when still, low lag when moving.

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
