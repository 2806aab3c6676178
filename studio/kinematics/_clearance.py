"""The self-collision guard of a pose stream: only the link pairs that may have come close are measured.

Retargeting checks every frame's pose for self-collision before taking it. Measuring all of an
arm's link pairs with coal costs 0.4 to 8 ms a pose, more than the rest of the frame. Between two
frames the joints move little, and a small joint motion can only move two links a bounded distance
towards each other: turning joint i by dq moves any point of a link beyond it by at most
``|dq| * r_i``, where ``r_i`` bounds the point's distance from joint i's axis (the lengths of the
links in between plus the link's own bounding sphere, whatever the pose). So once a pair has been
measured ``d`` apart at ``q_ref``, it is still at least ``margin`` apart at ``q`` whenever
``d - sum_i |q_i - q_ref_i| * r_i >= margin``, a certificate, not a guess. :class:`ClearanceGuard`
measures only the pairs without that certificate, so a pose stream costs a few pairs a frame,
and every pose it lets through is as clear as a full check would have found it.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ._robots import Collision, RobotArm, _link_of


def _bounding_radius(obj: pin.GeometryObject) -> float:
    """The largest distance from the geometry's joint origin to any of its points (m)."""
    shape = obj.geometry
    shape.computeLocalAABB()
    centre = np.asarray(obj.placement.act(np.asarray(shape.aabb_center, dtype=float)))
    return float(np.linalg.norm(centre)) + float(shape.aabb_radius)


def motion_bounds(arm: RobotArm) -> np.ndarray:
    """Per collision pair and joint, how far (m per rad) the joint can move one link of the
    pair towards the other: shape (pairs, nq), zero for joints outside the chain between them."""
    model, geom = arm.model, arm.collision_model
    link_length = np.array([np.linalg.norm(p.translation) for p in model.jointPlacements])
    bounds = np.zeros((len(geom.collisionPairs), arm.nq))
    for k, pair in enumerate(geom.collisionPairs):
        first, second = geom.geometryObjects[pair.first], geom.geometryObjects[pair.second]
        if first.parentJoint > second.parentJoint:
            first, second = second, first
        a, b = first.parentJoint, second.parentJoint
        radius = _bounding_radius(second)
        for i in range(a + 1, b + 1):  # joints between the two links move one relative to the other
            bounds[k, i - 1] = link_length[i + 1 : b + 1].sum() + radius
    return bounds


class ClearanceGuard:
    """The link pairs of ``arm`` closer than ``margin``, for a stream of nearby poses.

    Gives what ``arm.self_collisions(q, margin)`` gives, measuring only the pairs whose last
    measurement does not certify them clear at ``q`` (see the module docstring). Coal warm-starts
    each pair from its last answer here; near contact that varies a distance by about a
    millimetre, which the margin (5 mm on the live path) absorbs. Not thread-safe.

    Args:
        arm: the robot.
        margin: the clearance every pose must keep between links (m).
    """

    def __init__(self, arm: RobotArm, margin: float) -> None:
        self.arm = arm
        self.margin = float(margin)
        self.measured = 0
        """How many pair distances were measured so far (for benchmarks)."""
        geom = arm.collision_model
        pairs = len(geom.collisionPairs) if arm.checks_collisions else 0
        self._bounds = motion_bounds(arm) if pairs else np.zeros((0, arm.nq))
        self._q_ref = np.zeros((pairs, arm.nq))
        self._distance = np.full(pairs, -np.inf)  # unmeasured: never certified
        self._gdata = pin.GeometryData(geom) if pairs else None
        self._last: tuple[np.ndarray, list[Collision]] | None = None  # the last pose, answered

    def collisions(self, q: np.ndarray) -> list[Collision]:
        """The pairs closer than the margin at ``q`` (checked ``q`` of ``arm.nq`` angles), and
        the links nearer the table than the margin (:meth:`RobotArm.table_contacts`, measured
        every time but for the pose asked about last: about 0.02 ms): what
        ``arm.contacts(q, margin)`` gives. A frame asks twice about the pose it takes (as a
        candidate, then as the pose shown)."""
        if self._last is not None and np.array_equal(q, self._last[0]):
            return list(self._last[1])
        found = self._measure(q)
        self._last = (np.array(q, dtype=float), found)
        return list(found)

    def _measure(self, q: np.ndarray) -> list[Collision]:
        if self._gdata is None:
            return self.arm.table_contacts(q, self.margin)
        arm, geom, gdata = self.arm, self.arm.collision_model, self._gdata
        slack = self._distance - (np.abs(q - self._q_ref) * self._bounds).sum(axis=1)
        stale = np.flatnonzero(slack < self.margin)
        if len(stale):
            pin.updateGeometryPlacements(arm.model, arm.data, geom, gdata, q)
            for k in stale:
                self._distance[k] = pin.computeDistance(geom, gdata, int(k)).min_distance
            self._q_ref[stale] = q
            self.measured += len(stale)
        found = []
        for k in stale[self._distance[stale] < self.margin]:
            pair = geom.collisionPairs[int(k)]
            found.append(
                Collision(
                    _link_of(geom.geometryObjects[pair.first].name),
                    _link_of(geom.geometryObjects[pair.second].name),
                    float(self._distance[k]),
                )
            )
        found += arm.table_contacts(q, self.margin)
        return sorted(found, key=lambda c: c.distance)
