"""The live arm chain, defined once: tape frame -> tape shape -> human arm -> Puma560.

``reconstruct`` turns one frame's bend and twist into the tape's shape, :class:`ArmFitter` fits
the operator's 7-DOF arm to it (warm-started from the previous frame), and :class:`Retargeter`
maps that arm onto the Puma560 (joint or cartesian mode, mirrored by default). The live pipeline
and demonstration extraction both track frames through an :class:`ArmTracker`; a recording, all
at hand, has its fitted arm smoothed with the future rather than the past
(:func:`smooth_recorded_arm`)::

    tracker = ArmTracker(TrackerConfig(tape=recording.config, mode="joint"))
    for bend, twist in zip(recording.bend, recording.twist):
        tracked = tracker.track(bend, twist)  # q_human, q_robot, residual, tape_points, ...
    tracker.reset()  # the next frame starts cold (a new source, a new segment)
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field

import numpy as np

from .._checks import KinematicsError, instance_of, positive_number
from .._puma import IKResult, Puma560
from .._retarget import Mode, RetargetConfig, Retargeter
from ._filter import OneEuroFilter, smooth_constant_velocity, white_noise
from ._fit import ArmFit, ArmFitter, FitConfig
from ._human import HumanArm
from ._tape import TapeConfig, reconstruct

SMOOTHING_CUTOFF_HZ = (3.0, 3.0, 0.5, 3.0, 0.5, 0.5, 0.5)
"""The default cutoffs (Hz) of the fitted arm's smoothing, per joint: shoulder flexion and
abduction, humeral rotation, elbow flexion, forearm rotation, wrist flexion and deviation. A tape
frame sees the humeral rotation poorly near a straight elbow, and the last three hardly at all
(they all turn the hand about the forearm, see ``_fit.py``): they get the lower cutoff. Chosen
on the 3 samples and 3 simulated 7 s reaches at 110 Hz: joints turning back by more than 0.5
degrees between frames 48 times, against 4,377 unsmoothed and 144 with 2 Hz on every joint; the
shoulder and elbow's mean error 0.61 degrees, against 0.31 unsmoothed."""

RECORDED_ACCELERATION = 1.0
"""The default :attr:`TrackerConfig.recorded_acceleration` (rad/s^2 per sqrt(Hz)). Chosen on
three simulated 20 s takes at 110 Hz (seeds 3, 7, 11) against the true arm: the shoulder and
elbow's mean error 0.10 degrees (0.67-0.87 through the live filter, 0.27-0.29 unsmoothed), no
joint turning back by more than 0.5 degrees between frames (7-32 times live). 0.2 erred 0.08
degrees on these smooth simulated reaches; 1 leaves room for a quicker real one (about 7 Hz
passes on a joint with 0.3 degrees of noise, 3 Hz on one with 2 degrees)."""


@dataclass(frozen=True)
class TrackerConfig:
    """Everything that defines the live chain, documented once.

    Attributes:
        tape: the tape and where it lies on the operator (a recording's ``config``).
        mode: retargeting mode at start, ``"joint"`` or ``"cartesian"`` (switchable later
            through :attr:`ArmTracker.mode`).
        mirror: the robot mirrors the operator (the paper's choice).
        fit: the arm fit's solver defaults.
        retarget: the retargeting defaults.
        smoothing_cutoff_hz: the cutoffs (Hz, one per joint of the arm, or one for all) of the
            One Euro filter that smooths the fitted arm in time before it is shown and
            retargeted, for frames tracked with their time (:meth:`ArmTracker.track`'s ``t``);
            None: no smoothing. One frame's fit carries the tape's sensor noise into the joints
            it sees poorly (the humeral rotation near a straight elbow, and the forearm's and
            the wrist's turns about the forearm: :data:`SMOOTHING_CUTOFF_HZ`), about a degree
            back and forth a frame, which the robot's wrist copied. The default smooths those
            at 0.5 Hz and the others at 3 Hz; its lag on a still or slow arm is
            ``1 / (2 pi cutoff)``, 53 ms for the shoulder and elbow (318 ms for the poorly seen
            turns), less the faster the arm moves. Measured by ``benchmarks/bench_kinematics.py``
            (c).
        smoothing_beta: how much that cutoff rises with the arm's speed (Hz per rad/s).
        recorded_acceleration: how fast (rad/s^2 per sqrt(Hz), the white acceleration of a
            constant-velocity model) the arm is taken to change its speed when a recording's
            fitted arm is smoothed with the past and the future (:func:`smooth_recorded_arm`),
            in place of the live filter. See :data:`RECORDED_ACCELERATION`.
    """

    tape: TapeConfig = field(default_factory=TapeConfig)
    mode: Mode = "joint"
    mirror: bool = True
    fit: FitConfig = field(default_factory=FitConfig)
    retarget: RetargetConfig = field(default_factory=RetargetConfig)
    smoothing_cutoff_hz: float | tuple[float, ...] | None = SMOOTHING_CUTOFF_HZ
    smoothing_beta: float = 1.0
    recorded_acceleration: float = RECORDED_ACCELERATION

    def smoothing(self) -> OneEuroFilter | None:
        """A new filter of the fitted arm (None without smoothing)."""
        if self.smoothing_cutoff_hz is None:
            return None
        cutoff = np.asarray(self.smoothing_cutoff_hz, dtype=object)
        if cutoff.shape not in ((), (HumanArm.nq,)) or not all(
            isinstance(c, numbers.Real) and not isinstance(c, bool) and math.isfinite(c) and c > 0
            for c in cutoff.flat
        ):
            raise KinematicsError(
                f"TrackerConfig.smoothing_cutoff_hz must be a positive frequency in Hz or "
                f"{HumanArm.nq} of them, one per joint; got {self.smoothing_cutoff_hz!r}."
            )
        return OneEuroFilter(cutoff.astype(float), self.smoothing_beta)

    def __post_init__(self) -> None:
        for name, kind in (("tape", TapeConfig), ("fit", FitConfig), ("retarget", RetargetConfig)):
            instance_of(getattr(self, name), kind, f"TrackerConfig.{name}")
        if self.mode not in ("joint", "cartesian"):
            raise KinematicsError(
                f'TrackerConfig.mode must be "joint" or "cartesian"; got {self.mode!r}.'
            )
        if not isinstance(self.mirror, bool | np.bool_):
            raise KinematicsError(
                f"TrackerConfig.mirror must be True or False; got {self.mirror!r}."
            )
        self.smoothing()  # a bad cutoff or beta is refused here, in one sentence
        positive_number(self.recorded_acceleration, "TrackerConfig.recorded_acceleration")


