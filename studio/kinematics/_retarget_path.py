"""A recorded human-arm motion retargeted onto a robot, its IK branches planned with the whole
motion known.

Live, the retargeting knows only the past. It keeps to the IK branch it is on while a pose within
one frame's joint motion (``RetargetConfig.max_joint_step``) reaches the hand's target; when
none does, it walks at that step to the nearest pose of another branch, and misses the target
while it walks. A recording is known whole, so :func:`retarget_path` plans the branches:

1. The live pass, frame after frame: the path a session would have shown. Where it reaches every
   frame, that is the path.
2. *Tracks*: runs of frames along which a pose that reaches the target is followed within the
   step cap (:meth:`Retargeter.pose_near`). The live pass's reached runs are tracks, each also
   followed back before its first frame. More start from the poses the IK finds
   (:meth:`Retargeter.poses_reaching`) on the first frame and at the start, middle and end of
   each run of frames the live pass missed, each followed both ways for as long as it reaches
   and does not join a track already found.
3. The route through the tracks that misses the fewest frames, by dynamic programming over the
   frames. Staying on a track costs nothing. Leaving track k at frame a for track j at frame b
   costs the b - a - 1 frames between, walked in a straight line in joint space, and is allowed
   when no joint has further to go than b - a steps. A walk that would bring the robot's links
   closer than ``RetargetConfig.clearance`` is struck out and the route found again. A hop
   from one track to another in a frame is eased: spread over the frames around it where both
   tracks hold poses, wherever the blend still reaches every frame (``_eased``).
4. Through the frames the route still misses: between the reached frames either side of each
   run, the walk goes through poses that reach some of its frames, found frame by frame within
   the step cap of the last pose kept and of the reached frame after (``_through_misses``).

The live pass is one of the routes, and the plan is kept only where it reaches at least as many
frames, so a planned path never reaches fewer; step 4 only adds frames reached. Every joint stays
within its limits (the tracks' poses do, and a straight walk between two of them does) and moves
at most ``max_joint_step`` a frame.

Whether a tool has reached a target, and whether any pose of the robot could: the retargeting's
goal is the tool within ``RetargetConfig.reach_tolerance`` (1 cm) and
``RetargetConfig.reach_angle`` (5 deg) of the hand's target wherever the target is reachable.
This module is the one definition of both halves, used by the planner above and by the
retargeting's tests and benchmarks:

- :func:`tool_reaches`: the tool at ``q`` is within those tolerances of the target (the angle is
  not asked of an arm that follows the position only).
- :func:`reachable`: some pose of the arm reaches the target: within its joint limits, its links
  at least ``RetargetConfig.clearance`` apart, and, given ``near``, no joint further than
  ``RetargetConfig.max_joint_step`` from ``near`` (the target can be reached in the one frame the
  step cap allows from there), or given ``within_steps_of``, within the joint motion so many
  frames allow of each of those poses (the target can be reached on the way from one to the
  other). It is a search: the IK, run to convergence from ``near`` (or
  home) and from :data:`REACHABLE_STARTS` (:data:`NEAR_STARTS` given ``near``) starts drawn at
  random (seeded) within those bounds;
  "not reachable" means none of those starts found a pose.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from ._puma import Puma560
from ._retarget import RetargetConfig, Retargeter
from ._robots import RobotArm, RobotIK, tool_errors
from .human._human import HumanArm

REACHABLE_STARTS = 24
"""Random starts of :func:`reachable`'s search over the joint ranges, besides home."""

NEAR_STARTS = 8
"""Random starts of :func:`reachable`'s search within one frame's joint motion of ``near``,
besides ``near`` itself (a small box: fewer starts cover it)."""

REACHABLE_ITERATIONS = 200
"""IK iterations from each start of :func:`reachable`'s search (enough to converge)."""


