"""The continuous arm task: joints 1..J of the Puma560 reach a demonstrated pose, step by step.

The state is the first ``joints`` joint angles (radians, inside the robot's limits); the other
joints stay at the goal's values. With ``actions="single"`` an action moves ONE joint by
``step_deg`` (2J actions: joint 1 up, joint 1 down, joint 2 up, ...); ``actions="pairs"`` (the
default) adds every two joints moving together, each up or down (the diagonals, 2J**2 actions), and
``actions="all"`` every joint -1/0/+1 at once (3**J - 1 actions); see :data:`ACTION_SETS` and
:func:`action_directions`. A joint whose move would leave its limits stays where it is, as on
the paper's grid (the action's other joints still move). Reaching the goal pays :data:`GOAL_REWARD` and ends the
episode, every other step pays :data:`STEP_REWARD` (the paper's rewards), plus a potential-based
shaping term (:data:`DEFAULT_SHAPING`). Episodes start uniformly across the limits (a start already
at the goal is redrawn).

Why one or two joints per action is the default (measured in ``benchmarks/bench_actions.py``):
with one weight column per action, each multi-joint move learned only from its own visits and
the multi-joint sets learned far worse than one joint per action; the learner's factored action
value (:mod:`._factored`) shares what each joint's part of a move learned among every move that
has it, and with it the pairs learn in fewer real steps than single joints and move joints
together. Every joint -1/0/+1 at once (3**J - 1 actions, 728 for six joints) overshoots near the
goal even so. There is no "stay" action: it never helps a reach, and with function
approximation its estimate can stick above the moves' and freeze the arm.

The goal is judged where a user sees it: the tool (Puma560 DH frame 6) within
``position_tolerance`` metres and ``angle_tolerance_deg`` degrees of the goal's tool pose, by
forward kinematics. :func:`tool_pose` is a numba twin of :meth:`studio.kinematics.Puma560.forward`
built from the same DH table (a test holds them equal), so the kernels can call it.

Dynamics are defined once, here, in numba functions (:func:`reach_step`, :func:`reach_success`): the learner's compiled kernel and the Gymnasium environment
``TeachStudio/ArmReach-v0`` both call them.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numba import njit

from studio.kinematics import Puma560

from ._arm import DEFAULT_GOAL_DEG, GOAL_REWARD, STEP_REWARD
from ._errors import ConfigError, LearningError
from ._tiles import TileCoding

ROBOT_JOINTS = 6
"""The Puma560's joints."""
MIN_JOINTS = 3
"""Fewest joints the continuous task offers (the paper's three)."""
DEFAULT_JOINTS = 6
"""All six joints, so the tool's orientation is learned too."""
DEFAULT_STEP_DEG = 2.0
"""Joint increment per action, degrees (no coarser than 2 degrees)."""
MAX_STEP_DEG = 2.0
"""Coarsest step allowed: beyond it the tool jumps by several centimetres per step."""
MIN_STEP_DEG = 0.05
"""Finest step allowed: below it an episode across the limits takes tens of thousands of steps."""
DEFAULT_POSITION_TOLERANCE = 0.02
"""Tool within this many metres of the goal's tool position counts as reached."""
DEFAULT_ANGLE_TOLERANCE_DEG = 10.0
"""...and within this many degrees of the goal's tool orientation."""
DEFAULT_MAX_EPISODE_STEPS = 3_000
"""Episode cap of the registered environment (about three times the longest greedy path)."""
DEFAULT_TILINGS = 8
"""Offset tilings of the arm's default features."""
DEFAULT_TILES = 32
"""Tiles per joint of the arm's default features (each joint tiled alone, see
:meth:`ArmReach.features`): about 17 degrees of the widest joint each, about 2 degrees resolution
over 8 tilings."""
DEFAULT_SHAPING = 5.0
"""Weight of the potential-based shaping reward (Ng, Harada & Russell 1999): ``shaping`` times the
change of :func:`reach_potential` (minus the joints' distance to the goal's angles, in steps). It
gives every step a direction toward the goal, without which a 6-joint random start almost never
finds the goal's few-degree region; 0 gives the paper's bare +100 / -1. With gamma = 1 the terms of
an episode telescope to a constant per start, so the optimal policies are unchanged; with the
paper's gamma = 0.95 the term also charges ``(1 - gamma) x shaping x distance``, which only pulls
harder toward the goal.

Why 5 and not 1. A joint step toward the goal pays ``shaping - 1``, one away ``-shaping - 1``.
With 1 the step cost cancels exactly: every move toward the goal pays 0, so which joint to move is
told apart only by the discounted +100, ``100 x 0.95 ** (sum of the joints' distances)``, a
*product* of per-joint factors that no sum of per-joint (or pair) tile weights represents; the
fitted error exceeds the true gaps and the greedy policy steps a near-goal joint back and forth
(measured at six joints: 16% greedy success after 4,000 episodes, 32% after 16,000). With 5, the
value is dominated by a sum over joints of per-joint terms (+4 per step toward the goal, -6 per
step away), which per-joint tilings represent exactly, and the +100 only settles the last steps:
100% after 4,000 episodes (package README). A cycle still costs (toward then away:
``4 - 0.95 x 6 < 0``), so no loop pays; that holds while ``shaping < (1 + gamma) / (1 - gamma)``
(39 at gamma = 0.95)."""
MAX_SHAPING = 100.0
"""Upper bound on ``shaping``."""
ACTION_SETS = ("single", "pairs", "all")
"""What one action may move: one joint (2J actions), one joint or two together (2J**2), or any
joints at once (3**J - 1); each set begins with the one before it, in the same order."""
DEFAULT_ACTIONS = "pairs"
"""One joint or two together per action, learned with a factored action value
(:mod:`._factored`): measured, it learns in fewer real steps than one joint per action and moves
joints together (package README; ``benchmarks/bench_actions.py``)."""
STORED_ACTIONS = "single"
"""What a task stored before ``actions`` existed moves: one joint per action."""
LIMIT_SLACK_RAD = 1e-9
"""A demonstration may touch its joint limits within this rounding."""

