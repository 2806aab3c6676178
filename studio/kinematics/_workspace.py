"""The operator's reach mapped into a robot's workspace, and the soft limits around it.

A person reaches within a ball around their shoulder whose radius is their arm's length. A robot
on a table reaches within a ball around its shoulder (:attr:`RobotArm.shoulder`,
:attr:`RobotArm.reach`) cut by the table, less what its wrist cannot reach at every orientation
(:attr:`RobotSpec.usable_reach`). :class:`Workspace` maps the one onto the other, direction by
direction: the operator's hand at a share ``rho`` of their arm's length from their shoulder, in
direction ``d``, goes to the workspace's centre plus ``rho`` times the distance from the centre
to the workspace's edge along ``d``. So an outstretched arm puts the tool at the edge of the
robot's comfortable reach whichever way it points, a bent arm nearer the centre, and the hand's
path keeps its directions (its lengths scale by the edge's distance, which changes smoothly with
the direction except where the ball meets the table).

The retargeting (:class:`studio.kinematics.Retargeter`) places every hand target through it,
live, cut, played back and exported alike; the soft limits below then only guard what the map
already keeps inside: the table (:func:`soft_floor`), the column around the first axis an arm
with a sideways shoulder offset cannot enter (:func:`out_of_hollow`) and the ball's edge
(:func:`soft_ceiling`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._robots import RobotArm


@dataclass(frozen=True)
class Workspace:
    """Where a robot's tool goes comfortably: a ball around its shoulder, above a floor.

    Attributes:
        shoulder: the ball's centre, the robot's shoulder (m, base frame).
        radius: the ball's radius (m): the reach the operator's outstretched arm maps onto.
        floor: the lowest height a target is placed at (m, base frame).
        centre: where the operator's shoulder is placed (m, base frame): on the first axis,
            halfway up between the floor and the ball's top, so a hand raised and a hand lowered
            have as much room.
    """

    shoulder: np.ndarray
    radius: float
    floor: float
    centre: np.ndarray

    @classmethod
    def of(
        cls, robot: RobotArm, radius: float, floor: float, ahead: np.ndarray | None = None
    ) -> Workspace:
        """The workspace of ``robot`` for a reach of ``radius`` (m) above ``floor`` (m), its
        centre moved level by ``ahead`` (m, (2,); an arm whose first axis is a hollow it cannot
        reach: out of it, towards the operator)."""
        shoulder = np.asarray(robot.shoulder, dtype=float).copy()
        floor = min(floor, float(shoulder[2]))
        centre = shoulder.copy()
        centre[2] = 0.5 * (floor + shoulder[2] + radius)
        if ahead is not None:
            centre[:2] += ahead
        for array in (shoulder, centre):
            array.setflags(write=False)
        return cls(shoulder, float(radius), float(floor), centre)

    def edge(self, direction: np.ndarray) -> float:
        """The distance (m) from :attr:`centre` to the workspace's edge along the unit
        ``direction``: the nearer of the ball's surface and the floor."""
        lift = self.centre - self.shoulder
        along = float(direction @ lift)
        inside = along * along - float(lift @ lift) + self.radius * self.radius
        to_ball = -along + math.sqrt(max(inside, 0.0))
        if direction[2] < 0.0:
            return min(to_ball, (float(self.centre[2]) - self.floor) / -float(direction[2]))
        return to_ball

    def into(self, reach: np.ndarray) -> np.ndarray:
        """The point (m, base frame) for an offset from the operator's shoulder given as a
        share of their arm's length (``(3,)``, length at most 1 for a hand)."""
        share = float(np.linalg.norm(reach))
        if share == 0.0:
            return self.centre.copy()
        direction = reach / share
        return self.centre + share * self.edge(direction) * direction

    def out_of(self, point: np.ndarray) -> np.ndarray:
        """The offset, as a share of the operator's arm length, that :meth:`into` maps to
        ``point`` (its inverse)."""
        offset = np.asarray(point, dtype=float) - self.centre
        distance = float(np.linalg.norm(offset))
        if distance == 0.0:
            return np.zeros(3)
        direction = offset / distance
        return direction * (distance / max(self.edge(direction), 1e-9))

    def share(self, point: np.ndarray) -> float:
        """How far out ``point`` is, as a share of the way from the centre to the edge in its
        direction (1: on the edge; beyond 1: outside the workspace)."""
        return float(np.linalg.norm(self.out_of(point)))


