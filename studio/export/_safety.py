"""Safety checks of a joint trajectory before it is written for a real arm.

Every sample is checked against the robot's URDF limits (:class:`studio.kinematics.RobotArm`):

- positions within ``lower``/``upper`` (the hard limits less ``RobotArm.limit_margin``);
- velocities, by finite differences between consecutive samples, within ``velocity``;
- accelerations, by finite differences of those velocities, within ``acceleration``;
- self-collision: :meth:`RobotArm.self_collisions` (Pinocchio and coal on the URDF's collision
  geometry, adjacent links and the SRDF's disabled pairs excluded) closer than
  :data:`COLLISION_MARGIN_M`.

The differences are taken on exactly the samples that go into the file, so what is checked is
what a controller would be sent. Each problem is one :class:`studio.motion.Finding`; a refusal names the first
(by time) and counts the rest.
"""

from __future__ import annotations

import numpy as np

from studio.kinematics import OBSTACLE_TOUCH_M, TABLE, Obstacle, ObstacleGuard, RobotArm
from studio.motion import Finding

from ._errors import SafetyError

COLLISION_MARGIN_M = 0.005
"""Two links closer than this (m) count as colliding: a controller's tracking error and the
collision meshes' own error need room. The meshes are convex hulls, which already err outwards."""
LIMIT_TOLERANCE = 1e-6
"""Relative slack on the velocity and acceleration limits (floating-point noise of the
differences), and absolute slack (rad) on the position limits."""


def _first_over(values: np.ndarray, limit: np.ndarray) -> tuple[int, int] | None:
    """The first (row, joint) where ``|values|`` exceeds ``limit`` by more than the tolerance."""
    over = np.abs(values) > limit * (1.0 + LIMIT_TOLERANCE)
    if not over.any():
        return None
    row, joint = np.argwhere(over)[0]
    return int(row), int(joint)


