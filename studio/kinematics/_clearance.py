"""Clearance: the self-collision guard of a pose stream, and boxes in the robot's workspace.

Self-collision: only the link pairs that may have come close are measured.

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

Obstacles (:class:`Obstacle`, boxes in the robot's base frame, checked in :mod:`._checks`):
:class:`ObstacleGuard` checks the
robot's collision geometry against them at a pose and along a straight joint-space move, by the
same motion bounds (conservative advancement).
"""

from __future__ import annotations

import math

import coal
import numpy as np
import pinocchio as pin

from ._checks import Obstacle
from ._robots import TABLE, Collision, RobotArm, _link_of, shape_points


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


# --------------------------------------------------------------------------------- obstacles

OBSTACLE_TOUCH_M = 1e-4
"""Closer than this (m) to a box counts as touching it: the conservative advancement along a
move (:meth:`ObstacleGuard.move_collides`) stops there instead of creeping closer."""


def obstacle_bounds(arm: RobotArm) -> np.ndarray:
    """Per collision geometry and joint, how far (m per rad) turning the joint can move any
    point of the geometry: shape (geometries, nq), zero for joints after its link (or for the
    base, which no joint moves)."""
    model, geom = arm.model, arm.collision_model
    link_length = np.array([np.linalg.norm(p.translation) for p in model.jointPlacements])
    bounds = np.zeros((len(geom.geometryObjects), arm.nq))
    for k, obj in enumerate(geom.geometryObjects):
        b = obj.parentJoint
        radius = _bounding_radius(obj)
        for i in range(1, b + 1):
            bounds[k, i - 1] = link_length[i + 1 : b + 1].sum() + radius
    return bounds


class ObstacleGuard:
    """The robot's collision geometry against boxes in its base frame, at a pose and along a
    straight joint-space move.

    The boxes are coal boxes fixed in the base frame, checked against every link geometry a
    joint moves (the base stands where it stands) by coal's distance, as the self-collision
    check is. Along a move, conservative advancement (Mirtich 1996): at each point the nearest
    distance ``d`` of a link to a box bounds how far the move may go before they can touch,
    since turning joint i by ``dq`` moves a point of a link beyond it by at most
    ``|dq| * r_i`` (:func:`obstacle_bounds`); so the check is exact (no move through a box is
    missed however thin the box) and costs one distance query where the arm is far from every
    box. Not thread-safe (one scratch data).

    Args:
        arm: a robot loaded with its geometry (``load_robot(name)``).
        obstacles: the boxes.
        table_margin: also keep every link a joint after the first moves at least this far
            (m) above the table the robot stands on (the plane of its base, as
            :meth:`RobotArm.table_contacts` measures it); None: the table is not checked.
    """

    def __init__(
        self,
        arm: RobotArm,
        obstacles: tuple[Obstacle, ...] | list[Obstacle],
        table_margin: float | None = None,
    ) -> None:
        self.arm = arm
        self.obstacles = tuple(obstacles)
        self.table_margin = table_margin
        self.queries = 0
        """How many poses were measured so far (for benchmarks and tests)."""
        source = arm.collision_model
        geom = pin.GeometryModel()
        moving = []
        for obj in source.geometryObjects:
            if obj.parentJoint >= 1:
                moving.append(geom.addGeometryObject(pin.GeometryObject(obj)))
        boxes = []
        for i, box in enumerate(self.obstacles):
            placement = pin.SE3(np.eye(3), np.asarray(box.centre, dtype=float))
            shape = coal.Box(*box.size)
            boxes.append(
                geom.addGeometryObject(pin.GeometryObject(f"obstacle_{i + 1}", 0, placement, shape))
            )
        for b in boxes:
            for m in moving:
                geom.addCollisionPair(pin.CollisionPair(m, b))
        self._geom = geom
        self._gdata = pin.GeometryData(geom)
        self._data = arm.model.createData()
        kept = [k for k, obj in enumerate(source.geometryObjects) if obj.parentJoint >= 1]
        all_bounds = obstacle_bounds(arm)
        # per pair, the bound of its moving geometry
        self._bounds = np.array(
            [
                all_bounds[kept[geom.collisionPairs[k].first]]
                for k in range(len(geom.collisionPairs))
            ]
        ).reshape(len(geom.collisionPairs), arm.nq)
        # the table: each link a joint after the first moves, its lowest point's height above
        # the base's plane less the margin, as one more "pair" with the same motion bounds
        self._table = arm._table_points if table_margin is not None else []
        if self._table:
            rows = all_bounds[[k for k, *_ in self._table]].copy()
            rows[:, 0] = 0.0  # the first joint turns about the vertical: no height changes
            self._bounds = np.vstack([self._bounds, rows])
            self._source = pin.GeometryData(source)

    @property
    def _pairs(self) -> int:
        """How many distances :meth:`distances` gives: the (link, box) pairs, then the table's."""
        return len(self._geom.collisionPairs) + len(self._table)

    def distances(self, q: np.ndarray) -> np.ndarray:
        """Each (link, box) pair's distance at ``q`` (m, negative inside), then, with a
        ``table_margin``, each moving link's height above the table less that margin; shape
        (pairs,)."""
        if not self._pairs:
            return np.zeros(0)
        self.queries += 1
        found = []
        if len(self._geom.collisionPairs):
            pin.computeDistances(self.arm.model, self._data, self._geom, self._gdata, q)
            found = [r.min_distance for r in self._gdata.distanceResults]
        if self._table:
            source = self.arm.collision_model
            pin.updateGeometryPlacements(self.arm.model, self._data, source, self._source, q)
            for k, points, _, _ in self._table:
                placement = self._source.oMg[k]
                lowest = float((points @ placement.rotation[2]).min() + placement.translation[2])
                found.append(lowest - self.table_margin)
        return np.array(found, dtype=float)

    def contacts(self, q: object, margin: float = 0.0) -> list[Collision]:
        """The links closer than ``margin`` to a box at ``q``: ``Collision(link, "obstacle_<i>",
        distance)``, closest first."""
        arr = self.arm.check_q(q)
        found = []
        boxes = len(self._geom.collisionPairs)
        for k, d in enumerate(self.distances(arr)):
            if k >= boxes and d < margin:  # the table (its margin already taken off)
                name = self.arm.collision_model.geometryObjects[self._table[k - boxes][0]].name
                found.append(Collision(_link_of(name), TABLE, float(d)))
            elif d < margin:
                pair = self._geom.collisionPairs[k]
                found.append(
                    Collision(
                        _link_of(self._geom.geometryObjects[pair.first].name),
                        self._geom.geometryObjects[pair.second].name,
                        float(d),
                    )
                )
        return sorted(found, key=lambda c: c.distance)

    def move_collides(
        self,
        q_from: np.ndarray,
        q_to: np.ndarray,
        gap_from: np.ndarray | None = None,
        gap_to: np.ndarray | None = None,
    ) -> bool:
        """Whether the straight joint-space move from ``q_from`` to ``q_to`` (both ``nq``
        angles, rad) brings a link within :data:`OBSTACLE_TOUCH_M` of a box anywhere along it, its
        ends included.

        Advances from both ends: a pair measured ``g0`` apart at one end and ``g1`` at the
        other cannot touch in between while ``g0 + g1`` exceeds how far its link can move over
        the rest of the move, so a move well clear of every box costs its two ends only.

        Args:
            q_from: the start.
            q_to: the end.
            gap_from: :meth:`distances` at ``q_from`` when known (saves a query).
            gap_to: :meth:`distances` at ``q_to`` when known.
        """
        if not self._pairs:
            return False
        q0 = np.asarray(q_from, dtype=float)
        dq = np.asarray(q_to, dtype=float) - q0
        speed = self._bounds @ np.abs(dq)  # per pair, how far its link can move per unit t
        t0, t1 = 0.0, 1.0
        g0 = self.distances(q0) if gap_from is None else np.asarray(gap_from)
        g1 = self.distances(q0 + dq) if gap_to is None else np.asarray(gap_to)
        while True:
            if min(g0.min(), g1.min()) < OBSTACLE_TOUCH_M:
                return True
            if np.all(g0 + g1 > speed * (t1 - t0)):
                return False  # every pair is certified clear from one end or the other
            moving = speed > 0
            t0 += float(np.min(g0[moving] / speed[moving]))
            t1 -= float(np.min(g1[moving] / speed[moving]))
            if t0 >= t1:
                return False
            g0 = self.distances(q0 + t0 * dq)
            g1 = self.distances(q0 + t1 * dq)

    def path_collides(self, q_path: np.ndarray) -> bool:
        """Whether a joint path ``(N, nq)``, its samples joined by straight moves, touches a box."""
        path = np.atleast_2d(np.asarray(q_path, dtype=float))
        if len(path) == 1:
            return bool(self._pairs) and self.distances(path[0]).min() < OBSTACLE_TOUCH_M
        return any(self.move_collides(a, b) for a, b in zip(path[:-1], path[1:], strict=True))


