"""Fit the human arm to a stream of MediaPipe Pose landmarks (a camera source).

Each frame's landmarks pass a One Euro filter (:class:`OneEuroFilter`) before the fit of
:func:`fit_pose_landmarks`; the depth, several times noisier than x and y in MediaPipe's world
landmarks, gets a lower cutoff. The limb lengths the fit refines the arm at are the running
median of the lengths measured in recent frames. Joints the landmarks show weakly (humeral
rotation with a nearly straight elbow, forearm rotation with the palm's axis along the hand) move
toward their reading only by a fraction that shrinks with how weakly they are seen; joints not
seen at all (the wrist with the hand out of view) hold the previous frame's angle. So the arm
never jumps where the landmarks say little.

The torso's frame is read from a second, slower filter of the same landmarks: the body turns
slowly, and its yaw, read from depth differences across the shoulders and hips, is noisy.

Lag: for slow motion the filter delays the landmarks by ``1 / (2 pi min_cutoff)`` (the depth's,
the largest), whatever the frame rate; faster motion raises the cutoff and lowers the lag.
:attr:`PoseStreamFitter.lag_s` reports it (0.27 s by default; measured on the benchmark's
motion, the fitted elbow trails the true one by about 0.13 s).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from ._checks import check_side, instance_of, positive_number, whole_number
from ._errors import KinematicsError
from ._filter import OneEuroFilter
from ._pose import (
    FOREARM_ROTATION,
    HUMERAL_ROTATION,
    N_LANDMARKS,
    PoseConfig,
    PoseFit,
    _check_landmarks,
    _read,
    check_arm_seen,
    default_arm,
    fit_reading,
)


@dataclass(frozen=True)
class StreamConfig:
    """Defaults of the landmark stream's filtering, documented once.

    Attributes:
        min_cutoff_hz: the One Euro filter's cutoff for still landmarks' x and y (and the
            image landmarks); 1 Hz: a lag of 0.16 s for slow motion.
        depth_cutoff_hz: its cutoff for the world landmarks' depth (noisier: lower).
        beta: how much the cutoff rises with a landmark's speed (Hz per m/s); small, because
            MediaPipe's frame-to-frame jitter reads as speed (at 3 cm, about 1 m/s at 30 Hz).
        d_cutoff_hz: cutoff of the speed estimate.
        torso_cutoff_hz: cutoff of the landmarks the torso's frame is read from (the body turns
            slowly; its yaw, read from depth differences across the shoulders, is noisy).
        max_gap_s: a gap between frames longer than this restarts the filter (the person left
            and came back: no smoothing across).
        length_frames: the limb lengths are the median over this many recent frames.
        weak_gain: a weakly seen joint moves this fraction of the way to its reading per frame
            at the edge of observability, less the more weakly it is seen.
        pose: the per-frame fit's defaults.
    """

    min_cutoff_hz: float = 1.0
    depth_cutoff_hz: float = 0.6
    beta: float = 0.3
    d_cutoff_hz: float = 1.0
    torso_cutoff_hz: float = 0.3
    max_gap_s: float = 1.0
    length_frames: int = 90
    weak_gain: float = 0.2
    pose: PoseConfig = field(default_factory=PoseConfig)

    def __post_init__(self) -> None:
        for name in (
            "min_cutoff_hz",
            "depth_cutoff_hz",
            "d_cutoff_hz",
            "torso_cutoff_hz",
            "max_gap_s",
        ):
            positive_number(getattr(self, name), f"StreamConfig.{name}")
        for name in ("beta", "weak_gain"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise KinematicsError(f"StreamConfig.{name} must be a number >= 0; got {value!r}.")
        whole_number(self.length_frames, "StreamConfig.length_frames", 1)
        instance_of(self.pose, PoseConfig, "StreamConfig.pose")


class PoseStreamFitter:
    """Fits one side's arm to landmark frames as they arrive, filtered and held smoothly.

    Args:
        side: the person's arm to fit, ``"right"`` or ``"left"``.
        config: filtering defaults.

    Raises:
        KinematicsError: a bad side or config.
    """

    def __init__(self, side: str = "right", config: StreamConfig | None = None) -> None:
        self.side = check_side(side, "PoseStreamFitter's side")
        instance_of(config, StreamConfig, "PoseStreamFitter's config", optional=True)
        self.config = config or StreamConfig()
        self.arm = default_arm(self.side)
        self._data = self.arm.model.createData()
        cfg = self.config
        cutoff = np.empty((N_LANDMARKS, 3))
        cutoff[:, :2] = cfg.min_cutoff_hz
        cutoff[:, 2] = cfg.depth_cutoff_hz
        self._world = OneEuroFilter(cutoff, cfg.beta, cfg.d_cutoff_hz)
        self._image = OneEuroFilter(cfg.min_cutoff_hz, cfg.beta, cfg.d_cutoff_hz)
        self._torso = OneEuroFilter(cfg.torso_cutoff_hz, 0.0, cfg.d_cutoff_hz)
        self._lengths: deque[np.ndarray] = deque(maxlen=cfg.length_frames)
        self.reset()

    @property
    def lag_s(self) -> float:
        """The filter's lag (s) for slow motion, the largest it adds (faster motion: less).

        ``1 / (2 pi depth_cutoff_hz)`` with the defaults (0.27 s), the same at any frame rate.
        The torso's frame, filtered more, follows a turning body with ``1 / (2 pi
        torso_cutoff_hz)`` (0.53 s); the arm's own motion is not delayed by it.
        """
        return self._world.lag_s()

    def reset(self) -> None:
        """Forget the past frames: a new person, a new source."""
        self._world.reset()
        self._image.reset()
        self._torso.reset()
        self._lengths.clear()
        self._t: float | None = None
        self._q: np.ndarray | None = None
        self._had_image = False

    def update(
        self,
        t: float,
        landmarks: object,
        image_landmarks: object = None,
        image_size: tuple[float, float] | None = None,
    ) -> PoseFit:
        """Fit one frame.

        Args:
            t: the frame's time (s), increasing from frame to frame.
            landmarks: world landmarks, as :func:`fit_pose_landmarks` takes them.
            image_landmarks: optional image landmarks of the same frame.
            image_size: ``(width, height)`` in pixels, with image landmarks.

        Returns:
            A :class:`PoseFit` of the filtered landmarks; ``observable`` is this frame's.

        Raises:
            KinematicsError: bad landmarks, a missing arm or a time that does not increase;
                the fitter's state is unchanged then.
        """
        if not (isinstance(t, int | float) and math.isfinite(t)):
            raise KinematicsError(
                f"The frame's time must be a finite number of seconds; got {t!r}."
            )
        world, pixels, size, visibility = _check_landmarks(landmarks, image_landmarks, image_size)
        cfg = self.config
        check_arm_seen(visibility, self.side, cfg.pose)
        if self._t is not None and t <= self._t:
            raise KinematicsError(
                f"The frame's time {t} s does not follow the previous frame's {self._t} s; "
                "give increasing times (or reset the fitter for a new source)."
            )
        if self._t is not None and t - self._t > cfg.max_gap_s:
            self.reset()
        if (pixels is not None) != self._had_image:
            self._image.reset()
            self._had_image = pixels is not None
        torso = self._torso(t, world)
        world = self._world(t, world)
        if pixels is not None:
            pixels = self._image(t, pixels)
        self._t = float(t)
        lengths = np.median(self._lengths, axis=0) if self._lengths else None
        reading = _read(world, pixels, size, visibility, self.side, cfg.pose, lengths, torso)
        self._lengths.append(reading.lengths)
        q_hold = self.arm.neutral.copy() if self._q is None else self._q
        fit = fit_reading(reading, self.arm, self._data, cfg.pose, q_hold)
        q = fit.q_human.copy()
        if self._q is not None:
            gains = self._weak_gains(reading, fit.observable)
            q = self._q + gains * (q - self._q)
        self._q = q
        return PoseFit(
            q_human=q.copy(),
            observable=fit.observable,
            residual=fit.residual,
            points=fit.points,
            hand_seen=fit.hand_seen,
        )

    def _weak_gains(self, reading: object, observable: np.ndarray) -> np.ndarray:
        """Per joint, the fraction of the way to this frame's reading the arm moves."""
        cfg, pose = self.config, self.config.pose
        gains = np.ones(len(observable))
        flexion = math.acos(float(np.clip(reading.upper @ reading.fore, -1.0, 1.0)))
        strength = {
            HUMERAL_ROTATION: (math.sin(flexion) / math.sin(pose.bent_elbow)) ** 2,
            FOREARM_ROTATION: (reading.palm_sine / pose.palm_axis) ** 2,
        }
        for joint, seen in strength.items():
            if not observable[joint]:
                gains[joint] = cfg.weak_gain * min(seen, 1.0)
        return gains