def soft_floor(z: float, floor: float, width: float) -> float:
    """``z`` kept above ``floor`` smoothly: a softplus of width ``width`` (equal to ``z`` well above)."""
    x = (z - floor) / width
    return floor + width * (x + math.log1p(math.exp(-x)) if x > 0 else math.log1p(math.exp(x)))


def soft_ceiling(r: float, ceiling: float, width: float) -> float:
    """``r`` kept below ``ceiling`` smoothly: unchanged up to ``ceiling - width``, then bent
    (continuous slope) towards ``ceiling``, which it never reaches."""
    if width <= 0.0:
        return min(r, ceiling)
    knee = ceiling - width
    return r if r <= knee else knee + width * math.tanh((r - knee) / width)


def unfloored(z: float, floor: float, width: float) -> float:
    """The ``z`` that :func:`soft_floor` keeps at ``z`` (a height at the floor or below: as far
    below it as the softplus allows, ``width`` times the float's smallest log)."""
    y = max((z - floor) / width, 1e-300)
    return floor + width * (y + math.log(-math.expm1(-y)) if y > 30.0 else math.log(math.expm1(y)))


def unbent(r: float, ceiling: float, width: float) -> float:
    """The ``r`` that :func:`soft_ceiling` bends to ``r`` (one at the ceiling or beyond: far out)."""
    knee = ceiling - width
    if width <= 0.0:
        return r
    return r if r <= knee else knee + width * math.atanh(min((r - knee) / width, 1.0 - 1e-12))


def out_of_hollow(
    across: np.ndarray, hollow: float, width: float, forward: np.ndarray
) -> np.ndarray:
    """A target's level offset from a robot's first axis (m, (2,)) moved out of its hollow.

    An offset nearer the axis than ``hollow + width`` is moved to the radius
    ``-soft_ceiling(-r, -hollow, width)`` (beyond ``hollow``, smoothly: a further one stays
    exactly where it is), along ``across + (hollow + width / 2) * forward``, not straight out
    from the axis. Straight out, the direction of a hand held just above or below the shoulder
    turns with every millimetre of its noise, and the robot's base would turn with it. Any
    continuous way out of a disc tears somewhere (the disc's edge cannot shrink onto a point
    around the hollow); this one tears at a single point behind the axis (``forward`` the way
    the arm faces, towards the operator), where a hand rarely stays.
    """
    radius = float(np.linalg.norm(across))
    kept = -soft_ceiling(-radius, -hollow, width)
    if kept <= radius:
        return across
    way = across + (hollow + width / 2) * forward
    norm = float(np.linalg.norm(way))
    way = forward if norm == 0.0 else way / norm
    along = float(across @ way)
    return across + (math.sqrt(along * along + kept * kept - radius * radius) - along) * way


def into_hollow(moved: np.ndarray, hollow: float, width: float, forward: np.ndarray) -> np.ndarray:
    """An offset that :func:`out_of_hollow` moves to ``moved``, found by fixed-point steps (one
    within 0.1 mm, or the nearest found; ``moved`` itself from beyond the hollow's edge)."""
    if float(np.linalg.norm(moved)) >= hollow + width:
        return moved
    best, miss = moved, math.inf
    guess = moved.copy()
    for _ in range(50):
        error = out_of_hollow(guess, hollow, width, forward) - moved
        size = float(np.linalg.norm(error))
        if size < miss:
            best, miss = guess.copy(), size
        if size < 1e-4:
            break
        guess = guess - error
    return best
