"""The rollouts watched in the scene: the policy playing now, and the last rollout of each policy
watched, kept for download (CSV, MCAP on its robot)."""

from __future__ import annotations

import threading

import numpy as np

from ..scene import Scene

ROLLOUTS_KEPT = 16
"""Policies whose last watched rollout stays downloadable (each at most a megabyte or two)."""


class Rollouts:
    """What a studio's scene plays of the policies, and their last rollouts.

    A policy is named by its key: ``policy:<name>`` (an uploaded one) or ``run:<id>`` (a run's).

    Args:
        scene: the scene the rollouts play in, or None (headless: nothing ever plays).
    """

    def __init__(self, scene: Scene | None) -> None:
        self.scene = scene
        self.lock = threading.Lock()
        self.watching: str | None = None  # "policy:<name>" or "run:<id>" being played
        # the last rollout watched of each policy key: (times, q), the oldest watched first
        self._kept: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    def playing(self, key: str) -> bool:
        """Whether the scene is playing the rollout of policy ``key`` now."""
        return self.watching == key and self.scene is not None and self.scene.playing

    def keep(self, key: str, times: np.ndarray, q: np.ndarray) -> None:
        """Remember the rollout just watched of policy ``key`` (the last :data:`ROLLOUTS_KEPT`
        policies' are kept) and mark it as playing."""
        with self.lock:
            self._kept.pop(key, None)
            self._kept[key] = (times, q)
            while len(self._kept) > ROLLOUTS_KEPT:
                self._kept.pop(next(iter(self._kept)))
            self.watching = key

    def release(self) -> None:
        """Forget which policy plays (a pose shown by hand replaces it)."""
        with self.lock:
            self.watching = None

    def stop(self) -> None:
        """Stop watching: the robot follows the live source again."""
        self.release()
        if self.scene is not None:
            self.scene.stop_playback()

    def forget(self, key: str) -> None:
        """Drop the rollout of policy ``key`` (its file is gone)."""
        with self.lock:
            self._kept.pop(key, None)

    def last(self, key: str | None) -> tuple[str, np.ndarray, np.ndarray] | None:
        """The last rollout watched of policy ``key`` (None: of any policy) as ``(key, times,
        q)``, or None."""
        with self.lock:
            if key is None:
                key = next(reversed(self._kept), None)
            if key is None or key not in self._kept:
                return None
            return (key, *self._kept[key])
