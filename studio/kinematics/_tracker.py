"""The live arm chain, defined once: tape frame -> tape shape -> human arm -> Puma560.

``reconstruct`` turns one frame's bend and twist into the tape's shape, :class:`ArmFitter` fits
the operator's 7-DOF arm to it (warm-started from the previous frame), and :class:`Retargeter`
maps that arm onto the Puma560 (joint or cartesian mode, mirrored by default). The live pipeline
and demonstration extraction both track frames through an :class:`ArmTracker`, so the robot pose
the page shows live is the pose a demonstration cut from the same frames records::

    tracker = ArmTracker(TrackerConfig(tape=recording.config, mode="joint"))
    for bend, twist in zip(recording.bend, recording.twist):
        tracked = tracker.track(bend, twist)  # q_human, q_robot, residual, tape_points, ...
    tracker.reset()  # the next frame starts cold (a new source, a new segment)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._checks import instance_of
from ._errors import KinematicsError
from ._fit import ArmFit, ArmFitter, FitConfig
from ._human import HumanArm
from ._puma import IKResult, Puma560
from ._retarget import Mode, RetargetConfig, Retargeter
from ._tape import TapeConfig, reconstruct


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
    """

    tape: TapeConfig = field(default_factory=TapeConfig)
    mode: Mode = "joint"
    mirror: bool = True
    fit: FitConfig = field(default_factory=FitConfig)
    retarget: RetargetConfig = field(default_factory=RetargetConfig)

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


@dataclass(frozen=True)
class Tracked:
    """One tracked frame.

    Attributes:
        q_human: the fitted arm's joint angles (rad, (7,)).
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

    def track(self, bend: object, twist: object) -> Tracked:
        """Track one frame.

        Args:
            bend: bend angle per region (rad, ``(regions,)``).
            twist: twist angle per region (rad, ``(regions,)``).

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
        q_robot = self.retargeter.robot_from_human(fit.q_human)
        return Tracked(
            q_human=fit.q_human,
            q_robot=np.asarray(q_robot, dtype=np.float64),
            residual=float(fit.residual),
            success=bool(fit.success),
            tape_points=shape.positions,
            fit=fit,
            ik=self.retargeter.last_ik if self.retargeter.mode == "cartesian" else None,
        )