def sphere_cover(arm: RobotArm) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Spheres that together hold every moving link's collision geometry, for compiled checks
    that cannot call coal (the continuous learning task's).

    Each geometry's points (a convex hull's vertices, else its bounding box's corners) are
    wrapped in a capsule along their principal axis (its radius the farthest point from the
    axis), and the capsule in spheres ``h <= r`` apart of radius ``sqrt(r**2 + (h / 2)**2)``:
    a superset of the geometry, so a pose the spheres find clear of a box is clear of it.

    Returns:
        ``(joint (n,) int: the Pinocchio joint each sphere moves with (1 = the first),
        centre (n, 3): in that joint's frame (m), radius (n,) (m))``.
    """
    joints, centres, radii = [], [], []
    for obj in arm.collision_model.geometryObjects:
        if obj.parentJoint < 1:
            continue
        points = shape_points(obj.geometry)
        placement = obj.placement
        points = points @ np.asarray(placement.rotation).T + np.asarray(placement.translation)
        middle = points.mean(axis=0)
        _, _, axes = np.linalg.svd(points - middle, full_matrices=False)
        axis = axes[0]
        along = (points - middle) @ axis
        low, high = float(along.min()), float(along.max())
        off = points - middle - np.outer(along, axis)
        radius = max(float(np.linalg.norm(off, axis=1).max()), 1e-3)
        count = max(2, math.ceil((high - low) / radius) + 1)
        spacing = (high - low) / (count - 1)
        for u in np.linspace(low, high, count):
            joints.append(obj.parentJoint)
            centres.append(middle + u * axis)
            radii.append(math.hypot(radius, 0.5 * spacing))
    return np.array(joints, dtype=np.int64), np.array(centres).reshape(-1, 3), np.array(radii)