@dataclass(frozen=True)
class Tracked:
    """One tracked frame.

    Attributes:
        q_human: the fitted arm's joint angles (rad, (7,)), smoothed in time for a frame tracked
            with its time (:meth:`ArmTracker.track`); the frame's own fit is :attr:`fit`.
        q_robot: the Puma560's joint angles (rad, (6,)), within its limits.
        residual: RMS distance (m) from the tape's arm vertices to the fitted arm.
        success: the arm fit met the tape (:attr:`ArmFit.success`).
        tape_points: the reconstructed tape's vertices ((regions + 1, 3), m, arm base frame).
        fit: the full arm fit (landmarks, landmark error, iterations).
        ik: the Puma560 IK result in cartesian mode (an unreachable hand pose shows here);
            None in joint mode.
    """

    q_human: np.ndarray
    q_robot: np.ndarray
    residual: float
    success: bool
    tape_points: np.ndarray
    fit: ArmFit
    ik: IKResult | None = None


class ArmTracker:
    """Tracks the operator's arm, frame after frame, and mirrors it onto the Puma560.

    Args:
        config: a :class:`TrackerConfig`, or just the :class:`TapeConfig` (other settings at
            their defaults); default: the default tape.
        arm: the operator's arm (default: ``HumanArm(side=config.tape.side)``, the arm the tape
            is strapped to, at the default size).
        robot: the Puma560 (default: the retargeter's, whose IK is capped for the live path).

    Raises:
        KinematicsError: a bad config, or a tape whose regions cannot see the arm.
    """

    def __init__(
        self,
        config: TrackerConfig | TapeConfig | None = None,
        *,
        arm: HumanArm | None = None,
        robot: Puma560 | None = None,
    ) -> None:
        if config is None:
            config = TrackerConfig()
        elif isinstance(config, TapeConfig):
            config = TrackerConfig(tape=config)
        elif not isinstance(config, TrackerConfig):
            raise KinematicsError(
                f"ArmTracker's config must be a TrackerConfig or a TapeConfig, got "
                f"{type(config).__name__}; pass TrackerConfig(tape=...)."
            )
        instance_of(arm, HumanArm, "ArmTracker's arm", optional=True)
        self.config = config
        self.arm = arm if arm is not None else HumanArm(side=config.tape.side)
        self.fitter = ArmFitter(self.arm, config.tape, config.fit)
        self.retargeter = Retargeter(
            config.mode, mirror=config.mirror, robot=robot, arm=self.arm, config=config.retarget
        )
        self._smoothing = config.smoothing()
        self._last: tuple[float, np.ndarray] | None = None  # the last timed frame and its fit

    @property
    def tape(self) -> TapeConfig:
        """The tape being tracked."""
        return self.config.tape

    @property
    def robot(self) -> Puma560:
        """The Puma560 the arm is mirrored onto."""
        return self.retargeter.robot

    @property
    def mode(self) -> Mode:
        """``"joint"`` or ``"cartesian"``; settable at run time (applies from the next frame)."""
        return self.retargeter.mode

    @mode.setter
    def mode(self, value: Mode) -> None:
        self.retargeter.mode = value

    @property
    def mirror(self) -> bool:
        """Whether the robot mirrors the operator; settable at run time."""
        return self.retargeter.mirror

    @mirror.setter
    def mirror(self, value: bool) -> None:
        self.retargeter.mirror = value

    def reset(self) -> None:
        """Forget the previous frame: the next fit and cartesian IK start cold."""
        self.fitter.reset()
        self.retargeter.reset()
        self._restart_smoothing()

    def _restart_smoothing(self) -> None:
        self._last = None
        if self._smoothing is not None:
            self._smoothing.reset()

    def _smoothed(self, t: float, q_fit: np.ndarray) -> np.ndarray:
        """The fitted arm smoothed in time (see :attr:`TrackerConfig.smoothing_cutoff_hz`).

        A frame no later than the last (a source started again) or a fit that changed its
        shoulder branch (:attr:`FitConfig.branch_jump`) starts the filter afresh: no arm is
        drawn halfway between two branches.
        """
        if self._smoothing is None:
            return q_fit
        if isinstance(t, bool) or not isinstance(t, numbers.Real) or not math.isfinite(t):
            raise KinematicsError(f"ArmTracker.track's t must be a finite time in s; got {t!r}.")
        t = float(t)
        last = self._last
        if last is not None and (
            not t > last[0] or abs(q_fit[0] - last[1][0]) > self.config.fit.branch_jump
        ):
            self._smoothing.reset()
        self._last = (t, q_fit)
        return self._smoothing(t, q_fit)

    def track(self, bend: object, twist: object, t: float | None = None) -> Tracked:
        """Track one frame.

        Args:
            bend: bend angle per region (rad, ``(regions,)``).
            twist: twist angle per region (rad, ``(regions,)``).
            t: the frame's time (s): given, the fitted arm is smoothed in time over the frames
                tracked with theirs (:attr:`TrackerConfig.smoothing_cutoff_hz`); None, the
                frame's fit alone (and the smoothing starts afresh at the next timed frame).

        Returns:
            The arm, the robot and the tape of this frame, warm-started from the previous one.

        Raises:
            KinematicsError: wrong shapes or non-finite angles.
        """
        shape = reconstruct(bend, twist, self.config.tape)
        if shape.positions.ndim != 2:
            raise KinematicsError(
                f"ArmTracker.track takes one frame: bend and twist of shape "
                f"({self.config.tape.regions},); got a batch {shape.positions.shape[:-2]}; "
                "track the frames one by one."
            )
        fit = self.fitter.fit(shape)
        if t is None:
            self._restart_smoothing()
            q_human = fit.q_human
        else:
            q_human = self._smoothed(t, fit.q_human)
        q_robot = self.retargeter.robot_from_human(q_human)
        return Tracked(
            q_human=q_human,
            q_robot=np.asarray(q_robot, dtype=np.float64),
            residual=float(fit.residual),
            success=bool(fit.success),
            tape_points=shape.positions,
            fit=fit,
            ik=self.retargeter.last_ik if self.retargeter.mode == "cartesian" else None,
        )


