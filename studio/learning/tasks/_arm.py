"""The paper's arm task: joints 1..J of a robot (the paper's Puma560) on a grid of joint-angle bins.

Each joint's range ``[low_deg, high_deg]`` is cut into ``bins`` equal bins (the Puma560's: the
paper's [-180, 180] degrees for every joint; another robot's: each joint's own limits, so every
bin centre is a pose the arm can take); a state is one bin per
joint, and an action moves every joint by -1, 0 or +1 bin at once (3**J actions). A move that would
leave the range leaves that joint where it is. Reaching the goal pays +100 and ends the episode,
every other transition pays -1. Episodes start uniformly from every state but the goal. Boxes in
the robot's workspace (``obstacles``) refuse every move whose path touches one: the arm stays
where it is and pays the step's -1 (:mod:`._obstacles`); a state whose pose touches one is no
start. The table a robot stands on is such an obstacle on every robot's grid but the Puma560's
(the paper's, on its pedestal, with no table in its task): no learned path runs through it. With the
defaults (3 joints, 11 bins over [-180, 180] degrees) this is the paper's 1331-state, 27-action
task.

Numbering: states and actions are mixed-radix numbers with joint 1 as the most significant digit
(``numpy.ravel_multi_index`` order). Action digit ``d`` moves its joint by ``d - 1`` bins, so action
``(3**J - 1) // 2`` (all digits 1) stays put.

Default goal: the paper shows its goal only as a picture (Fig. 7), so we pick the bins nearest to
joint angles (0, 45, -90) degrees for joints 1-3 (an arm reaching forward and down, inside the
Puma560's limits) and 0 degrees for joints 4-6. With 11 bins that is bins (5, 6, 2). Another
robot's default goal is the bins nearest its default goal pose (:func:`default_goal`).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from .._config import GRID_DEFAULTS
from .._errors import LearningError
from ._mdp import TabularMDP
from ._obstacles import blocked_grid_moves, check_goal_clear, task_obstacles
from ._robot import PUMA560, check_robot, default_goal, task_arm

if TYPE_CHECKING:
    from studio.kinematics import Obstacle

MAX_JOINTS = 6
"""Most joints a grid covers (the Puma560 has six)."""
MAX_TABLE_ENTRIES = 12_000_000
"""Largest states x actions table a grid may have: one Q table is then 96 MB, the task's tables
200 MB, and each running experiment's working memory (Q, visit list, model; prioritized sweeping's
queue) 0.6 to 1 GB. Six joints fit with up to 5 bins each (11.4 million entries)."""
GOAL_REWARD = 100.0
"""Reward for the step that reaches the goal (paper)."""
STEP_REWARD = -1.0
"""Reward for every other step (paper)."""


@dataclass(frozen=True)
class ArmGrid:
    """A grid of joint-angle bins over the first ``joints`` joints of a robot's arm.

    Args:
        joints: how many joints, from joint 1, the grid covers (1 to 6, at most the robot's;
            the paper used 3).
        bins: bins per joint (the paper used 11).
        low_deg: lower end of every joint's range, degrees, or one per joint; default: the
            robot's grid range (its registry's ``grid_range_deg``: the paper's -180 on the
            Puma560), else each joint's lower limit.
        high_deg: upper end, likewise (the paper's 180, or each joint's upper limit).
        goal: the goal's bin per joint; default: the bins nearest the robot's default goal
            (:data:`DEFAULT_GOAL_DEG` for the Puma560).
        robot: the robot's registry name (``studio robots``).
        obstacles: boxes in the robot's base frame (:class:`studio.kinematics.Obstacle`, or
            their dicts): a move whose path touches one does not happen (:mod:`._obstacles`).

    Raises:
        LearningError: for a bad value, or a grid whose table would not fit in memory.
    """

    joints: int = GRID_DEFAULTS["joints"]
    bins: int = GRID_DEFAULTS["bins"]
    low_deg: float | tuple[float, ...] | None = None
    high_deg: float | tuple[float, ...] | None = None
    goal: tuple[int, ...] | None = None
    robot: str = PUMA560
    obstacles: tuple[Obstacle, ...] = ()

    def __post_init__(self) -> None:
        arm = task_arm(check_robot(self.robot))
        object.__setattr__(self, "obstacles", task_obstacles(self.obstacles))
        for name in ("joints", "bins"):
            value = getattr(self, name)
            if not isinstance(value, int | np.integer) or isinstance(value, bool):
                raise LearningError(f"{name} is {value!r}; give a whole number.")
        most = min(MAX_JOINTS, arm.nq)
        if not 1 <= self.joints <= most:
            raise LearningError(
                f"joints is {self.joints}; give 1 to {most} (the {arm.spec.title} has {arm.nq} joints)."
            )
        if self.bins < 2:
            raise LearningError(f"bins is {self.bins}; give at least 2 bins per joint.")
        span = arm.spec.grid_range_deg  # the paper's range on the Puma560, else the limits
        ends = []
        for end, (name, limit) in enumerate((("low_deg", arm.lower), ("high_deg", arm.upper))):
            value = getattr(self, name)
            if value is None:
                value = (
                    span[end] if span else tuple(float(x) for x in np.degrees(limit[: self.joints]))
                )
            ends.append(_range_end(name, value, self.joints))
            object.__setattr__(self, name, ends[-1])
        low, high = (np.broadcast_to(np.asarray(e, np.float64), (self.joints,)) for e in ends)
        if not np.all(low < high):
            raise LearningError(
                f"The joint range [{self.low_deg}, {self.high_deg}] degrees is empty; give low_deg below high_deg."
            )
        entries = self.bins**self.joints * 3**self.joints
        if entries > MAX_TABLE_ENTRIES:
            raise LearningError(
                f"A grid of {self.joints} joints x {self.bins} bins has {self.bins**self.joints:,} states x {3**self.joints} actions = {entries:,} table entries, over the limit of {MAX_TABLE_ENTRIES:,}; use fewer bins or joints."
            )
        object.__setattr__(self, "joints", int(self.joints))
        object.__setattr__(self, "bins", int(self.bins))
        if self.goal is None:
            goal = self.bins_of_angles(default_goal(self.robot)[: self.joints])
        else:
            goal = np.asarray(self.goal)
            if goal.shape != (self.joints,) or not np.issubdtype(goal.dtype, np.integer):
                raise LearningError(
                    f"goal is {self.goal!r}; give {self.joints} bin indices, one per joint."
                )
            if goal.min() < 0 or goal.max() >= self.bins:
                raise LearningError(
                    f"goal {self.goal!r} has a bin outside [0, {self.bins - 1}]; give bins in range."
                )
        object.__setattr__(self, "goal", tuple(int(b) for b in goal))
        if self.obstacles or self.keeps_off_table:
            check_goal_clear(
                self.robot, self.obstacles, self.poses()[self.goal_state], self.keeps_off_table
            )

    @property
    def keeps_off_table(self) -> bool:
        """Whether no move may bring the robot within :data:`._obstacles.TABLE_MARGIN_M` of
        the table it stands on: every robot's grid but one binned over the paper's range
        (its registry's ``grid_range_deg``: the Puma560's, the paper's task, with no table)."""
        return not task_arm(self.robot).spec.grid_range_deg

    # ------------------------------------------------------------------ sizes and numbering

    @property
    def n_states(self) -> int:
        """bins ** joints."""
        return self.bins**self.joints

    @property
    def n_actions(self) -> int:
        """3 ** joints: every joint moves -1, 0 or +1 bin."""
        return 3**self.joints

    @property
    def goal_state(self) -> int:
        """The goal's state number."""
        return self.state_of(self.goal)

    @property
    def stay_action(self) -> int:
        """The action that moves no joint."""
        return (self.n_actions - 1) // 2

    @property
    def bin_width(self) -> float:
        """Width of one bin, radians (the widest joint's when their ranges differ)."""
        return float(np.max(self._widths))

    @cached_property
    def _lows(self) -> np.ndarray:
        """Each joint's lower range end, radians ``(joints,)``."""
        return np.broadcast_to(np.radians(np.asarray(self.low_deg, np.float64)), (self.joints,))

    @cached_property
    def _widths(self) -> np.ndarray:
        """Each joint's bin width, radians ``(joints,)``."""
        high, low = np.asarray(self.high_deg, np.float64), np.asarray(self.low_deg, np.float64)
        return np.broadcast_to(np.radians(high - low) / self.bins, (self.joints,))

    def to_dict(self) -> dict:
        """The grid spec as JSON-ready values (the inverse of ``ArmGrid(**spec)``)."""
        return {
            "joints": self.joints,
            "bins": self.bins,
            "low_deg": self.low_deg if isinstance(self.low_deg, float) else list(self.low_deg),
            "high_deg": self.high_deg if isinstance(self.high_deg, float) else list(self.high_deg),
            "goal": list(self.goal),
            "robot": self.robot,
            **({"obstacles": [o.to_dict() for o in self.obstacles]} if self.obstacles else {}),
        }

    def state_of(self, bins: Sequence[int] | np.ndarray) -> int:
        """State number of one bin per joint."""
        b = np.asarray(bins)
        if b.shape != (self.joints,) or not np.issubdtype(b.dtype, np.integer):
            raise LearningError(f"bins is {bins!r}; give {self.joints} bin indices, one per joint.")
        if b.min() < 0 or b.max() >= self.bins:
            raise LearningError(
                f"bins {bins!r} has a bin outside [0, {self.bins - 1}]; give bins in range."
            )
        return int(np.ravel_multi_index(tuple(b), (self.bins,) * self.joints))

    def bins_of(self, state: int) -> tuple[int, ...]:
        """Bin per joint of a state number."""
        self._check_state(state)
        return tuple(int(b) for b in np.unravel_index(int(state), (self.bins,) * self.joints))

    def angles_of(self, state: int) -> np.ndarray:
        """Joint angles of the state's bin centres, radians ``(joints,)``."""
        return self._centres(np.asarray(self.bins_of(state)))

    def bins_of_angles(self, q_rad: Sequence[float] | np.ndarray) -> np.ndarray:
        """Nearest bin per joint for joint angles in radians (angles outside the range clip)."""
        q = np.asarray(q_rad, dtype=np.float64)
        if q.shape[-1:] != (self.joints,):
            raise LearningError(
                f"The joint angles have shape {q.shape}; give {self.joints} angles (radians) per row."
            )
        if not np.all(np.isfinite(q)):
            raise LearningError(
                "The joint angles hold NaN or infinite values; give finite angles in radians."
            )
        b = np.floor((q - self._lows) / self._widths).astype(np.int64)
        return np.clip(b, 0, self.bins - 1)

    def state_of_angles(self, q_rad: Sequence[float] | np.ndarray) -> int:
        """State whose bins are nearest to the joint angles (radians, ``(joints,)``)."""
        return self.state_of(self.bins_of_angles(q_rad))

    def _centres(self, bins: np.ndarray) -> np.ndarray:
        return self._lows + (bins + 0.5) * self._widths

    def nearest_start(self, q_rad: Sequence[float] | np.ndarray) -> int:
        """The state of the angles ``q_rad``, or, where that state is no start (its pose
        touches an obstacle, or comes near the table the robot stands on), the start state
        nearest to it (fewest bins away, then nearest in angle)."""
        state = self.state_of_angles(q_rad)
        starts = self.mdp().start_states
        if state == self.goal_state or state in starts:
            return state
        bins = np.array(np.unravel_index(starts, (self.bins,) * self.joints)).T
        own = np.array(self.bins_of(state))
        away = np.abs(bins - own)
        order = np.lexsort(((away**2).sum(axis=1), away.max(axis=1)))
        return int(starts[order[0]])

    def _check_state(self, state: int) -> None:
        if (
            not isinstance(state, int | np.integer)
            or isinstance(state, bool)
            or not 0 <= state < self.n_states
        ):
            raise LearningError(
                f"state is {state!r}; give a state number from 0 to {self.n_states - 1}."
            )

    def action_deltas(self) -> np.ndarray:
        """int ``(n_actions, joints)``: the bin change of every joint under every action."""
        digits = np.array(np.unravel_index(np.arange(self.n_actions), (3,) * self.joints)).T
        return digits.astype(np.int64) - 1

    # ------------------------------------------------------------------ the task

    def mdp(self) -> TabularMDP:
        """The grid as a :class:`TabularMDP` (the paper's rewards; starts anywhere but the goal).

        Built once per grid and shared: a :class:`TabularMDP` is read-only.
        """
        return self._table

    @cached_property
    def _table(self) -> TabularMDP:
        return _grid_table(self)

    def _build_table(self) -> TabularMDP:
        shape = (self.bins,) * self.joints
        state_bins = np.unravel_index(np.arange(self.n_states), shape)  # J arrays (S,)
        deltas = self.action_deltas()  # (A, J)
        next_state = np.zeros((self.n_states, self.n_actions), np.int64)
        for j in range(self.joints):  # one joint at a time keeps the peak memory at a few (S, A)
            moved = state_bins[j][:, None] + deltas[None, :, j]
            moved = np.where((moved >= 0) & (moved < self.bins), moved, state_bins[j][:, None])
            next_state += moved * self.bins ** (self.joints - 1 - j)
        goal = self.goal_state
        colliding = np.zeros(self.n_states, np.bool_)
        intended = next_state
        if self.obstacles or self.keeps_off_table:
            blocked, colliding = blocked_grid_moves(
                self.robot, self.obstacles, self.poses(), next_state, self.keeps_off_table
            )
            next_state = np.where(blocked, np.arange(self.n_states)[:, None], next_state)
        reward = np.where(next_state == goal, GOAL_REWARD, STEP_REWARD)
        terminal = np.zeros(self.n_states, np.bool_)
        terminal[goal] = True
        starts = np.flatnonzero(~terminal & ~colliding & _reaches(next_state, goal))
        return TabularMDP(next_state, reward, terminal, starts, intended)

    @property
    def hold(self) -> np.ndarray:
        """The angles of every robot joint the grid does not cover, rad (one per robot joint:
        the robot's default goal's, as rollouts hold them)."""
        return default_goal(self.robot)

    def poses(self) -> np.ndarray:
        """Every state's whole robot pose ``(n_states, nq)``, rad: its bin centres, the other
        joints at :attr:`hold`."""
        shape = (self.bins,) * self.joints
        bins = np.array(np.unravel_index(np.arange(self.n_states), shape)).T
        poses = np.tile(self.hold, (self.n_states, 1))
        poses[:, : self.joints] = self._centres(bins)
        return poses

    def shortest_steps(self, state: int) -> int:
        """Fewest actions from ``state`` to the goal: the largest bin distance over the joints."""
        return int(np.max(np.abs(np.asarray(self.bins_of(state)) - np.asarray(self.goal))))

    def mean_shortest_steps(self) -> float:
        """Mean of :meth:`shortest_steps` over the start states: the best possible curve level."""
        shape = (self.bins,) * self.joints
        state_bins = np.array(np.unravel_index(np.arange(self.n_states), shape)).T
        dist = np.max(np.abs(state_bins - np.asarray(self.goal)), axis=1)
        return float(dist[dist > 0].mean()) if np.any(dist > 0) else 0.0

    def path_from_joints(
        self, q_path_rad: np.ndarray | Sequence[Sequence[float]], *, stop_at_goal: bool = True
    ) -> list[int]:
        """The grid path a demonstration replays: :meth:`trace_joints`'s states.

        This is the one demonstration-to-grid-path function: the demonstration cutter, the
        page's run queue and ``studio train`` all replay what it returns, so a demonstration
        trains alike everywhere.

        Args:
            q_path_rad: joint angles in radians, ``(N, joints)`` or wider (see
                :meth:`trace_joints`).
            stop_at_goal: end the path at its first visit to the goal (see :meth:`trace_joints`).

        Returns:
            State numbers, consecutive ones one action apart, no state twice.
        """
        return self.trace_joints(q_path_rad, stop_at_goal=stop_at_goal).states

    def trace_joints(
        self, q_path_rad: np.ndarray | Sequence[Sequence[float]], *, stop_at_goal: bool = True
    ) -> GridPath:
        """A loop-free grid path (consecutive states one action apart) following a trajectory.

        Each row is mapped to its nearest bins. Between two samples whose bins differ by more
        than one step (a fast motion, or frames dropped), every lagging joint moves one bin per
        step toward the later sample at the same time (a diagonal, then straight, walk: a
        shortest grid path), so the path stays one action per step even when the arm jumps
        over the goal between two samples. Then:

        1. with ``stop_at_goal``, the walk is cut at its first visit to the goal, as an episode
           would end there. A reach-and-return motion (out to the goal, back to rest) keeps
           its reach; a hand wobbling in and out of the goal bin keeps its first arrival.
        2. loops are erased (:func:`erase_loops`): pauses, bin-boundary flicker and detours back
           to a visited state teach nothing.

        Args:
            q_path_rad: joint angles in radians, ``(N, joints)``; wider rows (for example the
                Puma560's six joints) use their first ``joints`` columns.
            stop_at_goal: end the path at its first visit to the goal.

        Returns:
            A :class:`GridPath`: the states (the first nearest to the first sample; the last
            the goal when cut there, else nearest to the last sample) and, per state, the
            sample by which the arm got there.

        Raises:
            LearningError: not an ``(N >= 1, joints or more)`` array of finite angles.
        """
        q = np.asarray(q_path_rad, dtype=np.float64)
        if q.ndim != 2 or q.shape[0] < 1 or q.shape[1] < self.joints:
            raise LearningError(
                f"The joint path has shape {q.shape}; give an (N, {self.joints}) or wider array of angles in radians with N >= 1."
            )
        bins = self.bins_of_angles(q[:, : self.joints])
        walk = [bins[0]]
        samples = [0]
        for i in range(1, bins.shape[0]):
            current, target = walk[-1], bins[i]
            steps = int(np.max(np.abs(target - current)))
            if steps == 0:
                continue
            # the diagonal-then-straight walk: each joint moves one bin per step until it arrives
            k = np.arange(1, steps + 1)[:, None]
            walk.extend(
                current + np.sign(target - current) * np.minimum(k, np.abs(target - current))
            )
            samples.extend([i] * steps)
        shape = (self.bins,) * self.joints
        states = [int(s) for s in np.ravel_multi_index(tuple(np.array(walk).T), shape)]
        goal = self.goal_state
        reaches_goal = goal in states
        if stop_at_goal and reaches_goal:
            end = states.index(goal) + 1
            states, samples = states[:end], samples[:end]
        states, samples = _erase_loops(states, samples)
        return GridPath(states=states, samples=samples, reaches_goal=reaches_goal)


def _reaches(next_state: np.ndarray, goal: int) -> np.ndarray:
    """Which states some sequence of moves takes to ``goal`` (S,) bool: walled off by boxes or
    the table, a state is no start (its episodes could never end)."""
    reached = np.zeros(len(next_state), np.bool_)
    reached[goal] = True
    while True:  # every state one move from a reached one, until nothing new
        more = reached[next_state].any(axis=1) & ~reached
        if not more.any():
            return reached
        reached |= more


@functools.lru_cache(maxsize=4)
def _grid_table(grid: ArmGrid) -> TabularMDP:
    """A grid's table, built once per process for equal grids (with obstacles it takes
    seconds: every move is checked against the boxes)."""
    return grid._build_table()


def _range_end(name: str, value: object, joints: int) -> float | tuple[float, ...]:
    """A range end as given: one finite angle for every joint, or ``joints`` of them."""
    if isinstance(value, list | tuple | np.ndarray):
        ends = np.asarray(value, dtype=np.float64) if len(value) == joints else None
        if ends is None or not np.all(np.isfinite(ends)):
            raise LearningError(
                f"{name} is {value!r}; give one finite angle in degrees, or {joints}, one per joint."
            )
        return tuple(float(x) for x in ends)
    if (
        not isinstance(value, int | float | np.integer | np.floating)
        or isinstance(value, bool)
        or not np.isfinite(value)
    ):
        raise LearningError(f"{name} is {value!r}; give a finite angle in degrees.")
    return float(value)


@dataclass(frozen=True)
class GridPath:
    """A grid path traced from a joint trajectory by :meth:`ArmGrid.trace_joints`.

    Attributes:
        states: the states, consecutive ones one action apart, none twice.
        samples: per state, the index of the trajectory sample by which the arm reached it
            (non-decreasing; a state filled in between two samples belongs to the later one).
        reaches_goal: whether the trajectory passes through the goal bin at all (between two
            samples counts).
    """

    states: list[int]
    samples: list[int]
    reaches_goal: bool

    @property
    def steps(self) -> int:
        """Actions along the path (states - 1)."""
        return max(0, len(self.states) - 1)


def erase_loops(path: Sequence[int]) -> list[int]:
    """The path with every loop cut out (a state visited twice keeps only its last visit's future).

    Tremor and sensor noise make a hand resting on a bin boundary flicker between two states;
    those back-and-forth steps (and any wider detour back to a visited state) teach nothing, so a
    demonstration keeps the loop-free path. Consecutive states stay one action apart, since each
    kept step is a step of the original path.
    """
    return _erase_loops(list(path), [0] * len(path))[0]


def _erase_loops(states: list[int], samples: list[int]) -> tuple[list[int], list[int]]:
    """:func:`erase_loops`, carrying each state's sample index (a revisit takes the later one)."""
    out: list[int] = []
    out_samples: list[int] = []
    index: dict[int, int] = {}
    for state, sample in zip(states, samples, strict=True):
        if state in index:
            cut = index[state]
            for dropped in out[cut + 1 :]:
                del index[dropped]
            del out[cut + 1 :]
            del out_samples[cut + 1 :]
            out_samples[cut] = sample  # the arm leaves from its latest visit
            continue
        index[state] = len(out)
        out.append(state)
        out_samples.append(sample)
    return out, out_samples