# layout of the flat float64 parameter array the compiled functions take
_J, _STEP, _POS_TOL2, _MIN_TRACE = 0, 1, 2, 3
_GOAL_P = 4  # 3 values
_GOAL_R = 7  # 9 values, row-major
_LOWER = 16  # 6 values
_UPPER = 22
_HOLD = 28
_D = 34
_A = 40
_ALPHA = 46
_SHAPING = 52
_POS_TOL = 53
_ANG_TOL = 54
_MULTI = 55  # 0: one joint per action (the fast path), else the table below
_TABLE = 56  # per action, ROBOT_JOINTS directions -1/0/+1
_N_PARAMS = 56


@dataclass(frozen=True)
class ArmReach:
    """The continuous reaching task over joints 1..``joints`` of the Puma560.

    Attributes:
        joints: joints learned, from joint 1 (3 to 6).
        step_deg: joint increment per action, degrees.
        goal: goal joint angles in radians: ``joints`` values, or six (the joints beyond
            ``joints`` are held there); default: :data:`studio.learning.DEFAULT_GOAL_DEG`.
        position_tolerance: metres.
        angle_tolerance_deg: degrees.
        shaping: weight of the potential-based shaping reward (:data:`DEFAULT_SHAPING`).
        actions: what one action moves, one of :data:`ACTION_SETS`.

    Raises:
        LearningError: a bad value, or a goal outside the joint limits.
    """

    joints: int = DEFAULT_JOINTS
    step_deg: float = DEFAULT_STEP_DEG
    goal: tuple[float, ...] | None = None
    position_tolerance: float = DEFAULT_POSITION_TOLERANCE
    angle_tolerance_deg: float = DEFAULT_ANGLE_TOLERANCE_DEG
    shaping: float = DEFAULT_SHAPING
    actions: str = DEFAULT_ACTIONS

    def __post_init__(self) -> None:
        if self.actions not in ACTION_SETS:
            raise ConfigError(
                [
                    f"actions is {self.actions!r}; give {', '.join(map(repr, ACTION_SETS))} (one joint per action, also two together, or any joints at once)."
                ],
                ["actions"],
            )
        if (
            not isinstance(self.joints, int | np.integer)
            or isinstance(self.joints, bool)
            or not MIN_JOINTS <= self.joints <= ROBOT_JOINTS
        ):
            raise ConfigError(
                [
                    f"joints is {self.joints!r}; give {MIN_JOINTS} to {ROBOT_JOINTS} (joints 1..J of the arm)."
                ],
                ["joints"],
            )
        object.__setattr__(self, "joints", int(self.joints))
        for name, low, high in (
            ("step_deg", MIN_STEP_DEG, MAX_STEP_DEG),
            ("position_tolerance", 1e-4, 1.0),
            ("angle_tolerance_deg", 0.1, 180.0),
            ("shaping", 0.0, MAX_SHAPING),
        ):
            value = getattr(self, name)
            if (
                not isinstance(value, int | float | np.integer | np.floating)
                or isinstance(value, bool)
                or not math.isfinite(value)
                or not low <= value <= high
            ):
                raise ConfigError(
                    [f"{name} is {value!r}; give a number from {low} to {high}."], [name]
                )
            object.__setattr__(self, name, float(value))
        lower, upper = _limits()
        if self.goal is None:
            goal = np.radians(DEFAULT_GOAL_DEG)
        else:
            g = np.asarray(self.goal, dtype=np.float64).reshape(-1)
            if g.shape not in ((self.joints,), (ROBOT_JOINTS,)) or not np.all(np.isfinite(g)):
                raise ConfigError(
                    [
                        f"goal is {self.goal!r}; give {self.joints} or {ROBOT_JOINTS} finite joint angles in radians."
                    ],
                    ["goal"],
                )
            goal = np.radians(DEFAULT_GOAL_DEG).copy()
            goal[: g.shape[0]] = g
        outside = np.flatnonzero(
            (goal < lower - LIMIT_SLACK_RAD) | (goal > upper + LIMIT_SLACK_RAD)
        )
        if outside.size:
            j = int(outside[0])
            raise ConfigError(
                [
                    f"The goal's joint {j + 1} is {np.degrees(goal[j]):.1f} deg, outside its limits [{np.degrees(lower[j]):.0f}, {np.degrees(upper[j]):.0f}]; give a goal inside the limits."
                ],
                ["goal"],
            )
        object.__setattr__(self, "goal", tuple(float(x) for x in np.clip(goal, lower, upper)))

    # ------------------------------------------------------------------ sizes

    @property
    def n_actions(self) -> int:
        """2J (one joint up or down by one step), 2J**2 with the pairs, 3**J - 1 with all."""
        return int(self.directions.shape[0])

    @cached_property
    def directions(self) -> np.ndarray:
        """Each action's move, in steps per joint: int8 ``(n_actions, joints)`` of -1/0/+1."""
        return action_directions(self.joints, self.actions)

    @property
    def step(self) -> float:
        """The joint increment, radians."""
        return math.radians(self.step_deg)

    @property
    def lower(self) -> np.ndarray:
        """Lower limits of the learned joints, radians ``(joints,)``."""
        return _limits()[0][: self.joints].copy()

    @property
    def upper(self) -> np.ndarray:
        """Upper limits of the learned joints, radians ``(joints,)``."""
        return _limits()[1][: self.joints].copy()

    def to_dict(self) -> dict:
        """JSON-ready settings (the inverse of ``ArmReach(**d)``)."""
        return {
            "joints": self.joints,
            "step_deg": self.step_deg,
            "goal": list(self.goal),
            "position_tolerance": self.position_tolerance,
            "angle_tolerance_deg": self.angle_tolerance_deg,
            "shaping": self.shaping,
            "actions": self.actions,
        }

    @classmethod
    def from_dict(cls, data: dict) -> ArmReach:
        """Settings from :meth:`to_dict`'s form (one written before ``actions`` existed moves one
        joint per action)."""
        goal = None if data.get("goal") is None else tuple(data["goal"])
        return cls(**{"actions": STORED_ACTIONS, **data, "goal": goal})

    def features(
        self, tilings: int = DEFAULT_TILINGS, tiles: int = DEFAULT_TILES, size: int | None = None
    ) -> TileCoding:
        """The default tile coding of this task: every joint tiled on its own.

        One grid over all joints would need ``(tiles + 1) ** joints`` tiles per tiling (1.3e9
        for six joints at 32 tiles) and generalise only within a few degrees in every joint at
        once. With one joint moving per action and the shaping of :data:`DEFAULT_SHAPING`, an
        action's value is nearly a sum of per-joint terms (is the moved joint above or below its
        goal angle, how far are the others), which tilings of each joint alone represent:
        ``J x (tiles + 1)`` tiles per tiling, six joints learn in seconds. Measured against pairs
        of joints (``J (J - 1) / 2 x (tiles + 1) ** 2`` tiles per tiling) at six joints, 4,000
        episodes: 100% greedy success for single joints against 77% for pairs and 94% for both
        (see the package README); pass ``TileCoding(groups=...)`` for other choices.
        """
        singles = tuple((j,) for j in range(self.joints))
        return TileCoding(tilings=tilings, tiles=tiles, size=size, groups=singles)

    @cached_property
    def params(self) -> np.ndarray:
        """The flat parameter array of :func:`reach_step` and friends (read-only)."""
        robot = Puma560()
        table = self.directions
        p = np.zeros(_N_PARAMS + ROBOT_JOINTS * table.shape[0], np.float64)
        p[_MULTI] = 0.0 if self.actions == "single" else 1.0
        p[_TABLE:].reshape(-1, ROBOT_JOINTS)[:, : self.joints] = table
        p[_J] = self.joints
        p[_STEP] = self.step
        p[_POS_TOL2] = self.position_tolerance**2
        p[_MIN_TRACE] = 1.0 + 2.0 * math.cos(math.radians(self.angle_tolerance_deg))
        lower, upper = _limits()
        p[_LOWER : _LOWER + 6] = lower
        p[_UPPER : _UPPER + 6] = upper
        p[_HOLD : _HOLD + 6] = self.goal
        p[_D : _D + 6] = [row.d for row in robot.dh]
        p[_A : _A + 6] = [row.a for row in robot.dh]
        p[_ALPHA : _ALPHA + 6] = [row.alpha for row in robot.dh]
        p[_SHAPING] = self.shaping
        p[_POS_TOL] = self.position_tolerance
        p[_ANG_TOL] = math.radians(self.angle_tolerance_deg)
        oMgoal = robot.forward(np.asarray(self.goal))
        p[_GOAL_P : _GOAL_P + 3] = oMgoal[:3, 3]
        p[_GOAL_R : _GOAL_R + 9] = oMgoal[:3, :3].reshape(-1)
        p.flags.writeable = False
        return p

    # ------------------------------------------------------------------ Python-side helpers

    def success(self, q: Sequence[float] | np.ndarray) -> bool:
        """Whether joint angles ``q`` (the learned joints, radians) put the tool at the goal."""
        state = self._state(q)
        return bool(reach_success(self.params, state))

    def tool_pose(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """The tool pose ``oMtool`` (4x4) at the learned joints ``q``, other joints held."""
        out = np.empty((4, 4))
        tool_pose(self.params, self._state(q), out)
        return out

    def full_q(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """All six joint angles: ``q`` for the learned joints, the goal's for the others."""
        full = np.array(self.goal, dtype=np.float64)
        full[: self.joints] = self._state(q)
        return full

    def random_start(self, rng: np.random.Generator) -> np.ndarray:
        """A start drawn uniformly across the limits, not already at the goal."""
        while True:
            q = rng.uniform(self.lower, self.upper)
            if not reach_success(self.params, q):
                return q

    def _state(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        state = np.asarray(q, dtype=np.float64).reshape(-1)
        if state.shape != (self.joints,) or not np.all(np.isfinite(state)):
            raise LearningError(
                f"q has shape {state.shape}; give {self.joints} finite joint angles in radians."
            )
        return np.ascontiguousarray(state)

    def demonstration_actions(
        self, q_path: np.ndarray | Sequence[Sequence[float]], index: int = 0
    ) -> tuple[np.ndarray, np.ndarray]:
        """The start and the action sequence that follow a demonstrated joint path.

        The walk starts at the path's first sample and steps toward each later sample in turn
        until every joint is within half a step of it; it stops at its first arrival at the goal.
        Each step takes the action that moves only joints more than half a step from the sample,
        each toward it, with the largest sum of their distances (with one joint per action: the
        farthest joint first).

        Args:
            q_path: joint angles, radians, ``(N, joints)`` or wider (the first ``joints`` columns).
            index: the demonstration's number, for messages.

        Returns:
            ``(start (joints,), actions (K,) int64)``.

        Raises:
            LearningError: a bad shape, a sample outside the joint limits, or a path that never
                comes within tolerance of the goal.
        """
        q = np.asarray(q_path, dtype=np.float64)
        if q.ndim != 2 or q.shape[0] < 1 or q.shape[1] < self.joints:
            raise LearningError(
                f"Demonstration {index} has shape {q.shape}; give an (N, {self.joints}) or wider array of joint angles in radians."
            )
        q = np.ascontiguousarray(q[:, : self.joints])
        if not np.all(np.isfinite(q)):
            raise LearningError(
                f"Demonstration {index} holds NaN or infinite angles; re-record it."
            )
        lower, upper = self.lower, self.upper
        bad = (q < lower - LIMIT_SLACK_RAD) | (q > upper + LIMIT_SLACK_RAD)
        if bad.any():
            k, j = (int(v) for v in np.argwhere(bad)[0])
            raise LearningError(
                f"Demonstration {index} leaves joint {j + 1}'s limits at sample {k} ({np.degrees(q[k, j]):.1f} deg, outside [{np.degrees(lower[j]):.0f}, {np.degrees(upper[j]):.0f}]); cut that part off or record it again inside the limits."
            )
        q = np.clip(q, lower, upper)
        actions = np.empty(_walk_capacity(q, self.step), np.int64)
        n = _walk(self.params, q, actions)
        if n < 0:
            raise LearningError(
                f"Demonstration {index} never brings the tool within {self.position_tolerance * 100:g} cm and {self.angle_tolerance_deg:g} deg of the goal; end it at the goal or make the goal its final pose."
            )
        return q[0].copy(), actions[:n].copy()


def action_directions(joints: int, actions: str = DEFAULT_ACTIONS) -> np.ndarray:
    """The moves of action set ``actions`` over ``joints`` joints: int8 ``(n, joints)``, -1/0/+1.

    Singles first (joint 1 up, joint 1 down, joint 2 up, ...), then with ``"pairs"`` or ``"all"``
    each pair of joints ``j < k`` as (+, +), (+, -), (-, +), (-, -), then with ``"all"`` the
    moves of three or more joints (in ``itertools.product((1, 0, -1), repeat=joints)`` order).
    """
    rows: list[tuple[int, ...]] = []
    for j in range(joints):
        for d in (1, -1):
            rows.append(tuple(d if i == j else 0 for i in range(joints)))
    if actions in ("pairs", "all"):
        for j, k in itertools.combinations(range(joints), 2):
            for dj, dk in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
                rows.append(tuple(dj if i == j else dk if i == k else 0 for i in range(joints)))
    if actions == "all":
        rows += [m for m in itertools.product((1, 0, -1), repeat=joints) if sum(map(abs, m)) > 2]
    return np.array(rows, dtype=np.int8).reshape(-1, joints)


def _limits() -> tuple[np.ndarray, np.ndarray]:
    robot = _robot()
    return np.asarray(robot.lower, dtype=np.float64), np.asarray(robot.upper, dtype=np.float64)


_ROBOT: list[Puma560] = []


def _robot() -> Puma560:
    """One shared Puma560 (building its Pinocchio model costs a few milliseconds)."""
    if not _ROBOT:
        _ROBOT.append(Puma560())
    return _ROBOT[0]


def _walk_capacity(q: np.ndarray, step: float) -> int:
    """An upper bound on the walk's actions: the path's joint travel in steps, plus slack."""
    travel = np.abs(np.diff(q, axis=0)).sum() if q.shape[0] > 1 else 0.0
    return int(travel / step) + q.shape[0] * q.shape[1] + 8


# --------------------------------------------------------------------------- compiled dynamics


@njit(nogil=True, cache=True)
def tool_pose(params, state, out):
    """Standard-DH forward kinematics ``prod_i Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)`` into ``out``.

    The numba twin of :meth:`studio.kinematics.Puma560.forward`: ``state`` holds the learned
    joints, the others come from the held goal angles in ``params``.
    """
    joints = int(params[_J])
    for i in range(4):
        for k in range(4):
            out[i, k] = 1.0 if i == k else 0.0
    for i in range(ROBOT_JOINTS):
        theta = state[i] if i < joints else params[_HOLD + i]
        ct, st = math.cos(theta), math.sin(theta)
        ca, sa = math.cos(params[_ALPHA + i]), math.sin(params[_ALPHA + i])
        a, d = params[_A + i], params[_D + i]
        # A = [[ct, -st ca, st sa, a ct], [st, ct ca, -ct sa, a st], [0, sa, ca, d]]
        for r in range(3):
            x, y, z, p = out[r, 0], out[r, 1], out[r, 2], out[r, 3]
            out[r, 0] = x * ct + y * st
            out[r, 1] = -x * st * ca + y * ct * ca + z * sa
            out[r, 2] = x * st * sa - y * ct * sa + z * ca
            out[r, 3] = x * a * ct + y * a * st + z * d + p


@njit(nogil=True, cache=True)
def _errors(params, state):
    """``(squared position error m^2, trace(R_goal^T R))`` of the tool at ``state``."""
    pose = np.empty((4, 4))
    tool_pose(params, state, pose)
    dx = pose[0, 3] - params[_GOAL_P]
    dy = pose[1, 3] - params[_GOAL_P + 1]
    dz = pose[2, 3] - params[_GOAL_P + 2]
    trace = 0.0  # trace(R_goal^T R) = 1 + 2 cos(angle between them)
    for r in range(3):
        for c in range(3):
            trace += params[_GOAL_R + 3 * r + c] * pose[r, c]
    return dx * dx + dy * dy + dz * dz, trace


@njit(nogil=True, cache=True)
def reach_success(params, state):
    """Whether the tool is within the position and angle tolerances of the goal's tool pose."""
    distance2, trace = _errors(params, state)
    return distance2 <= params[_POS_TOL2] and trace >= params[_MIN_TRACE]


@njit(nogil=True, cache=True)
def reach_potential(params, state):
    """Shaping potential: minus the joints' distance to the goal's joint angles, in steps."""
    total = 0.0
    for j in range(state.shape[0]):
        total += abs(state[j] - params[_HOLD + j])
    return -total / params[_STEP]


@njit(nogil=True, cache=True)
def reach_step(params, state, action):
    """Apply ``action`` to ``state`` (in place); returns ``(reward, terminated)``.

    Action ``2 j`` moves joint ``j`` up one step, ``2 j + 1`` down; a multi-joint task's other
    actions move the joints of their row of the action table (:func:`action_directions`). A
    joint whose move would leave its limits stays where it is. The reward is the paper's (+100 at
    the goal, -1 otherwise) plus ``shaping`` times the change of :func:`reach_potential`.
    """
    shaping = params[_SHAPING]
    before = reach_potential(params, state) if shaping != 0.0 else 0.0
    if params[_MULTI] == 0.0:
        j = action // 2
        moved = state[j] + (params[_STEP] if action % 2 == 0 else -params[_STEP])
        if params[_LOWER + j] <= moved <= params[_UPPER + j]:
            state[j] = moved
    else:
        row = _TABLE + ROBOT_JOINTS * action
        for j in range(state.shape[0]):
            direction = params[row + j]
            if direction != 0.0:
                moved = state[j] + direction * params[_STEP]
                if params[_LOWER + j] <= moved <= params[_UPPER + j]:
                    state[j] = moved
    done = reach_success(params, state)
    reward = GOAL_REWARD if done else STEP_REWARD
    if shaping != 0.0:
        reward += shaping * (reach_potential(params, state) - before)
    return reward, done


@njit(nogil=True, cache=True)
def _walk(params, path, actions):
    """Fill ``actions`` with the walk along ``path``; returns their number.

    Returns -1 when the walk never reaches the goal. See :meth:`ArmReach.demonstration_actions`.
    """
    joints = path.shape[1]
    n_actions = (params.shape[0] - _N_PARAMS) // ROBOT_JOINTS
    step = params[_STEP]
    state = path[0].copy()
    if reach_success(params, state):
        return 0
    n = 0
    for i in range(1, path.shape[0]):
        while n < actions.shape[0]:
            best = -1
            best_score = 0.5 * step
            for a in range(n_actions):
                row = _TABLE + ROBOT_JOINTS * a
                score = 0.0
                for j in range(joints):
                    direction = params[row + j]
                    if direction == 0.0:
                        continue
                    gap = path[i, j] - state[j]
                    moved = state[j] + direction * step
                    if (
                        abs(gap) <= 0.5 * step
                        or direction * gap < 0.0
                        or not params[_LOWER + j] <= moved <= params[_UPPER + j]
                    ):
                        score = -1.0
                        break
                    score += abs(gap)
                if score > best_score:
                    best_score = score
                    best = a
            if best < 0:
                break
            actions[n] = best
            n += 1
            _, done = reach_step(params, state, best)
            if done:
                return n
    return -1
