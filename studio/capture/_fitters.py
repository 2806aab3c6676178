"""One fitter per observation kind, into the 7-joint human arm, then the one retargeting.

Every teacher ends in the same ``q_human``; every robot starts from it. The live pipeline and
demonstration extraction both fit through :func:`fitter_for`; a recording's frames, all at hand,
are smoothed with the future as well (:func:`fit_frames`), so a demonstration cut from a
recording, its export and its timeline follow the person more closely than the live scene could:

- tape frames: the kinematics package's :class:`~studio.kinematics.ArmTracker` (reconstruct, fit
  the arm to the tape, retarget); a recording's fitted arm smoothed with the future
  (:meth:`TapeFitter.fit_recorded`);
- pose landmarks: :class:`~studio.kinematics.PoseStreamFitter` (Kalman filtered, joints the
  camera cannot see held smoothly), then a :class:`~studio.kinematics.Retargeter`; a
  recording's landmarks smoothed with the future (:meth:`LandmarkFitter.fit_recorded`);
- hand poses: :func:`~studio.kinematics.fit_hand_pose` (damped least squares on the arm within
  its limits, seeded with the previous solution), then the same retargeting.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Protocol, runtime_checkable

import numpy as np
import viser.transforms as vtf

from studio.kinematics import (
    ArmTracker,
    HumanArm,
    KinematicsError,
    Retargeter,
    TapeConfig,
    TrackerConfig,
    smooth_landmarks,
    smooth_recorded_arm,
)

from ._observations import HUMAN_JOINTS, HandPose, LandmarkFrame, Observation, TapeFrame

ARM_LANDMARKS = {"right": (12, 14, 16), "left": (11, 13, 15)}
"""MediaPipe Pose's shoulder, elbow and wrist landmarks of the person's right and left arm."""
MIN_VISIBILITY = 0.5
"""An arm landmark less visible than this (MediaPipe's visibility) counts as out of the picture."""


@dataclass(frozen=True)
class Fitted:
    """One observation fitted and retargeted.

    Attributes:
        q_human: the human arm's joints (rad, (7,)).
        q_robot: the Puma560's joints (rad, (6,)), within its limits.
        residual: how far the arm misses the observation (m): the tape's RMS distance, the
            landmarks' residual, or the hand's distance from its target.
        success: the fit met the observation (tape: :attr:`ArmFit.success`; hand: within 1 cm).
        tape_points: the reconstructed tape (tape frames only), arm base frame, m.
        observable: which joints the observation determined (landmarks only).
        warning: one sentence when the fit cannot follow (no person, the arm out of the picture,
            a hand out of reach, the tape off the arm), else None.
    """

    q_human: np.ndarray
    q_robot: np.ndarray
    residual: float
    success: bool
    tape_points: np.ndarray | None = None
    observable: np.ndarray | None = None
    warning: str | None = None


@runtime_checkable
class ObservationFitter(Protocol):
    """Fits one observation kind into the human arm and retargets it (``mode``/``mirror``
    switchable at run time, from the next observation)."""

    mode: str
    mirror: bool

    def fit(self, observation: Observation) -> Fitted:
        """The arm and robot for this observation (warm-started from the previous one)."""

    def reset(self) -> None:
        """Forget the previous observations (a new source or segment starts cold)."""


def tape_fit_warning(residual_m: float) -> str:
    """What to tell the user when the arm model cannot follow the tape."""
    return (
        f"The arm model misses the tape by {residual_m * 1000.0:.0f} mm (RMS); check that the "
        "tape lies along the arm and that its shoulder and wrist regions fit this operator."
    )


FIT_WARNING_AFTER_S = 0.5
"""The arm model must miss the tape by more than the fit's ``max_residual`` for this long (in the
tape's own time) before the user is warned: a tape that lies wrong stays wrong, while sensor noise
and an arm passing through a hard pose last a few frames."""
FIT_WARNING_CLEAR_FRACTION = 0.5
"""Once shown, the warning stays until the residual falls below this fraction of ``max_residual``,
so a residual hovering at the threshold shows one steady warning instead of a flickering one."""


class FitWatch:
    """Decides, frame by frame, whether the arm fit is bad enough to tell the user.

    The warning is about what it says, the residual: it shows once the residual has stayed above
    the fit's ``max_residual`` for :data:`FIT_WARNING_AFTER_S`, and clears once it falls below
    :data:`FIT_WARNING_CLEAR_FRACTION` of it. The threshold is the fitter's own (one definition,
    :class:`studio.kinematics.FitConfig`), set above what sensor noise gives: a tape with the
    simulator's noise (0.002 rad per angle) is fitted to 2 mm RMS typically and under 13 mm at
    worst. A single frame whose fit misses its landmarks by a millimetre is not a warning.

    Args:
        max_residual: the fit's ``max_residual`` (m).
    """

    def __init__(self, max_residual: float) -> None:
        self.on = float(max_residual)
        self.off = float(max_residual) * FIT_WARNING_CLEAR_FRACTION
        self._above_since: float | None = None
        self.warning: str | None = None

    def update(self, t: float, residual: float) -> str | None:
        """Take the residual (m) of the frame at time ``t`` (s); return the warning to show."""
        if residual > self.on:
            if self._above_since is None or t < self._above_since:  # a looped recording restarts
                self._above_since = t
            if t - self._above_since >= FIT_WARNING_AFTER_S or self.warning is not None:
                self.warning = tape_fit_warning(residual)
            return self.warning
        self._above_since = None
        if self.warning is not None and residual < self.off:
            self.warning = None
        elif self.warning is not None:
            self.warning = tape_fit_warning(residual)
        return self.warning


class TapeFitter:
    """Tape frames through the kinematics package's :class:`ArmTracker`."""

    def __init__(self, tape: TapeConfig, mode: str = "joint", mirror: bool = True) -> None:
        self.tracker = ArmTracker(TrackerConfig(tape=tape, mode=mode, mirror=mirror))
        self.watch = FitWatch(self.tracker.config.fit.max_residual)

    mode = property(
        lambda self: self.tracker.mode, lambda self, v: setattr(self.tracker, "mode", v)
    )
    mirror = property(
        lambda self: self.tracker.mirror, lambda self, v: setattr(self.tracker, "mirror", v)
    )

    def fit(self, observation: Observation) -> Fitted:
        assert isinstance(observation, TapeFrame)
        tracked = self.tracker.track(observation.bend, observation.twist, observation.t)
        return Fitted(
            tracked.q_human,
            tracked.q_robot,
            float(tracked.residual),
            bool(tracked.success),
            tape_points=tracked.tape_points,
            warning=self.watch.update(float(observation.t), float(tracked.residual)),
        )

    def fit_recorded(self, observations: Sequence[Observation]) -> list[Fitted]:
        """A recording's tape frames, each fitted on its own in order, the fitted arm then
        smoothed with the past and the future (:func:`~studio.kinematics.smooth_recorded_arm`)
        in place of the live filter, and retargeted."""
        frames = list(observations)
        tracked = []
        for frame in frames:
            assert isinstance(frame, TapeFrame)
            tracked.append(self.tracker.track(frame.bend, frame.twist))  # no time: its own fit
        if not frames:
            return []
        times = [frame.t for frame in frames]
        q_human = smooth_recorded_arm(times, [x.q_human for x in tracked], self.tracker.config)
        retargeter = self.tracker.retargeter
        retargeter.reset()
        return [
            Fitted(
                q,
                np.asarray(retargeter.robot_from_human(q), dtype=np.float64),
                float(x.residual),
                bool(x.success),
                tape_points=x.tape_points,
                warning=self.watch.update(float(t), float(x.residual)),
            )
            for q, x, t in zip(q_human, tracked, times, strict=True)
        ]

    def reset(self) -> None:
        self.tracker.reset()
        self.watch = FitWatch(self.tracker.config.fit.max_residual)


class _Retargeted:
    """The shared part of the landmark and hand fitters: the arm, its retargeting, the last pose."""

    def __init__(self, side: str, mode: str, mirror: bool) -> None:
        self.arm = HumanArm(side=side)  # checks the side
        self.side = self.arm.side
        self.retargeter = Retargeter(mode, mirror=mirror, arm=self.arm)
        self.q_human = np.zeros(HUMAN_JOINTS)

    mode = property(
        lambda self: self.retargeter.mode, lambda self, v: setattr(self.retargeter, "mode", v)
    )
    mirror = property(
        lambda self: self.retargeter.mirror,
        lambda self, v: setattr(self.retargeter, "mirror", v),
    )

    def _fitted(
        self, q_human: np.ndarray, residual: float, success: bool, **extra: object
    ) -> Fitted:
        self.q_human = np.array(q_human, dtype=float)
        q_robot = self.retargeter.robot_from_human(self.q_human)
        return Fitted(self.q_human.copy(), q_robot, float(residual), success, **extra)  # type: ignore[arg-type]

    def reset(self) -> None:
        self.q_human = np.zeros(HUMAN_JOINTS)
        self.retargeter.reset()


def arm_out_of_view(frame: LandmarkFrame, side: str) -> bool:
    """Whether the ``side`` arm's shoulder, elbow or wrist is outside the picture or hidden."""
    if frame.world is None:
        return True
    rows = list(ARM_LANDMARKS[side])
    if frame.image is not None:
        xy, visibility = frame.image[rows, :2], frame.image[rows, 2]
        inside = ((xy >= 0.0) & (xy <= 1.0)).all(axis=1)
        return bool(not (inside & (visibility >= MIN_VISIBILITY)).all())
    return bool((frame.world[rows, 3] < MIN_VISIBILITY).any())


def no_person_warning() -> str:
    """What to say when the camera sees no one."""
    return "No person in view; stand facing the camera, about two metres away, with your upper body in the picture."


def arm_out_warning(side: str) -> str:
    """What to say when the teaching arm is out of the picture."""
    return f"Your {side} arm is out of the picture; step back or turn so the camera sees it from shoulder to wrist."


class LandmarkFitter(_Retargeted):
    """Pose landmark frames through :class:`~studio.kinematics.PoseStreamFitter`; frames without
    a person or with the arm out of the picture hold the last pose and say why."""

    def __init__(self, side: str = "right", mode: str = "joint", mirror: bool = True) -> None:
        super().__init__(side, mode, mirror)
        from studio.kinematics import PoseStreamFitter

        self.stream = PoseStreamFitter(side=self.side)

    def fit(self, observation: Observation) -> Fitted:
        return self._fit(observation, smoothed=False)

    def fit_recorded(self, observations: Sequence[Observation]) -> list[Fitted]:
        """A recording's frames, fitted in order, each run of frames that show the arm
        smoothed with the past and the future first (:func:`~studio.kinematics.smooth_landmarks`).

        A run ends where the person or the arm leaves the picture, or at a gap longer than
        ``StreamConfig.max_gap_s``; a frame outside every run is fitted as live.
        """
        frames = list(observations)
        smoothed = [False] * len(frames)
        for run in self._runs(frames):
            in_run = [frames[i] for i in run]
            first = in_run[0]
            assert isinstance(first, LandmarkFrame)
            times = np.array([f.t for f in in_run])
            world = np.array([f.world for f in in_run])
            image = np.array([f.image for f in in_run]) if first.image is not None else None
            size = np.array([(f.width, f.height) for f in in_run], dtype=float)
            try:
                world, image = smooth_landmarks(times, world, image, size, self.stream.config)
            except KinematicsError:  # left as recorded, fitted as live
                continue
            for k, i in enumerate(run):
                frame = frames[i]
                assert isinstance(frame, LandmarkFrame)
                frames[i] = replace(
                    frame, world=world[k], image=None if image is None else image[k]
                )
                smoothed[i] = True
        return [self._fit(f, smoothed=s) for f, s in zip(frames, smoothed, strict=True)]

    def _runs(self, frames: list[Observation]) -> list[list[int]]:
        """Index runs of two or more frames that show the arm, one picture size, no long gap."""
        runs: list[list[int]] = []
        last: LandmarkFrame | None = None
        for i, frame in enumerate(frames):
            assert isinstance(frame, LandmarkFrame)
            if frame.world is None or arm_out_of_view(frame, self.side):
                last = None
                continue
            joins = (
                last is not None
                and 0.0 < frame.t - last.t <= self.stream.config.max_gap_s
                and (frame.image is None) == (last.image is None)
                and (frame.width, frame.height) == (last.width, last.height)
            )
            if joins:
                runs[-1].append(i)
            else:
                runs.append([i])
            last = frame
        return [run for run in runs if len(run) > 1]

    def _fit(self, observation: Observation, smoothed: bool) -> Fitted:
        assert isinstance(observation, LandmarkFrame)
        frame = observation
        hidden = np.zeros(HUMAN_JOINTS, dtype=bool)
        if frame.world is None:
            return self._fitted(
                self.q_human, 0.0, False, observable=hidden, warning=no_person_warning()
            )
        warning = arm_out_warning(self.side) if arm_out_of_view(frame, self.side) else None
        try:
            pose = self.stream.update(
                frame.t,
                frame.world,
                image_landmarks=frame.image,
                image_size=(frame.width, frame.height),
                smoothed=smoothed,
            )
        except KinematicsError as err:  # the arm not seen, or landmarks the fit refuses
            why = warning or str(err)
            return self._fitted(self.q_human, 0.0, False, observable=hidden, warning=why)
        observable = np.asarray(pose.observable, dtype=bool)
        return self._fitted(
            pose.q_human,
            float(pose.residual),
            warning is None,
            observable=observable,
            warning=warning,
        )

    def reset(self) -> None:
        super().reset()
        self.stream.reset()


def hand_matrix(position: np.ndarray, wxyz: np.ndarray) -> np.ndarray:
    """The 4x4 pose of a hand at ``position`` with orientation ``wxyz``."""
    out = np.eye(4)
    out[:3, :3] = vtf.SO3(np.asarray(wxyz, dtype=float)).as_matrix()
    out[:3, 3] = position
    return out


class HandFitter(_Retargeted):
    """Hand poses through :func:`~studio.kinematics.fit_hand_pose`, seeded with the last arm."""

    def fit(self, observation: Observation) -> Fitted:
        assert isinstance(observation, HandPose)
        from studio.kinematics import fit_hand_pose

        target = hand_matrix(observation.position, observation.wxyz)
        hand = fit_hand_pose(target, side=self.side, q_seed=self.q_human)
        warning = None
        if not hand.reached:
            warning = (
                f"The hand cannot reach that point ({hand.position_error_m * 100:.0f} cm short); "
                "the arm stops at its nearest pose: drag the handle closer to the shoulder."
            )
        return self._fitted(
            hand.q_human, hand.position_error_m, bool(hand.reached), warning=warning
        )


def fit_frames(fitter: ObservationFitter, observations: Sequence[Observation]) -> list[Fitted]:
    """A recording's observations fitted in order by ``fitter``.

    A recording has every frame at hand, where a live source has only the past, so what is cut
    or exported from it, and its timeline, follow the person more closely than the live scene
    did (played back as a source, it runs through the live fit again): landmark frames are
    smoothed with the future before the fit (:meth:`LandmarkFitter.fit_recorded`), and a tape's
    fitted arm after it (:meth:`TapeFitter.fit_recorded`). Hand poses, which carry no sensor
    noise, are fitted one by one, as live.
    """
    if isinstance(fitter, LandmarkFitter | TapeFitter):
        return fitter.fit_recorded(observations)
    return [fitter.fit(observation) for observation in observations]


def fitter_for(
    observation: Observation,
    *,
    tape: TapeConfig | None = None,
    side: str | None = None,
    mode: str = "joint",
    mirror: bool = True,
) -> ObservationFitter:
    """The fitter for ``observation``'s kind.

    Args:
        observation: the first observation of a stream (its type picks the fitter).
        tape: the tape config (tape frames; default: the default tape).
        side: the teaching arm for landmarks and hand poses (default: the tape's side).
        mode: retargeting mode, ``"joint"`` or ``"cartesian"``.
        mirror: the robot mirrors the operator.
    """
    tape = tape if tape is not None else TapeConfig()
    side = side or tape.side
    if isinstance(observation, LandmarkFrame):
        return LandmarkFitter(side, mode, mirror)
    if isinstance(observation, HandPose):
        return HandFitter(side, mode, mirror)
    return TapeFitter(tape, mode, mirror)