def reach_errors(
    robot: RobotArm | Puma560, q: np.ndarray, oMdes: np.ndarray
) -> tuple[float, float]:
    """How far (m) and how turned (rad) the tool at ``q`` is from ``oMdes`` (4x4); the angle is
    0 for an arm that follows the position only."""
    orientation = not isinstance(robot, RobotArm) or robot.spec.orientation
    return tool_errors(robot.forward(q), oMdes, orientation)


def tool_reaches(
    robot: RobotArm | Puma560,
    q: np.ndarray,
    oMdes: np.ndarray,
    config: RetargetConfig | None = None,
) -> bool:
    """Whether the tool at ``q`` has reached ``oMdes`` (:meth:`RetargetConfig.within_reach`)."""
    return (config or RetargetConfig()).within_reach(*reach_errors(robot, q, oMdes))


def reachable(
    arm: RobotArm,
    oMdes: np.ndarray,
    config: RetargetConfig | None = None,
    near: np.ndarray | None = None,
    *,
    within_steps_of: Sequence[tuple[np.ndarray, int]] = (),
) -> bool:
    """Whether some pose of ``arm`` reaches ``oMdes`` (see the module docstring).

    Args:
        arm: the robot (the Puma560 too, as ``load_robot("puma560")``).
        oMdes: the tool's target (4x4, the arm's base frame).
        config: the tolerances, the clearance and the step cap.
        near: a pose: only poses within one frame's joint motion of it count.
        within_steps_of: ``(pose, frames)`` pairs: only poses within ``frames`` frames' joint
            motion of every such pose count (a target reachable on the way from one pose to
            another, ``frames`` after the first and before the second).
    """
    config = config or RetargetConfig()
    bounds = [*within_steps_of, *([] if near is None else [(near, 1)])]
    lower, upper = steps_box(arm, config, bounds)
    if np.any(lower > upper):
        return False
    rng = np.random.default_rng(0)
    first = arm.home if near is None else near
    starts = REACHABLE_STARTS if near is None else NEAR_STARTS
    found = pose_within(
        arm, oMdes, config, (lower, upper), (first, *rng.uniform(lower, upper, (starts, arm.nq)))
    )
    return found is not None


def steps_box(
    arm: RobotArm, config: RetargetConfig, poses: Sequence[tuple[np.ndarray, int]]
) -> tuple[np.ndarray, np.ndarray]:
    """The joint box ``(lower, upper)`` within the limits and within ``frames`` frames' joint
    motion (``config.max_joint_step`` each) of every ``(pose, frames)``; empty (some lower above
    its upper) where they do not meet."""
    lower, upper = arm.lower, arm.upper
    for pose, frames in poses:
        reach = config.max_joint_step * frames
        lower, upper = np.maximum(lower, pose - reach), np.minimum(upper, pose + reach)
    return lower, upper


def pose_within(
    arm: RobotArm,
    oMdes: np.ndarray,
    config: RetargetConfig,
    box: tuple[np.ndarray, np.ndarray],
    starts: Iterable[np.ndarray],
    iterations: int = REACHABLE_ITERATIONS,
    accept: Callable[[np.ndarray], bool] | None = None,
) -> np.ndarray | None:
    """The first pose within ``box`` (``(lower, upper)``) that the IK finds from one of
    ``starts`` (each clipped into it), that reaches ``oMdes`` clear of contact (its own links
    and the table: :meth:`RobotArm.contacts`) and that ``accept`` (if given) takes; None if
    none does."""
    lower, upper = box
    for start in starts:
        q = arm.inverse(
            oMdes, np.clip(start, lower, upper), iterations=iterations, lower=lower, upper=upper
        ).q
        if not tool_reaches(arm, q, oMdes, config) or arm.contacts(q, config.clearance):
            continue
        if accept is None or accept(q):
            return q
    return None


APART = 0.2
"""Poses the IK finds on one frame count as different branches when a joint differs by more
than this (rad)."""

JOINED = 0.05
"""A track being followed stops where it comes this near a track already found (rad, every
joint): it has joined that branch."""

DEPART_EVERY = 2
"""The route may leave a track at every this many frames, and at its last frame."""