def differences(times: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Velocities (N-1, nq) between consecutive samples and accelerations (N-2, nq) between
    consecutive velocities: what a controller sent these samples would have to do."""
    dt = np.diff(times)
    velocity = np.diff(q, axis=0) / dt[:, None]
    acceleration = np.diff(velocity, axis=0) / (0.5 * (dt[1:] + dt[:-1]))[:, None]
    return velocity, acceleration


def limit_findings(robot: RobotArm, times: np.ndarray, q: np.ndarray) -> list[Finding]:
    """The first position, velocity and acceleration violation of each joint (at most one of each
    kind per joint, so a long over-speed segment is one finding, not thousands)."""
    found: list[Finding] = []
    names = robot.joint_names
    low = q < robot.lower - LIMIT_TOLERANCE
    high = q > robot.upper + LIMIT_TOLERANCE
    for j, name in enumerate(names):
        rows = np.flatnonzero(low[:, j] | high[:, j])
        if rows.size:
            i = int(rows[0])
            bound = robot.lower[j] if low[i, j] else robot.upper[j]
            found.append(
                Finding(
                    i,
                    float(times[i]),
                    "position",
                    name,
                    f"sample {i} (t = {times[i]:.3f} s): joint {name} at {q[i, j]:.4f} rad is "
                    f"{abs(q[i, j] - bound):.4f} rad beyond its limit {bound:.4f} rad (its hard "
                    f"limit less a {robot.limit_margin[j]:.3f} rad margin)",
                )
            )
    if len(times) < 2:
        return found
    velocity, acceleration = differences(times, q)
    kinds = [
        ("velocity", velocity, robot.velocity, "rad/s", 1),
        ("acceleration", acceleration, robot.acceleration, "rad/s^2", 1),
    ]
    for what, values, limit, unit, offset in kinds:
        for j, name in enumerate(names):
            hit = _first_over(values[:, j : j + 1], limit[j : j + 1])
            if hit is None:
                continue
            i = hit[0] + offset
            value = float(values[hit[0], j])
            found.append(
                Finding(
                    i,
                    float(times[i]),
                    what,
                    name,
                    f"sample {i} (t = {times[i]:.3f} s): joint {name} {what} {abs(value):.3f} "
                    f"{unit} exceeds its limit {limit[j]:.3f} {unit} by "
                    f"{abs(value) - limit[j]:.3f} {unit}",
                )
            )
    return found


def collision_findings(
    robot: RobotArm, times: np.ndarray, q: np.ndarray, margin: float = COLLISION_MARGIN_M
) -> list[Finding]:
    """The first sample at which each link pair comes closer than ``margin`` (m), and at which
    each link comes nearer than that to the table the robot stands on (the plane of its base:
    :meth:`~studio.kinematics.RobotArm.table_contacts`)."""
    found: dict[tuple[str, str], Finding] = {}
    if not robot.checks_collisions:
        return []
    for i in range(len(times)):
        for hit in robot.contacts(q[i], margin):
            pair = (hit.link_a, hit.link_b)
            if pair in found:
                continue
            at = f"sample {i} (t = {times[i]:.3f} s)"
            if hit.link_b == TABLE:
                where = (
                    f"reaches {-hit.distance * 100:.2f} cm below"
                    if hit.distance < 0
                    else f"comes within {hit.distance * 100:.2f} cm of"
                )
                sentence = (
                    f"{at}: link {hit.link_a} {where} the table top the robot stands on (its "
                    f"base's plane), inside the {margin * 100:.1f} cm margin"
                )
            else:
                gap = (
                    f"overlap by {-hit.distance * 100:.2f} cm"
                    if hit.distance < 0
                    else f"are {hit.distance * 100:.2f} cm apart"
                )
                sentence = (
                    f"{at}: links {hit.link_a} and {hit.link_b} {gap}, inside the "
                    f"{margin * 100:.1f} cm self-collision margin"
                )
            found[pair] = Finding(
                i, float(times[i]), "collision", f"{hit.link_a}/{hit.link_b}", sentence
            )
    return list(found.values())


def obstacle_findings(
    robot: RobotArm, times: np.ndarray, q: np.ndarray, obstacles: tuple[Obstacle, ...]
) -> list[Finding]:
    """The first sample by which the arm touches one of ``obstacles`` (boxes in its base frame),
    checked along the straight moves between the samples, not only at them
    (:class:`~studio.kinematics.ObstacleGuard`)."""
    if not obstacles or not robot.checks_collisions:
        return []
    guard = ObstacleGuard(robot, obstacles)
    for i in range(len(q)):
        if not guard.path_collides(q[max(i - 1, 0) : i + 1]):
            continue
        hits = guard.contacts(q[i], OBSTACLE_TOUCH_M) or guard.contacts(q[max(i - 1, 0)], 1.0)
        link, box = (hits[0].link_a, hits[0].link_b) if hits else ("arm", "obstacle")
        sentence = (
            f"sample {i} (t = {times[i]:.3f} s): link {link} touches {box.replace('_', ' ')} "
            "of the policy's task on its way there"
        )
        return [Finding(i, float(times[i]), "collision", f"{link}/{box}", sentence)]
    return []


def check_trajectory(
    robot: RobotArm,
    times: np.ndarray,
    q: np.ndarray,
    *,
    margin: float = COLLISION_MARGIN_M,
    extra: list[Finding] | None = None,
    obstacles: tuple[Obstacle, ...] = (),
) -> list[Finding]:
    """Every safety finding of ``q`` (N, nq) at ``times`` (N,), sorted by time.

    Args:
        robot: the arm the trajectory is for.
        times: sample times (s), strictly rising.
        q: joint angles (rad), one row per sample, in ``robot.joint_names`` order.
        margin: the self-collision margin (m).
        extra: findings made earlier (targets out of reach while retargeting).
        obstacles: boxes the trajectory must not touch, along it (a policy's task's).
    """
    findings = [*(extra or []), *limit_findings(robot, times, q)]
    findings += collision_findings(robot, times, q, margin)
    findings += obstacle_findings(robot, times, q, tuple(obstacles))
    return sorted(findings, key=lambda f: (f.sample, f.what))


TIMING = ("velocity", "acceleration")
"""The kinds of finding a slower timing of the same path mends (a pose or a collision it cannot)."""
RETIME_HINT = "pass --retime to time its path within the limits (TOPP-RA)"
"""What a refusal of a motion kept at its own times (a recording's capture times) suggests."""


def timing_findings(findings: list[Finding]) -> list[Finding]:
    """The findings a slower timing of the same path mends (:data:`TIMING`)."""
    return [f for f in findings if f.what in TIMING]


def refuse(findings: list[Finding], source: str, robot: RobotArm, *, own_times: bool) -> None:
    """Raise a :class:`SafetyError` naming the first finding, or return when there is none.

    The error carries the refusal twice: for the command line, with its flags, and in plain
    words for a page (``in_words``); the findings are the same.

    Args:
        own_times: the samples are at the source's own times (a recording's capture times),
            not timed within the limits: where a velocity or acceleration is over its limit,
            the sentence then suggests timing it (:data:`RETIME_HINT`); timing cannot mend a
            pose.
    """
    if not findings:
        return
    more = len(findings) - 1
    rest = f" (and {more} more finding{'s' if more > 1 else ''})" if more else ""
    problem = f"Refused: {source} for the {robot.spec.title}: {findings[0].sentence}{rest}"
    retimes = own_times and bool(timing_findings(findings))
    fix = RETIME_HINT if retimes else "export a slower or other motion or for another robot"
    in_words = (
        "at its own times it moves faster than the robot may; exported at the person's pace, "
        "slowed only where the robot needs it, it keeps to the limits"
        if retimes
        else f"the {robot.spec.title} cannot make this motion as it is: export another motion "
        "or for another robot"
    )
    anyway = "write it anyway with every finding stated in the file"
    raise SafetyError(
        f"{problem}; {fix}, or pass --unchecked to {anyway}.",
        [f.sentence for f in findings],
        found=tuple(findings),
        in_words=f"{problem}; {in_words}, or {anyway}.",
    )
