"""The simulated operator: a 7-DOF arm making natural reaching motions, seen through a ShapeTape.

The operator moves between poses along minimum-jerk paths (Flash & Hogan's model of human
reaching), pauses now and then, and trembles slightly (physiological tremor, 8-12 Hz). The tape
strapped along the arm (:func:`studio.kinematics.tape_from_arm`) turns each pose into bend/twist
angles, plus sensor noise. Poses are drawn as Puma560 configurations (within a fraction of its
joint ranges) mapped back onto the human arm by the joint-mode :class:`Retargeter`, so the
operator's motion, mirrored onto the robot, stays inside the robot's range (any segment can become
a demonstration); :meth:`OperatorMotion.reach` ends the motion at the pose that maps onto a given
robot goal.

Two ways to run it: :class:`SimulatorSource` (a live source paced at 110 Hz with absolute
deadlines) and :func:`simulate` (as fast as possible, for tests, samples and benchmarks). Both
give the same frames for the same seed.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from ._errors import CaptureError
from ._observations import TRIGGER_BIT, TapeFrame
from ._recording_format import DEFAULT_RATE_HZ
from ._source import DEFAULT_QUEUE_FRAMES, ThreadedSource

if TYPE_CHECKING:
    from studio.kinematics import HumanArm, Retargeter, TapeConfig

CHUNK_SECONDS = 0.1
"""The live source computes frames this far ahead in one vectorised batch."""


@dataclass(frozen=True)
class OperatorConfig:
    """How the simulated operator moves and how noisy the tape is.

    Attributes:
        move_seconds: range of a reaching movement's duration (s).
        pause_seconds: range of a pause's duration (s).
        pause_probability: chance of a pause after each movement.
        robot_range_fraction: targets are drawn within this fraction of the Puma560's ranges of
            joints 1-3 (about their middle), so retargeted motion keeps off the robot's limits.
        wrist_range_fraction: the same for the robot's wrist joints 4-6.
        tremor_rad: amplitude of the tremor per joint (rad).
        tremor_hz: frequency range of the tremor (physiological tremor is 8-12 Hz).
        noise_rad: standard deviation of the tape's sensor noise per angle (rad).
        hold_seconds: how long :func:`simulate` holds still at a goal before it ends.
    """

    move_seconds: tuple[float, float] = (1.0, 2.0)
    pause_seconds: tuple[float, float] = (0.2, 0.8)
    pause_probability: float = 0.5
    robot_range_fraction: float = 0.6
    wrist_range_fraction: float = 0.3
    tremor_rad: float = 0.002
    tremor_hz: tuple[float, float] = (8.0, 12.0)
    noise_rad: float = 0.002
    hold_seconds: float = 0.5


def minimum_jerk(s: np.ndarray) -> np.ndarray:
    """The minimum-jerk profile ``10 s^3 - 15 s^4 + 6 s^5`` for normalised time ``s`` in [0, 1]."""
    s = np.clip(s, 0.0, 1.0)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s * s)


class OperatorMotion:
    """The operator's arm pose over time, sampled frame by frame (deterministic for a seed).

    Args:
        seed: seed of the motion's random draws.
        rate_hz: frames per second.
        operator: motion settings.
        arm: the operator's :class:`studio.kinematics.HumanArm` (default: the retargeter's, else
            a right arm).
        retargeter: the joint-mode :class:`studio.kinematics.Retargeter` that maps robot poses
            onto the arm (default: mirrored, for ``arm``).
    """

    def __init__(
        self,
        seed: int = 0,
        rate_hz: float = DEFAULT_RATE_HZ,
        operator: OperatorConfig | None = None,
        arm: HumanArm | None = None,
        retargeter: Retargeter | None = None,
    ) -> None:
        from studio.kinematics import HumanArm, Retargeter

        self.operator = operator or OperatorConfig()
        self.rate_hz = float(rate_hz)
        if arm is None:
            arm = retargeter.arm if retargeter is not None else HumanArm("right")
        self.arm = arm
        self.retargeter = retargeter or Retargeter("joint", mirror=True, arm=self.arm)
        self.robot = self.retargeter.robot
        self._rng = np.random.default_rng(seed)
        op = self.operator
        self._tremor_freq = self._rng.uniform(*op.tremor_hz, size=(2, self.arm.nq))
        self._tremor_phase = self._rng.uniform(0.0, 2 * np.pi, size=(2, self.arm.nq))
        self._lock = threading.Lock()
        self.k = 0  # next frame index
        start = self._random_target()
        # the current segment: (from pose, to pose, start frame, length in frames), where a
        # positive length is a minimum-jerk movement, a negative one a pause of that many frames,
        # and zero a hold at a reach's goal
        self._segment = (start, start, 0, 0)
        self._goal: np.ndarray | None = None
        self._holding = False

    # targets -----------------------------------------------------------------------------------
    def _random_target(self) -> np.ndarray:
        op = self.operator
        lower, upper = self.robot.lower, self.robot.upper
        mid, half = (lower + upper) / 2, (upper - lower) / 2
        fraction = np.full(self.robot.nq, op.wrist_range_fraction)
        fraction[:3] = op.robot_range_fraction
        q_robot = mid + self._rng.uniform(-1.0, 1.0, self.robot.nq) * fraction * half
        margin = GOAL_MARGIN_RAD  # keep off the arm's limits, where the fit is singular
        return np.clip(self.human_of(q_robot), self.arm.lower + margin, self.arm.upper - margin)

    def human_of(self, q_robot: np.ndarray) -> np.ndarray:
        """The human pose whose joint-mode retargeting is ``q_robot`` (within the arm's limits)."""
        q_human = np.asarray(self.retargeter.human_from_robot(np.asarray(q_robot, dtype=float)))
        return np.clip(q_human, self.arm.lower, self.arm.upper)

    def reach(self, q_robot_goal: np.ndarray) -> None:
        """Start a movement from the current pose that ends (and holds) at the robot goal."""
        self.reach_human(self.human_of(q_robot_goal))

    def reach_human(self, q_human_goal: np.ndarray) -> None:
        """Start a movement from the current pose that ends (and holds) at this arm pose (rad,
        (7,), kept within the arm's limits)."""
        goal = np.clip(np.asarray(q_human_goal, dtype=float), self.arm.lower, self.arm.upper)
        with self._lock:
            current = self._pose_at(self.k)
            frames = self._movement_frames()
            self._segment = (current, goal, self.k, frames)
            self._goal = goal
            self._holding = True

    def wander(self) -> None:
        """Go back to random reaching after a :meth:`reach`."""
        with self._lock:
            self._holding = False
            self._goal = None

    @property
    def reaching(self) -> bool:
        """Whether a :meth:`reach` is in progress or holding at its goal."""
        return self._holding

    def frames_to_goal(self) -> int:
        """Frames until the current reach arrives (0 if none or already there)."""
        _, _, start, frames = self._segment
        return max(0, start + frames - self.k) if self._holding else 0

    # sampling ----------------------------------------------------------------------------------
    def _movement_frames(self) -> int:
        return max(2, round(self._rng.uniform(*self.operator.move_seconds) * self.rate_hz))

    def _pose_at(self, k: int) -> np.ndarray:
        q_from, q_to, start, frames = self._segment
        if frames <= 0:
            return q_to.copy()
        return q_from + (q_to - q_from) * minimum_jerk(np.asarray((k - start) / frames))

    def _advance_segment(self) -> None:
        """Called when the current segment (movement or pause) is over at frame ``self.k``."""
        op = self.operator
        _, q_to, _, frames = self._segment
        if self._holding:
            self._segment = (q_to, q_to, self.k, 0)
            return
        if frames > 0 and self._rng.random() < op.pause_probability:
            pause = round(self._rng.uniform(*op.pause_seconds) * self.rate_hz)
            self._segment = (q_to, q_to, self.k, -pause)  # negative length: a pause
            return
        self._segment = (q_to, self._random_target(), self.k, self._movement_frames())

    def sample(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The next ``n`` frames' poses ``(n, 7)`` and whether a reach is on ``(n,)``."""
        q = np.empty((n, self.arm.nq))
        reaching = np.zeros(n, dtype=bool)
        with self._lock:
            for i in range(n):
                _, q_to, start, frames = self._segment
                end = start + abs(frames)
                if self.k >= end and not (self._holding and frames == 0):
                    self._advance_segment()
                q[i] = self._pose_at(self.k) if self._segment[3] > 0 else self._segment[1]
                reaching[i] = self._holding
                self.k += 1
        t = (np.arange(n) + self.k - n) / self.rate_hz
        op = self.operator
        tremor = np.zeros_like(q)
        for f, p in zip(self._tremor_freq, self._tremor_phase, strict=True):
            tremor += np.sin(2 * np.pi * f * t[:, None] + p)
        q += op.tremor_rad / 2 * tremor
        return q, reaching


class _Simulation:
    """Frames from a motion: the shared core of :func:`simulate` and :class:`SimulatorSource`."""

    def __init__(
        self,
        seed: int,
        rate_hz: float,
        config: TapeConfig | None,
        operator: OperatorConfig | None,
        retargeter: Retargeter | None,
    ) -> None:
        from studio.kinematics import TapeConfig, tape_from_arm

        seeds = np.random.SeedSequence(seed).spawn(2)
        self.motion = OperatorMotion(
            int(seeds[0].generate_state(1)[0]), rate_hz, operator, retargeter=retargeter
        )
        self.config = config if config is not None else TapeConfig()
        self.rate_hz = float(rate_hz)
        self._noise_rng = np.random.default_rng(seeds[1])
        self._tape_from_arm = tape_from_arm
        self._last_reading: tuple[np.ndarray, np.ndarray] | None = None  # noiseless, last frame
        self.k = 0

    def next(self, n: int) -> tuple[list[TapeFrame], np.ndarray]:
        q, reaching = self.motion.sample(n)
        # a stream: each region's reading continuous from the last chunk's last frame on
        bend, twist = self._tape_from_arm(
            self.motion.arm, q, self.config, in_time=True, previous=self._last_reading
        )
        self._last_reading = (bend[-1].copy(), twist[-1].copy())
        # noise drawn frame by frame (bend then twist), so any chunking gives the same frames
        shape = (n, 2, self.config.regions)
        noise = self._noise_rng.normal(0.0, self.motion.operator.noise_rad, shape)
        bend = bend + noise[:, 0]
        twist = twist + noise[:, 1]
        frames = [
            TapeFrame(
                (self.k + i) / self.rate_hz,
                self.k + i,
                bend[i],
                twist[i],
                TRIGGER_BIT if reaching[i] else 0,
            )
            for i in range(n)
        ]
        self.k += n
        return frames, q


@dataclass(frozen=True, eq=False)
class Simulated:
    """What :func:`simulate` made: the frames and the true arm poses behind them.

    Attributes:
        frames: the tape frames.
        q_human: the true arm pose per frame ``(N, 7)`` (before noise: the fitter's oracle).
        config: the tape config.
        reach_start: frame index where the reach to ``goal`` began (or ``None``).
        reach_end: frame index where it arrived (or ``None``).
    """

    frames: list[TapeFrame]
    q_human: np.ndarray
    config: TapeConfig
    reach_start: int | None = None
    reach_end: int | None = None


def simulate(
    seconds: float,
    seed: int = 0,
    rate_hz: float = DEFAULT_RATE_HZ,
    config: TapeConfig | None = None,
    goal: np.ndarray | None = None,
    operator: OperatorConfig | None = None,
    retargeter: Retargeter | None = None,
) -> Simulated:
    """Simulate ``seconds`` of capture as fast as possible (the live source's frames, same seed).

    Args:
        seconds: duration.
        seed: the seed (same seed, same frames).
        rate_hz: frame rate.
        config: the :class:`TapeConfig` (default ``TapeConfig()``).
        goal: a Puma560 configuration ``(6,)``: the motion ends there (mirrored, joint mode),
            arriving ``operator.hold_seconds`` before the end after a normal-length movement.
        operator: motion settings.
        retargeter: the joint-mode retargeter to use.

    Returns:
        The frames and the true poses.
    """
    n = round(seconds * rate_hz)
    if n < 1:
        raise CaptureError(f"seconds is {seconds}; give a positive duration.")
    sim = _Simulation(seed, rate_hz, config, operator, retargeter)
    frames: list[TapeFrame] = []
    poses: list[np.ndarray] = []
    reach_start = reach_end = None
    if goal is not None:
        op = sim.motion.operator
        tail = round((op.move_seconds[1] + op.hold_seconds) * rate_hz)
        head = max(0, n - tail)
        if head:
            f, q = sim.next(head)
            frames += f
            poses.append(q)
        reach_start = len(frames)
        sim.motion.reach(np.asarray(goal, dtype=float))
        reach_end = min(n, reach_start + sim.motion.frames_to_goal())
    rest = n - len(frames)
    if rest:
        f, q = sim.next(rest)
        frames += f
        poses.append(q)
    return Simulated(frames, np.concatenate(poses), sim.config, reach_start, reach_end)


class SimulatorSource(ThreadedSource[TapeFrame]):
    """The default source: a simulated operator wearing a tape, live at ``rate_hz``.

    Frames are computed a chunk ahead and released on absolute deadlines (``start + k / rate``),
    so the rate does not drift and a late wake-up is caught up rather than dropped.

    Args:
        seed: the seed (same seed, same frames as :func:`simulate`).
        rate_hz: frame rate (the paper's 110 Hz).
        config: the :class:`TapeConfig`.
        operator: motion settings.
        retargeter: the joint-mode retargeter (made if omitted).
        queue_frames: frames buffered before dropping.
    """

    kind = "simulator"

    def __init__(
        self,
        seed: int = 0,
        rate_hz: float = DEFAULT_RATE_HZ,
        config: TapeConfig | None = None,
        operator: OperatorConfig | None = None,
        retargeter: Retargeter | None = None,
        queue_frames: int = DEFAULT_QUEUE_FRAMES,
    ) -> None:
        super().__init__(queue_frames)
        if not rate_hz > 0:
            raise CaptureError(f"rate_hz is {rate_hz}; give a positive frame rate.")
        self.seed = seed
        self.rate_hz = float(rate_hz)
        self._sim = _Simulation(seed, rate_hz, config, operator, retargeter)
        self.config = self._sim.config

    def reach(self, q_robot_goal: np.ndarray) -> None:
        """Make the operator reach (and hold) the pose that mirrors onto this Puma560 goal.

        A goal the human arm cannot mirror exactly (say the robot's elbow bent backwards past
        straight) is approached as closely as the arm's limits allow. The trigger bit is set from
        now until :meth:`wander`, marking the demonstration in the recording.
        """
        self._sim.motion.reach(np.asarray(q_robot_goal, dtype=float))

    def reach_human(self, q_human_goal: np.ndarray) -> None:
        """Make the operator reach (and hold) this arm pose (rad, (7,)): a goal of another robot
        than the Puma560, turned into the arm that puts the hand where that robot's tool goes
        (:meth:`studio.kinematics.Retargeter.human_reaching`). Marked like :meth:`reach`."""
        self._sim.motion.reach_human(np.asarray(q_human_goal, dtype=float))

    def wander(self) -> None:
        """Return to random reaching after :meth:`reach`."""
        self._sim.motion.wander()

    def _produce(self) -> None:
        period = 1.0 / self.rate_hz
        chunk = max(1, round(CHUNK_SECONDS * self.rate_hz))
        start = time.monotonic() - self._sim.k * period
        while not self._stop_event.is_set():
            frames, _ = self._sim.next(chunk)
            for frame in frames:
                delay = start + frame.frame * period - time.monotonic()
                if delay > 0 and self._stop_event.wait(delay):
                    return
                self._push(frame)


GOAL_MARGIN_RAD = np.radians(4.0)
"""How far inside the arm's joint limits :func:`goal_configuration` keeps the mirrored pose: a
joint at its limit is a singular pose for the fit (a straight elbow hides the arm's plane)."""


class GoalGrid(Protocol):
    """What :func:`goal_configuration` asks of a task's grid (:class:`studio.learning.ArmGrid`
    has it): capture knows no learning task, only a grid of joint bins with a goal."""

    @property
    def joints(self) -> int:
        """How many joints, from joint 1, the grid covers."""

    @property
    def goal_state(self) -> int:
        """The goal's state."""

    def angles_of(self, state: int) -> np.ndarray:
        """The centre of a state's bins (rad), one angle per covered joint."""

    def state_of_angles(self, q_rad: np.ndarray) -> int:
        """The state whose bins hold these angles (rad)."""


def goal_configuration(grid: GoalGrid, retargeter: Retargeter | None = None) -> np.ndarray:
    """A Puma560 configuration in the grid's goal bin that the operator can mirror comfortably.

    The goal bins' centres, with joints beyond ``grid.joints`` at zero, moved (within the bin) so
    that the mirrored arm pose keeps :data:`GOAL_MARGIN_RAD` from every arm limit. With the default
    ``ArmGrid`` this bends the elbow slightly (joint 3 at -86 instead of -98 degrees, which the
    human elbow cannot mirror), so :meth:`SimulatorSource.reach` and the samples end in the goal.

    Args:
        grid: the :class:`studio.learning.ArmGrid`.
        retargeter: the joint-mode retargeter (default: mirrored, right arm).

    Returns:
        ``q_robot`` (6,), radians.
    """
    from studio.kinematics import Retargeter

    retargeter = retargeter or Retargeter("joint", mirror=True)
    arm = retargeter.arm
    q_robot = np.zeros(6)
    q_robot[: grid.joints] = grid.angles_of(grid.goal_state)
    q_human = retargeter.human_from_robot(q_robot)
    q_human = np.clip(q_human, arm.lower + GOAL_MARGIN_RAD, arm.upper - GOAL_MARGIN_RAD)
    moved = retargeter.robot_from_human(q_human)
    if grid.state_of_angles(moved[: grid.joints]) == grid.goal_state:
        return moved
    return q_robot