CHUNK = 2200
"""Frames routed at a time (20 s at 110 Hz): the route search holds every track's poses over
the frames it routes, so a long recording is routed a chunk at a time, each chunk from the last
one's final pose."""

MID_WALK = 40
"""Frames of the longest walk looked at from a track before its last frame (180 degrees at the
4.5 degree step); from its last frame, walks of any length are."""

WALK_BAN = 10
"""A walk that brings links into contact is struck out from the departures this many frames
either side of it too (their walks pass the same poses)."""

EASE = 16
"""Frames a hop from one track to another is spread over (:func:`_eased`), half before it and
half after, where both tracks hold poses."""

WALK_RETRIES = 8
"""Routes found again after a walk was struck out for a collision, before the live pass is
kept."""

THROUGH_STARTS = 16
"""Random starts, within the step cap of the poses either side, of the search for a pose that
reaches a frame the route walks through (besides the last pose kept)."""


@dataclass(frozen=True)
class RetargetedPath:
    """A human-arm path retargeted onto one robot, frame by frame (:func:`retarget_path`).

    Attributes:
        q: the robot's joints, one row per frame (rad, ``(N, nq)``).
        position_error: how far the tool stays from the hand's target per frame (m; 0 in joint
            mode, which has no target).
        out_of_reach: the frames whose target is out of reach (``RetargetConfig.reach_tolerance``):
            the IK found no pose that reaches it.
        pulled_in: per frame, how far the hand's target was drawn back into the robot's reach
            (m; the hand went beyond it, and the robot followed the drawn-back target; 0 in
            joint mode).
        reached: per frame, whether the tool is on the hand's target
            (:func:`tool_reaches`; True in joint mode, which has no target). A frame neither
            reached nor out of reach is one the robot walks from one IK branch to another.
    """

    q: np.ndarray
    position_error: np.ndarray
    out_of_reach: np.ndarray
    pulled_in: np.ndarray
    reached: np.ndarray


@dataclass
class _Track:
    """Poses that reach the target on frames ``start`` .. ``start + len(q) - 1``."""

    start: int
    q: np.ndarray

    @property
    def end(self) -> int:
        return self.start + len(self.q) - 1


def retarget_path(
    robot: RobotArm,
    q_human: np.ndarray,
    config: RetargetConfig | None = None,
    *,
    side: str = "right",
    as_live: bool = False,
) -> RetargetedPath:
    """Retarget a human-arm path ``(N, 7)`` onto ``robot``, its IK branches planned.

    The Puma560 in joint mode (the paper's, which has no branches to plan), any other arm in
    cartesian mode, planned as the module docstring says. The first frame is settled first (the
    IK starts cold there, so it gets ``config.settle_tries`` passes). Safe beside a live session
    of the same robot: it computes on scratch data of its own (:meth:`RobotArm.scratch_copy`).

    Args:
        robot: the robot, from :func:`load_robot`.
        q_human: the human arm's angles, one row per frame (rad).
        config: the retargeting's settings.
        side: the operator's arm the angles are of (``HumanArm``'s convention for that side),
            as the recording says: a left arm's angles read as a right arm's would mirror the
            robot's motion.
        as_live: the path a live session would have shown (frame after frame, each
            warm-started from the one before), without the plan.

    Raises:
        KinematicsError: angles of the wrong shape or not finite, or a side other than
            ``"right"`` or ``"left"``.
    """
    config = config or RetargetConfig()
    q_h = np.asarray(q_human, dtype=float).reshape(-1, 7)
    human = HumanArm(side=side)
    if robot.spec.joint_mode:  # joint mode (the Puma560's, the paper's): no target
        retargeter, targets = Retargeter(arm=human, config=config), None
    else:
        retargeter = Retargeter(robot=robot.scratch_copy(), arm=human, config=config)
        targets = [retargeter.hand_target(q) for q in q_h]
    live = _live(retargeter, q_h, config, targets)
    arm = retargeter.robot
    if as_live or targets is None or live.reached.all():
        return live
    assert isinstance(arm, RobotArm)
    planned = _plan(retargeter, q_h, targets, live.q, live.reached, config)
    reached = _reaching(arm, planned, targets, config)
    if reached.sum() < live.reached.sum():  # never fewer frames than live
        planned, reached = live.q, live.reached
    planned = _through_misses(arm, planned, reached, targets, config)
    errors = [reach_errors(arm, q, t) for q, t in zip(planned, targets, strict=True)]
    now = np.array([config.within_reach(*e) for e in errors], dtype=bool)
    error = np.array([e[0] for e in errors])
    return RetargetedPath(planned, error, live.out_of_reach & ~now, live.pulled_in, now)