def smooth_recorded_arm(
    times: object, q_human: object, config: TrackerConfig | None = None
) -> np.ndarray:
    """A recording's fitted arm ``(N, 7)``, each frame's own fit, smoothed with the past and the
    future: for a recording, where every frame is at hand, in place of the live filter
    (:attr:`TrackerConfig.smoothing_cutoff_hz`), which lags the arm to smooth it.

    Each joint goes through a constant-velocity smoother (:func:`smooth_constant_velocity`,
    acceleration :attr:`TrackerConfig.recorded_acceleration`) with the noise its own frames show
    (:func:`white_noise`): the tape's sensor noise reaches the joints a frame sees poorly (the
    humeral rotation near a straight elbow, the forearm's and wrist's turns) many times over.
    The frames are smoothed in runs, cut where the time does not increase (a source started
    again) and where the fit changed its shoulder branch (:attr:`FitConfig.branch_jump`), as
    the live filter starts afresh there: no arm lies halfway between two branches.

    Args:
        times: the frames' times (s), shape (N,).
        q_human: each frame's fitted arm (rad), shape (N, 7).
        config: the tracker's settings (default: ``TrackerConfig()``).

    Returns:
        The smoothed arm, shape (N, 7); a run of fewer than 3 frames as fitted.
    """
    config = config if config is not None else TrackerConfig()
    t = np.asarray(times, dtype=float)
    q = np.asarray(q_human, dtype=float)
    if t.ndim != 1 or q.shape != (len(t), HumanArm.nq):
        raise KinematicsError(
            f"smooth_recorded_arm takes one time per frame and {HumanArm.nq} joints a frame; "
            f"got {t.shape} times and angles of shape {q.shape}."
        )
    cuts = np.flatnonzero(~(np.diff(t) > 0.0) | (np.abs(np.diff(q[:, 0])) > config.fit.branch_jump))
    out = q.copy()
    for start, stop in zip(np.r_[0, cuts + 1], np.r_[cuts + 1, len(t)], strict=True):
        if stop - start < 3:
            continue
        run = q[start:stop]
        noise = np.maximum(white_noise(run), SMOOTHED_NOISE_FLOOR)
        out[start:stop] = smooth_constant_velocity(
            t[start:stop], run, noise, config.recorded_acceleration
        )
    return out


SMOOTHED_NOISE_FLOOR = 1e-5
"""The least noise (rad) a joint is smoothed with: a joint that never moves shows none, and the
smoother needs some."""
