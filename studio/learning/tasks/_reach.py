"""The continuous arm task: joints 1..J of a robot reach a demonstrated pose, step by step.

The robot is any arm of the registry (``studio.kinematics.robot_names``; ``robot``, the Puma560
by default). The state is its first ``joints`` joint angles (radians, inside the robot's limits,
at most six); the other joints stay at the goal's values. With ``actions="single"`` an action moves
ONE joint by ``step_deg`` (2J actions: joint 1 up, joint 1 down, joint 2 up, ...);
``actions="pairs"`` adds every two joints moving together, each up or down (the
diagonals, 2J**2 actions), and
``actions="all"`` every joint -1/0/+1 at once (3**J - 1 actions); see :data:`ACTION_SETS` and
:func:`action_directions`. ``actions="follow"`` adds to the single joints one action that moves
every joint at once along the demonstrated paths (:attr:`ArmReach.paths`, :mod:`._follow`), so a
policy can move as its demonstrations did; it is the default, and without demonstrations it is
one joint per action. ``actions="all-follow"`` adds the follow action to ``"all"``'s moves
instead: the follow action reaches the goal, the multi-joint moves let a policy cut the
demonstrated paths short (without demonstrations it is ``"all"``). A joint whose move would leave its limits stays where it is, as on
the paper's grid (the action's other joints still move). Reaching the goal pays :data:`GOAL_REWARD` and ends the
episode, every other step pays :data:`STEP_REWARD` (the paper's rewards), plus a potential-based
shaping term (:data:`DEFAULT_SHAPING`). Episodes start uniformly across the limits (a start already
at the goal is redrawn).

Why one joint per action, and beside it the follow action when there are demonstrations, is the
default (:data:`DEFAULT_ACTIONS`; measured in ``benchmarks/bench_actions.py``,
``benchmarks/bench_robots_learning.py`` and ``benchmarks/bench_demos.py``): with one weight
column per action, each multi-joint move learned only from its own visits and the multi-joint
sets learned far worse; the learner's factored action value (:mod:`._factored`) shares what
each joint's part of a move learned among every move that has it, and with it the pairs learn in
fewer real steps and move joints together, but their greedy success is not steady over training
(:data:`DEFAULT_ACTIONS`). Every joint -1/0/+1 at once (3**J - 1 actions, 728 for six joints)
overshoots near the goal even so. There is no "stay" action: it never helps a reach, and with
function approximation its estimate can stick above the moves' and freeze the arm.

The goal is judged where a user sees it: the robot's tool frame (the Puma560's DH frame 6) within
``position_tolerance`` metres and ``angle_tolerance_deg`` degrees of the goal's tool pose, by
forward kinematics. :func:`tool_pose` is a numba twin of the robot's forward kinematics, so the
kernels can call it: for every arm, the Puma560 (its URDF built from its DH table) as any other,
the serial chain Pinocchio builds from its URDF (each joint's fixed placement and rotation axis,
then the tool frame's placement: :attr:`studio.kinematics.RobotArm.chain`). A test holds it equal
to Pinocchio's forward kinematics for every offered robot.

Dynamics are defined once, here, in numba functions (:func:`reach_step`, :func:`reach_success`): the learner's compiled kernel and the Gymnasium environment
``TeachStudio/ArmReach-v0`` both call them.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from ..._kernels import frozen
from .._config import (
    ACTION_SETS,
    DEFAULT_ACTIONS,
    DEFAULT_JOINTS,
    DEFAULT_SHAPING,
    DEFAULT_STEP_DEG,
    DEFAULT_TILINGS,
    FACTORED_ACTION_SETS,
    FOLLOW_ACTION_SETS,
)
from .._errors import ConfigError, LearningError
from .._tiles import TileCoding
from ._arm import GOAL_REWARD, STEP_REWARD
from ._chain import chain_joint, compose, put_chain
from ._follow import (
    checked_paths,
    cost_bound,
    follow,
    follow_cost,
    followed_points,
    with_cost_group,
)
from ._obstacles import (
    check_goal_clear,
    move_blocked,
    obstacle_values,
    sphere_count,
    sweep_bound,
    task_obstacles,
)
from ._reach_layout import (
    _ANG_TOL,
    _CHAIN_N,
    _COUNTS,
    _GOAL_P,
    _GOAL_R,
    _HOLD,
    _J,
    _LOWER,
    _MIN_TRACE,
    _MULTI,
    _N_BOXES,
    _N_PARAMS,
    _N_SPHERES,
    _OBST,
    _POINT,
    _POS_TOL,
    _POS_TOL2,
    _SHAPING,
    _STEP,
    _SWEEP,
    _TABLE,
    _TOOL,
    _UPPER,
    MAX_CHAIN,
    MAX_JOINTS,
    action_directions,
)
from ._robot import PUMA560, check_robot, default_goal, task_arm

if TYPE_CHECKING:
    from studio.kinematics import Obstacle

MIN_JOINTS = 3
"""Fewest joints the continuous task offers (the paper's three)."""
MAX_STEP_DEG = 2.0
"""Coarsest step allowed: beyond it the tool jumps by several centimetres per step."""
MIN_STEP_DEG = 0.05
"""Finest step allowed: below it an episode across the limits takes tens of thousands of steps."""
DEFAULT_POSITION_TOLERANCE = 0.02
"""Tool within this many metres of the goal's tool position counts as reached."""
DEFAULT_ANGLE_TOLERANCE_DEG = 10.0
"""...and within this many degrees of the goal's tool orientation."""
DEFAULT_TILES = 32
"""Fewest tiles per joint of the arm's default features (each joint tiled alone, see
:meth:`ArmReach.features`): on the Puma560 about 17 degrees of the widest joint each, about 2
degrees resolution over 8 tilings, and 10 degrees of joint 1 (:attr:`ArmReach.default_tiles`)."""
MAX_TILE_DEG = 10.0
"""Widest tile of joints 1-3 in the default features, degrees: the Puma560's joint 1 at 32 tiles
(320 / 32). Joints 1-3 place the tool, so near the goal the greedy policy must tell a step up from
a step down within a degree or two of them; where they turn further (the UR arms' +-360 degrees)
the default adds tiles to keep this width. Measured on the UR5 (6 joints, 4,000 episodes, its
ready goal): 32 tiles (22.5 degrees) 85% greedy success, the greedy policy stepping back and forth
one or two degrees from the goal angles; 64 tiles 100%."""
MAX_SHAPING = 100.0
"""Upper bound on ``shaping``."""
STORED_ACTIONS = "single"
"""What a task stored before ``actions`` existed moves: one joint per action."""
AROUND_GROUPS = ((0, 1), (0, 2))
"""The tile groups a task with obstacles adds to the per-joint ones (:meth:`ArmReach.features`):
joint 1 with joint 2, joint 1 with joint 3, the joints that carry the arm around its base and
up. Measured with a box where a demonstration passes (package README, "Around an obstacle";
``benchmarks/bench_obstacles.py --task arm-reach``, against ``--per-joint-tiles``)."""
LIMIT_SLACK_RAD = 1e-9
"""A demonstration may touch its joint limits within this rounding."""


@dataclass(frozen=True)
class ArmReach:
    """The continuous reaching task over joints 1..``joints`` of a robot.

    Attributes:
        joints: joints learned, from joint 1 (3 to 6, and at most the robot's).
        step_deg: joint increment per action, degrees.
        goal: goal joint angles in radians: ``joints`` values, or one per robot joint (the
            joints beyond ``joints`` are held there); default: the robot's
            (:func:`studio.learning.default_goal`: the Puma560's is
            :data:`studio.learning.DEFAULT_GOAL_DEG`).
        position_tolerance: metres.
        angle_tolerance_deg: degrees.
        shaping: weight of the potential-based shaping reward (:data:`DEFAULT_SHAPING`).
        actions: what one action moves, one of :data:`ACTION_SETS`.
        robot: the robot's registry name (``studio robots`` lists them).
        paths: with ``actions="follow"`` or ``"all-follow"``, the demonstrated joint paths (each ``(N, joints)``
            radians, ending at the goal) that the last action follows: it moves every joint at
            once, by at most one step, along them to the goal (:func:`._follow.follow`), so a policy
            can move as the demonstrations did.
            :func:`run_experiments` fills them from its demonstrations; without any the task
            is one joint per action.
        demo_potential: weight of the demonstrations' shaping potential (Brys et al. 2015,
            :mod:`._demo_shaping`), in reward per joint step; 0 switches it off; None (the
            default) gives what :data:`._demo_shaping.DEMO_SHAPING` leaves beside ``shaping``
            (5 under the paper's reward ``shaping=0``, 0 under the default shaping).
        obstacles: boxes in the robot's base frame (:class:`studio.kinematics.Obstacle`, or
            their dicts): a move that would bring a link into one does not happen
            (:mod:`._obstacles`).

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
    robot: str = PUMA560
    paths: tuple[tuple[tuple[float, ...], ...], ...] = ()
    demo_potential: float | None = None
    obstacles: tuple[Obstacle, ...] = ()

    def __post_init__(self) -> None:
        arm = task_arm(check_robot(self.robot))
        object.__setattr__(self, "obstacles", task_obstacles(self.obstacles))
        most = min(MAX_JOINTS, arm.nq)
        if self.actions not in ACTION_SETS:
            raise ConfigError(
                [
                    f"actions is {self.actions!r}; give {', '.join(map(repr, ACTION_SETS))} (one joint per action, also two together, any joints at once, one joint or following the demonstrations, or any joints at once or following them)."
                ],
                ["actions"],
            )
        if (
            not isinstance(self.joints, int | np.integer)
            or isinstance(self.joints, bool)
            or not MIN_JOINTS <= self.joints <= most
        ):
            raise ConfigError(
                [
                    f"joints is {self.joints!r}; give {MIN_JOINTS} to {most} (joints 1..J of the {arm.spec.title})."
                ],
                ["joints"],
            )
        object.__setattr__(self, "joints", int(self.joints))
        for name, low, high in (
            ("step_deg", MIN_STEP_DEG, MAX_STEP_DEG),
            ("position_tolerance", 1e-4, 1.0),
            ("angle_tolerance_deg", 0.1, 180.0),
            ("shaping", 0.0, MAX_SHAPING),
            ("demo_potential", 0.0, MAX_SHAPING),
        ):
            value = getattr(self, name)
            if name == "demo_potential" and value is None:
                continue
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
        lower, upper = _limits(self.robot)
        goal = default_goal(self.robot)
        if self.goal is not None:
            g = np.asarray(self.goal, dtype=np.float64).reshape(-1)
            if g.shape not in ((self.joints,), (arm.nq,)) or not np.all(np.isfinite(g)):
                raise ConfigError(
                    [
                        f"goal is {self.goal!r}; give {self.joints} or {arm.nq} finite joint angles in radians."
                    ],
                    ["goal"],
                )
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
        object.__setattr__(
            self,
            "paths",
            checked_paths(self.paths, self.actions, self.joints, self.lower, self.upper, self.step),
        )
        if self.obstacles:
            goal_q = np.ascontiguousarray(self.goal[: self.joints])
            if move_blocked(self.params, goal_q, goal_q):
                check_goal_clear(self.robot, self.obstacles, np.asarray(self.goal))
                raise ConfigError(
                    [
                        "An obstacle comes within a few centimetres of the robot at the goal; move or shrink the box, or choose another goal."
                    ],
                    ["obstacles"],
                )

    def with_paths(self, q_paths: Sequence[np.ndarray]) -> ArmReach:
        """This task following ``q_paths`` (joint paths, radians, ``(N, joints)`` or wider) when
        its actions follow (:data:`FOLLOW_ACTION_SETS`) and it has none yet; else this task
        unchanged."""
        if self.actions not in FOLLOW_ACTION_SETS or self.paths or len(q_paths) == 0:
            return self
        return dataclasses.replace(
            self, paths=tuple(np.asarray(q)[:, : self.joints] for q in q_paths)
        )

    # ------------------------------------------------------------------ sizes

    @property
    def n_actions(self) -> int:
        """2J (one joint up or down by one step), 2J**2 with the pairs, 3**J - 1 with all, one
        more when following paths (2J + 1, or 3**J with ``"all-follow"``)."""
        return int(self.directions.shape[0]) + (1 if self.paths else 0)

    @cached_property
    def directions(self) -> np.ndarray:
        """Each fixed action's move, in steps per joint: int8 ``(actions, joints)`` of -1/0/+1
        (all but the follow action, which is last)."""
        return action_directions(self.joints, self.actions)

    @property
    def step(self) -> float:
        """The joint increment, radians."""
        return math.radians(self.step_deg)

    @property
    def lower(self) -> np.ndarray:
        """Lower limits of the learned joints, radians ``(joints,)``."""
        return _limits(self.robot)[0][: self.joints].copy()

    @property
    def upper(self) -> np.ndarray:
        """Upper limits of the learned joints, radians ``(joints,)``."""
        return _limits(self.robot)[1][: self.joints].copy()

    def to_dict(self) -> dict:
        """JSON-ready settings (the inverse of ``ArmReach(**d)``; ``paths`` only when there are
        any, ``demo_potential`` only when set)."""
        return {
            "joints": self.joints,
            "step_deg": self.step_deg,
            "goal": list(self.goal),
            "position_tolerance": self.position_tolerance,
            "angle_tolerance_deg": self.angle_tolerance_deg,
            "shaping": self.shaping,
            "actions": self.actions,
            "robot": self.robot,
            **(
                {"paths": [[list(row) for row in path] for path in self.paths]}
                if self.paths
                else {}
            ),
            **({} if self.demo_potential is None else {"demo_potential": self.demo_potential}),
            **({"obstacles": [o.to_dict() for o in self.obstacles]} if self.obstacles else {}),
        }

    @classmethod
    def from_dict(cls, data: dict) -> ArmReach:
        """Settings from :meth:`to_dict`'s form (one written before ``actions`` existed moves one
        joint per action; one written before ``robot`` existed is the Puma560's)."""
        goal = None if data.get("goal") is None else tuple(data["goal"])
        paths = tuple(tuple(tuple(row) for row in path) for path in data.get("paths") or ())
        obstacles = tuple(data.get("obstacles") or ())
        settings = {"actions": STORED_ACTIONS, **data, "goal": goal, "paths": paths}
        return cls(**{**settings, "obstacles": obstacles})

    @property
    def default_tiles(self) -> int:
        """Tiles per joint of :meth:`features` by default: :data:`DEFAULT_TILES`, or more where
        joints 1-3 turn further than 32 tiles of :data:`MAX_TILE_DEG` (32 for the Puma560 and
        the Panda, 72 for the UR arms)."""
        lower, upper = _limits(self.robot)
        placing = slice(0, min(3, self.joints))
        widest = float(np.degrees(np.max(upper[placing] - lower[placing])))
        return max(DEFAULT_TILES, math.ceil(widest / MAX_TILE_DEG - 1e-6))

    def features(
        self, tilings: int = DEFAULT_TILINGS, tiles: int | None = None, size: int | None = None
    ) -> TileCoding:
        """The default tile coding of this task: every joint tiled on its own, ``tiles`` per
        joint (default: :attr:`default_tiles`).

        One grid over all joints would need ``(tiles + 1) ** joints`` tiles per tiling (1.3e9
        for six joints at 32 tiles) and generalise only within a few degrees in every joint at
        once. With one joint moving per action and the shaping of :data:`DEFAULT_SHAPING`, an
        action's value is nearly a sum of per-joint terms (is the moved joint above or below its
        goal angle, how far are the others), which tilings of each joint alone represent:
        ``J x (tiles + 1)`` tiles per tiling, six joints learn in seconds. Measured against pairs
        of joints (``J (J - 1) / 2 x (tiles + 1) ** 2`` tiles per tiling) at six joints, 4,000
        episodes: 100% greedy success for single joints against 77% for pairs and 94% for both
        (see the package README); pass ``TileCoding(groups=...)`` for other choices.

        With obstacles, one joint per action (``"single"``, ``"follow"``) also tiles joint 1
        with joint 2 and joint 1 with joint 3 (:data:`AROUND_GROUPS`): where a box refuses a
        move depends on where the arm stands as a whole, which a sum of per-joint terms cannot
        tell. The factored action sets (:data:`FACTORED_ACTION_SETS`) keep the per-joint
        features their value is factored over.
        """
        singles = tuple((j,) for j in range(self.joints))
        tiles = self.default_tiles if tiles is None else tiles
        coding = TileCoding(tilings=tilings, tiles=tiles, size=size, groups=singles)
        if self.paths:
            coding = with_cost_group(coding, self.joints)
        if self.obstacles and self.actions not in FACTORED_ACTION_SETS:
            coding = dataclasses.replace(coding, groups=(*(coding.groups or ()), *AROUND_GROUPS))
        return coding

    @cached_property
    def observation_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The box of :meth:`observe`: the joint limits, and with followed paths the follow
        cost's, 0 to :func:`._follow.cost_bound`."""
        if not self.paths:
            return self.lower, self.upper
        high = cost_bound(
            self.lower, self.upper, followed_points(self.paths, self.joints, self.step)
        )
        return np.append(self.lower, 0.0), np.append(self.upper, high)

    def observe(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """What a learner observes at joint angles ``q``: the joints, and with followed paths
        then the follow cost (:func:`._follow.follow_cost`; :mod:`._follow` says why)."""
        state = self._state(q)
        if not self.paths:
            return state.copy()
        return np.append(state, follow_cost(self.params, state)[1])

    @cached_property
    def params(self) -> np.ndarray:
        """The flat parameter array of :func:`reach_step` and friends (read-only)."""
        table = self.directions
        points = followed_points(self.paths, self.joints, self.step)
        chain = task_arm(self.robot).chain
        frames = min(MAX_CHAIN, len(chain.translations))
        blocks = obstacle_values(self.robot, self.obstacles, frames)
        obstacles_at = _N_PARAMS + MAX_JOINTS * table.shape[0] + _POINT * points.shape[0]
        p = np.zeros(obstacles_at + blocks.shape[0], np.float64)
        p[obstacles_at:] = blocks
        p[_OBST] = obstacles_at
        if self.obstacles:
            p[_N_BOXES] = len(self.obstacles)
            p[_N_SPHERES] = sphere_count(self.robot, frames)
            p[_SWEEP] = sweep_bound(self.robot, chain.translations[:frames])
        p[_MULTI] = 0.0 if self.n_actions == 2 * self.joints else 1.0  # single joints only
        p[_COUNTS] = table.shape[0]
        p[_COUNTS + 1] = points.shape[0]
        followed = _TABLE + MAX_JOINTS * table.shape[0]
        p[_TABLE:followed].reshape(-1, MAX_JOINTS)[:, : self.joints] = table
        p[followed:obstacles_at].reshape(-1, _POINT)[:, : self.joints] = points[:, : self.joints]
        p[followed:obstacles_at].reshape(-1, _POINT)[:, MAX_JOINTS:] = points[:, self.joints :]
        p[_J] = self.joints
        p[_STEP] = self.step
        p[_POS_TOL2] = self.position_tolerance**2
        p[_MIN_TRACE] = 1.0 + 2.0 * math.cos(math.radians(self.angle_tolerance_deg))
        lower, upper = _limits(self.robot)
        p[_LOWER : _LOWER + self.joints] = lower[: self.joints]
        p[_UPPER : _UPPER + self.joints] = upper[: self.joints]
        p[_HOLD : _HOLD + len(self.goal)] = self.goal
        p[_SHAPING] = self.shaping
        p[_POS_TOL] = self.position_tolerance
        p[_ANG_TOL] = math.radians(self.angle_tolerance_deg)
        put_chain(p, self.robot)
        oMgoal = np.empty((4, 4))
        tool_pose(frozen(p), np.asarray(self.goal[: self.joints]), oMgoal)  # the kernels' form
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
        """All the robot's joint angles: ``q`` for the learned joints, the goal's for the others."""
        full = np.array(self.goal, dtype=np.float64)
        full[: self.joints] = self._state(q)
        return full

    def random_start(self, rng: np.random.Generator) -> np.ndarray:
        """A start drawn uniformly across the limits, not already at the goal nor touching an
        obstacle."""
        while True:
            q = rng.uniform(self.lower, self.upper)
            if not reach_success(self.params, q) and not move_blocked(self.params, q, q):
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
        free = self.params.copy()
        free[_N_BOXES] = 0.0  # the demonstrated moves as if nothing stood in the way
        free = frozen(free)  # read-only, as the kernels always get it
        n = _follow_walk(free, q[0], actions) if self.paths else -1
        if n < 0:
            n = _walk(free, q, actions)
        if n < 0:
            raise LearningError(
                f"Demonstration {index} never brings the tool within {self.position_tolerance * 100:g} cm and {self.angle_tolerance_deg:g} deg of the goal; end it at the goal or make the goal its final pose."
            )
        return q[0].copy(), actions[:n].copy()


def tool_positions(robot: str, q: np.ndarray) -> np.ndarray:
    """``robot``'s tool positions ``(N, 3)`` (m) for joint angles ``(N, nq)`` (rad), by the
    compiled forward kinematics (no shared scratch data: safe from any thread)."""
    arm = task_arm(robot)
    q = np.asarray(q, dtype=np.float64).reshape(-1, arm.nq)
    joints = min(MAX_JOINTS, arm.nq)
    p = ArmReach(joints=joints, robot=robot).params.copy()
    read_only = frozen(p)  # the kernels' form; it follows the writes to p
    out = np.empty((q.shape[0], 3))
    pose = np.empty((4, 4))
    for i, row in enumerate(q):
        p[_HOLD : _HOLD + arm.nq] = row
        tool_pose(read_only, np.ascontiguousarray(row[:joints]), pose)
        out[i] = pose[:3, 3]
    return out


def _limits(robot: str) -> tuple[np.ndarray, np.ndarray]:
    """Every joint's limits of ``robot``, radians ``(nq,)`` each."""
    arm = task_arm(robot)
    return np.asarray(arm.lower, dtype=np.float64), np.asarray(arm.upper, dtype=np.float64)


def _walk_capacity(q: np.ndarray, step: float) -> int:
    """An upper bound on the walk's actions: the path's joint travel in steps, plus slack."""
    travel = np.abs(np.diff(q, axis=0)).sum() if q.shape[0] > 1 else 0.0
    return int(travel / step) + q.shape[0] * q.shape[1] + 8


# --------------------------------------------------------------------------- compiled dynamics


@njit(nogil=True, cache=True)
def tool_pose(params, state, out):
    """The tool pose ``oMtool`` at ``state`` into ``out`` (4x4): the numba twin of the robot's
    forward kinematics. ``state`` holds the learned joints, the others come from the held goal
    angles in ``params``. Serial-chain forward kinematics: per joint its fixed placement, then the
    rotation by its angle about its axis (Rodrigues), then the tool frame's placement; the
    composition of Pinocchio's ``oMi = oMparent * jointPlacement * M(q)``."""
    for i in range(4):
        for k in range(4):
            out[i, k] = 1.0 if i == k else 0.0
    rotation = np.empty(12)
    for i in range(int(params[_CHAIN_N])):
        chain_joint(out, params, state, i, rotation)
    compose(out, params, _TOOL)


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
    actions move the joints of their row of the action table (:func:`action_directions`), and
    the one after the table follows the demonstrated paths (:func:`._follow.follow`). A joint whose move
    would leave its limits stays where it is; a move that would bring a link into an obstacle
    does not happen (:func:`._obstacles.move_blocked`: the arm stays, the step pays -1). The reward is the paper's (+100 at
    the goal, -1 otherwise) plus ``shaping`` times the change of :func:`reach_potential`.
    """
    shaping = params[_SHAPING]
    before = reach_potential(params, state) if shaping != 0.0 else 0.0
    boxed = params[_N_BOXES] != 0.0
    start = state.copy() if boxed else state
    if params[_MULTI] == 0.0:
        j = action // 2
        moved = state[j] + (params[_STEP] if action % 2 == 0 else -params[_STEP])
        if params[_LOWER + j] <= moved <= params[_UPPER + j]:
            state[j] = moved
    elif action >= params[_COUNTS]:
        follow(params, state)
    else:
        row = _TABLE + MAX_JOINTS * action
        for j in range(state.shape[0]):
            direction = params[row + j]
            if direction != 0.0:
                moved = state[j] + direction * params[_STEP]
                if params[_LOWER + j] <= moved <= params[_UPPER + j]:
                    state[j] = moved
    if boxed and move_blocked(params, start, state):
        state[:] = start  # the move would touch an obstacle: it does not happen
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
    n_actions = int(params[_COUNTS])  # the follow action is walked by _follow_walk
    step = params[_STEP]
    state = path[0].copy()
    if reach_success(params, state):
        return 0
    n = 0
    for i in range(1, path.shape[0]):
        while n < actions.shape[0]:
            best = np.int64(-1)  # not the constant: reach_step would compile again for a literal
            best_score = 0.5 * step
            for a in range(n_actions):
                row = _TABLE + MAX_JOINTS * a
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


@njit(nogil=True, cache=True)
def _follow_walk(params, start, actions):
    """Fill ``actions`` with the follow action from ``start`` until the goal; returns their
    number, or -1 when following stalls (a move under half a step) before it."""
    state = start.copy()
    if reach_success(params, state):
        return 0
    follow = int(params[_COUNTS])
    before = np.empty_like(state)
    for n in range(actions.shape[0]):
        before[:] = state
        actions[n] = follow
        _, done = reach_step(params, state, follow)
        if done:
            return n + 1
        moved = 0.0
        for j in range(state.shape[0]):
            moved = max(moved, abs(state[j] - before[j]))
        if moved < 0.5 * params[_STEP]:
            return -1
    return -1