def _reaching(
    arm: RobotArm, q: np.ndarray, targets: list[np.ndarray], config: RetargetConfig
) -> np.ndarray:
    """Per frame, whether the tool at ``q`` is on its target."""
    return np.array([tool_reaches(arm, *pair, config) for pair in zip(q, targets, strict=True)])


def _through_misses(
    arm: RobotArm,
    path: np.ndarray,
    reached: np.ndarray,
    targets: list[np.ndarray],
    config: RetargetConfig,
) -> np.ndarray:
    """``path`` with each run of frames it misses walked through poses that reach some of them.

    Between the reached frames either side of a run (or the run's open end), the walk is
    straight in joint space. Frame by frame along the run, a pose is searched that reaches the
    frame's target within the step cap of the last pose kept (the reached frame before, or the
    last such pose) and of the reached frame after, and whose straight walks from the one and
    on to the other keep the links clear; each one found is kept, and the walk goes straight
    from one to the next. So no frame reached before is missed after, no joint moves further
    than the step cap a frame, and the walk touches nothing.
    """
    path = path.copy()
    n = len(path)
    rng = np.random.default_rng(0)
    for first, last in _runs(~reached):
        end = [(last + 1, path[last + 1])] if last + 1 < n else []
        kept = [(first - 1, path[first - 1])] if first > 0 else []
        for i in range(first, last + 1):
            before = kept[-1:]
            ends = [(q, abs(frame - i)) for frame, q in [*before, *end]]
            lower, upper = steps_box(arm, config, ends)
            if np.any(lower > upper):
                continue
            starts = [q for _, q in before]
            starts += list(rng.uniform(lower, upper, (THROUGH_STARTS, arm.nq)))
            found = pose_within(
                arm,
                targets[i],
                config,
                (lower, upper),
                starts,
                config.restart_iterations,
                accept=lambda q, i=i, before=before, end=end: _clear_walk(
                    arm, [*before, (i, q), *end], config
                ),
            )
            if found is not None:
                kept.append((i, found))
        if any(i >= first for i, _ in kept):
            path[first : last + 1] = _straight([*kept, *end], first, last)
    return path


def _clear_walk(arm: RobotArm, poses: list[tuple[int, np.ndarray]], config: RetargetConfig) -> bool:
    """Whether the straight walks between ``poses`` (``(frame, q)``, in order) keep the links
    clear on every frame between them."""
    first, last = poses[0][0], poses[-1][0]
    walk = _straight(poses, first, last)
    return not any(arm.contacts(q, config.clearance) for q in walk[1:-1])


def _straight(poses: list[tuple[int, np.ndarray]], first: int, last: int) -> np.ndarray:
    """Frames ``first`` .. ``last`` walked straight in joint space from one of ``poses``
    (``(frame, q)`` in order of frame) to the next; held before the first and after the last."""
    frames = np.arange(first, last + 1)
    at = np.array([i for i, _ in poses], dtype=float)
    q = np.array([q for _, q in poses])
    return np.column_stack([np.interp(frames, at, q[:, j]) for j in range(q.shape[1])])


def _live(
    retargeter: Retargeter,
    q_h: np.ndarray,
    config: RetargetConfig,
    targets: list[np.ndarray] | None,
) -> RetargetedPath:
    """The path a live session would have shown, frame after frame; ``targets``: the hand's
    target per frame (None in joint mode, whose frames all count as reached)."""
    robot = retargeter.robot
    q = np.empty((len(q_h), robot.nq))
    error = np.zeros(len(q_h))
    out = np.zeros(len(q_h), dtype=bool)
    reached = np.ones(len(q_h), dtype=bool)
    pulled = np.zeros(len(q_h))
    for _ in range(config.settle_tries if len(q_h) else 0):
        retargeter.robot_from_human(q_h[0])
        if not isinstance(retargeter.last_ik, RobotIK) or retargeter.last_ik.success:
            break
    for i, q_frame in enumerate(q_h):
        q[i] = retargeter.robot_from_human(q_frame)
        pulled[i] = retargeter.pulled_in
        ik = retargeter.last_ik
        if isinstance(ik, RobotIK) and targets is not None:
            error[i] = ik.position_error
            out[i] = not ik.success and ik.position_error > config.reach_tolerance
            reached[i] = tool_reaches(robot, q[i], targets[i], config)
    return RetargetedPath(q, error, out, pulled, reached)


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """The runs of True in ``flags``, as (first, last) frames."""
    edges = np.flatnonzero(np.diff(np.r_[0, flags.astype(int), 0]))
    return [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _plan(
    retargeter: Retargeter,
    q_h: np.ndarray,
    targets: list[np.ndarray],
    live: np.ndarray,
    reached: np.ndarray,
    config: RetargetConfig,
) -> np.ndarray:
    """The planned path's joints (see the module docstring), or ``live``'s. ``targets``: the
    hand's target on each frame."""
    found = _Found(len(q_h))
    for first, last in _runs(reached):
        before = _follow(retargeter, q_h, first, live[first], -1, found, targets)
        found.add(_Track(first - len(before), np.vstack([*before[::-1], live[first : last + 1]])))
    seeds = {0}
    for first, last in _runs(~reached):
        seeds |= {first, (first + last) // 2, last}
    for t in sorted(seeds):
        for q in retargeter.poses_reaching(q_h[t], APART):
            if found.joined(t, q):
                continue
            before = _follow(retargeter, q_h, t, q, -1, found, targets)
            after = _follow(retargeter, q_h, t, q, 1, found, targets)
            found.add(_Track(t - len(before), np.vstack([*before[::-1], q, *after])))
    arm = retargeter.robot
    assert isinstance(arm, RobotArm)
    if not found.tracks:  # no pose found reaches any frame
        return live
    # Routed a chunk at a time (the search holds every track's poses over its frames), each
    # chunk from the last one's final pose.
    path = np.empty_like(live)
    for c0 in range(0, len(q_h), CHUNK):
        c1 = min(c0 + CHUNK, len(q_h))
        lo = max(c0 - 1, 0)
        tracks = [_Track(0, path[lo : lo + 1])] if c0 else []
        for track in found.tracks:
            first, last = max(track.start, lo), min(track.end, c1 - 1)
            if first <= last:
                q = track.q[first - track.start : last - track.start + 1]
                tracks.append(_Track(first - lo, q))
        piece = _chunk_path(tracks, targets[lo:c1], arm, config, anchored=c0 > 0)
        if piece is None:
            return live
        path[lo:c1] = piece
    return path


def _chunk_path(
    tracks: list[_Track],
    targets: list[np.ndarray],
    arm: RobotArm,
    config: RetargetConfig,
    anchored: bool,
) -> np.ndarray | None:
    """The joints of the route through ``tracks`` over the frames of ``targets`` (the hand's
    target on each) whose walks keep the links clear, its hops eased (:func:`_eased`); None if
    none is found in ``WALK_RETRIES`` tries. ``anchored``: it starts on the first track, at
    frame 0."""
    if not tracks:
        return None
    frames = len(targets)
    banned: set[tuple[int, int, int]] = set()
    for _ in range(WALK_RETRIES):
        route = _route(tracks, frames, config.max_joint_step, banned, anchored)
        path, clash = _walked(tracks, route, frames, arm, config.clearance)
        if clash is None:
            return _eased(tracks, route, path, targets, arm, config)
        k, t, j = clash  # its neighbours would mostly touch too
        banned |= {(k, t + dt, j) for dt in range(-WALK_BAN, WALK_BAN + 1)}
    return None


class _Found:
    """The tracks found so far, and the poses they hold on each frame."""

    def __init__(self, frames: int) -> None:
        self.tracks: list[_Track] = []
        self._on: list[list[np.ndarray]] = [[] for _ in range(frames)]

    def add(self, track: _Track) -> None:
        self.tracks.append(track)
        for i, q in enumerate(track.q):
            self._on[track.start + i].append(q)

    def joined(self, t: int, q: np.ndarray) -> bool:
        """Whether ``q`` on frame ``t`` lies on a track already found."""
        on = self._on[t]
        return bool(on) and float(np.abs(np.asarray(on) - q).max(axis=1).min()) < JOINED


def _follow(
    retargeter: Retargeter,
    q_h: np.ndarray,
    t: int,
    q: np.ndarray,
    direction: int,
    found: _Found,
    targets: list[np.ndarray],
) -> list[np.ndarray]:
    """The poses that follow ``q`` (on frame ``t``) frame by frame in ``direction`` while one
    within a step reaches the target (``targets``, per frame), until it joins a track already
    ``found``."""
    out = []
    t += direction
    while 0 <= t < len(q_h):
        near = retargeter.pose_near(q, q_h[t], targets[t])
        if near is None:
            break
        q = near
        out.append(q)
        if found.joined(t, q):
            break
        t += direction
    return out


def _route(
    tracks: list[_Track],
    frames: int,
    step: float,
    banned: set[tuple[int, int, int]],
    anchored: bool = False,
) -> list[tuple[int, int, int]]:
    """The route that misses the fewest frames: (track, first frame, last frame) per leg. It
    starts on any track (the frames before it held), or, ``anchored``, on the first."""
    count, nq = len(tracks), tracks[0].q.shape[1]
    every = np.vstack([track.q for track in tracks])
    # no walk between two tracks' poses is longer than this
    window = math.ceil(float((every.max(axis=0) - every.min(axis=0)).max()) / step) + 1
    mid = min(window, MID_WALK)
    poses = np.full((count, frames + window + 1, nq), np.nan)
    for k, track in enumerate(tracks):
        poses[k, track.start : track.end + 1] = track.q
    best = np.full((count, frames), np.inf)
    came = np.full((count, frames, 2), -1)
    for k, track in enumerate(tracks[:1] if anchored else tracks):
        best[k, track.start] = track.start  # the frames before are held, missed
    steps = np.arange(1, window + 1)
    starts = np.array([track.start for track in tracks])
    ends = np.array([track.end for track in tracks])
    for t in range(frames):
        alive = ends > t
        for k in np.flatnonzero(np.isfinite(best[:, t])):
            end = tracks[k].end
            if t < end and best[k, t] < best[k, t + 1]:
                best[k, t + 1], came[k, t + 1] = best[k, t], (k, t)
            if t % DEPART_EVERY and t != end:
                continue
            walk = window if t == end else mid  # the longest walk looked at from here
            near = np.flatnonzero(alive & (starts <= t + walk))  # tracks a walk could reach
            with np.errstate(invalid="ignore"):
                ahead = poses[near, t + 1 : t + 1 + walk]
                ok = np.ceil(np.abs(ahead - poses[k, t]).max(axis=2) / step - 1e-9) <= steps[:walk]
            ok[near == k] = False
            for row in np.flatnonzero(ok.any(axis=1)):
                j = int(near[row])
                b = t + 1 + int(ok[row].argmax())
                cost = best[k, t] + b - t - 1
                if b < frames and (k, t, j) not in banned and cost < best[j, b]:
                    best[j, b], came[j, b] = cost, (k, t)
            if t == end:  # beyond the window any walk has time enough: on at their first frame
                for j in np.flatnonzero(starts > t + window):
                    cost = best[k, t] + starts[j] - t - 1
                    if (k, t, j) not in banned and cost < best[j, starts[j]]:
                        best[j, starts[j]], came[j, starts[j]] = cost, (k, t)
    missed = [best[k, track.end] + frames - 1 - track.end for k, track in enumerate(tracks)]
    k = int(np.argmin(missed))
    t = tracks[k].end
    legs = [[k, t, t]]
    while True:
        pk, pt = came[k, t]
        if pk < 0:
            legs[-1][1] = t
            break
        if pk != k:
            legs[-1][1] = t
            legs.append([int(pk), int(pt), int(pt)])
        k, t = int(pk), int(pt)
    return [(k, a, b) for k, a, b in reversed(legs)]


def _eased(
    tracks: list[_Track],
    route: list[tuple[int, int, int]],
    path: np.ndarray,
    targets: list[np.ndarray],
    arm: RobotArm,
    config: RetargetConfig,
) -> np.ndarray:
    """``path`` with each hop between two tracks (one leg's last frame, the next leg's first
    frame after it) spread over the frames around it where both tracks hold poses: there the
    path blends from the one to the other, ``EASE`` frames at most.

    Two tracks a step apart are two IK answers moving differently; hopping from one to the
    other in a frame turns the joints back (a step one way, then the track's the other). The
    blend moves the joints by the tracks' difference a little each frame instead. It is kept
    only where every blended pose still reaches its target clear of contact and no joint steps
    further than ``max_joint_step``: so the eased path reaches as many frames as the hop did.
    """
    path = path.copy()
    for (k, a, b), (j, c, d) in zip(route, route[1:], strict=False):
        if c != b + 1:
            continue  # a walk, not a hop
        one, other = tracks[k], tracks[j]
        first = max(other.start, a, b + 1 - EASE // 2, 1)
        last = min(one.end, d, b + EASE // 2, len(path) - 2)
        if last - first < 1:
            continue
        frames = np.arange(first, last + 1)
        weight = ((frames - first + 1) / (last - first + 2))[:, None]
        blend = (1.0 - weight) * one.q[frames - one.start] + weight * other.q[frames - other.start]
        eased = np.vstack([path[first - 1], blend, path[last + 1]])
        if np.abs(np.diff(eased, axis=0)).max() > config.max_joint_step + 1e-9:
            continue
        if all(
            tool_reaches(arm, q, targets[i], config) and not arm.contacts(q, config.clearance)
            for i, q in zip(frames, blend, strict=True)
        ):
            path[first : last + 1] = blend
    return path


def _walked(
    tracks: list[_Track],
    route: list[tuple[int, int, int]],
    frames: int,
    arm: RobotArm,
    clearance: float,
) -> tuple[np.ndarray, tuple[int, int, int] | None]:
    """The joints along ``route``: its legs, the straight walks between them and the first and
    last poses held before and after; and the first walk that brings links into contact (as the
    route's (track, frame, next track)), or None."""
    nq = tracks[0].q.shape[1]
    path = np.empty((frames, nq))
    k0, a0, _ = route[0]
    path[:a0] = tracks[k0].q[a0 - tracks[k0].start]
    for (k, a, b), nxt in zip(route, [*route[1:], None], strict=True):
        path[a : b + 1] = tracks[k].q[a - tracks[k].start : b - tracks[k].start + 1]
        if nxt is None:
            path[b + 1 :] = path[b]
            break
        j, c, _ = nxt
        start, goal = path[b], tracks[j].q[c - tracks[j].start]
        for i in range(b + 1, c):
            path[i] = start + (goal - start) * (i - b) / (c - b)
            if arm.contacts(path[i], clearance):
                return path, (k, b, j)
    return path, None
