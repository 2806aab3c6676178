"""ShapeTape: configuration, reconstruction of its shape from bend/twist, and the inverse.

Reconstruction (Measurand's tapeAPI): start from the base frame whose columns are u (along the
tape), n and b (across it). For each region i, rotate the frame about u by ``twist[i]``, then
about the new b by ``bend[i]``, then advance the position by u * (length / regions). In the
frame's own coordinates one region is the rotation ``Rx(twist) @ Rz(bend)`` followed by a step of
one region length along the new x, so the tape's vertices are a chain of equal chords and a
constant bend with zero twist puts them on a circle (see the tests).

This module also holds the tape's *forward model* of an operator, :func:`tape_from_arm`: where the
tape lies when strapped from the back, over the shoulder, along the arm to the wrist and on over
the hand, for a given arm pose. The simulator uses it to make frames and the fitter's tests use it
as their oracle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

import numpy as np
from numba import njit

from ..._kernels import frozen
from .._checks import KinematicsError, check_side, positive_number, real_array, whole_number

if TYPE_CHECKING:
    from ._human import HumanArm

DEFAULT_LENGTH = 1.84
"""The paper's tape length (m)."""
DEFAULT_REGIONS = 16
"""The paper's number of bend/twist pairs."""
DEFAULT_SHOULDER_REGION = 9
"""Default index of the vertex at the shoulder: the first 9 regions (1.035 m) lie over the back."""
DEFAULT_WRIST_REGION = 14
"""Default end of the arm part: regions 9..13 cover the 0.563 m default arm (region 13 holds the
wrist), and the last two regions lie over the hand."""
DEFAULT_SHOULDER_ARC_REGIONS = 2
"""Regions of the fixed arc that takes the tape from the back over the top of the shoulder."""

FRAME_ATOL = 1e-6
"""How far from orthonormal (and from a twist-then-bend) tape frames may be through rounding."""

_STRAIGHT = 1e-12  # sin(bend) below this is a straight region; its twist is set to zero


def _validate_angles(bend: object, twist: object, regions: int) -> tuple[np.ndarray, np.ndarray]:
    bend_a = real_array(bend, "bend", "pass one angle in radians per region")
    twist_a = real_array(twist, "twist", "pass one angle in radians per region")
    if bend_a.shape != twist_a.shape or bend_a.shape[-1:] != (regions,):
        raise KinematicsError(
            f"bend and twist must both have shape (..., {regions}) for a {regions}-region tape; "
            f"got {bend_a.shape} and {twist_a.shape}."
        )
    if not (np.all(np.isfinite(bend_a)) and np.all(np.isfinite(twist_a))):
        raise KinematicsError("bend or twist contains NaN or infinite angles; pass finite radians.")
    return bend_a, twist_a


def _check_config(config: object) -> None:
    if not isinstance(config, TapeConfig):
        raise KinematicsError(
            f"config must be a TapeConfig, got {type(config).__name__}; pass TapeConfig(...)."
        )


def _back_angles(regions_before_shoulder: int) -> tuple[np.ndarray, np.ndarray]:
    """Bend/twist of the fixed back path: straight up the back, then an arc over the shoulder."""
    bend = np.zeros(regions_before_shoulder)
    arc = min(DEFAULT_SHOULDER_ARC_REGIONS, regions_before_shoulder)
    if arc:
        bend[regions_before_shoulder - arc :] = (math.pi / 2) / arc
    return bend, np.zeros(regions_before_shoulder)


@dataclass(frozen=True, eq=False)
class TapeConfig:
    """How the tape is made and where it lies on the operator.

    Vertex ``k`` of the tape is the point at arc length ``k * region_length`` from its start;
    region ``i`` runs from vertex ``i`` to vertex ``i + 1``.

    Attributes:
        length: tape length (m); the paper's tape is 1.84 m.
        regions: number of equal bend/twist regions; the paper's tape has 16.
        base: where the tape starts (4x4, columns u, n, b and the start point) in the arm base
            frame (shoulder at the origin, x forward, y left, z up). Default (None): the start
            of the fixed back path of :func:`tape_from_arm`, chosen so that vertex
            ``shoulder_region`` lies on the shoulder: the tape runs straight up the back, arcs
            over the top of the shoulder (outwards, towards ``side``) and reaches the shoulder
            heading outwards.
        shoulder_region: the vertex at the shoulder; regions before it lie over the back.
        wrist_region: regions ``shoulder_region .. wrist_region - 1`` cover the arm from the
            shoulder to the wrist (the wrist lies within region ``wrist_region - 1``); any regions
            after lie over the hand.
        side: the arm wearing the tape, used for the default ``base`` only.
    """

    length: float = DEFAULT_LENGTH
    regions: int = DEFAULT_REGIONS
    base: np.ndarray | None = field(default=None, compare=False)  # compared in __eq__
    shoulder_region: int = DEFAULT_SHOULDER_REGION
    wrist_region: int = DEFAULT_WRIST_REGION
    side: Literal["right", "left"] = "right"

    def __post_init__(self) -> None:
        object.__setattr__(self, "length", positive_number(self.length, "The tape length (m)"))
        if (
            isinstance(self.regions, bool)
            or not isinstance(self.regions, int | np.integer)
            or self.regions < 1
        ):
            raise KinematicsError(f"Tape regions must be a positive integer; got {self.regions!r}.")
        check_side(self.side, "The tape's side")
        s = whole_number(self.shoulder_region, "The tape's shoulder_region", 0)
        w = whole_number(self.wrist_region, "The tape's wrist_region", 1)
        object.__setattr__(self, "regions", int(self.regions))
        object.__setattr__(self, "shoulder_region", s)
        object.__setattr__(self, "wrist_region", w)
        if not (0 <= s < w <= self.regions):
            raise KinematicsError(
                f"The tape's arm regions (shoulder_region={s}, wrist_region={w}) must satisfy "
                f"0 <= shoulder_region < wrist_region <= regions ({self.regions}); "
                "lower them or use a longer tape."
            )
        if self.base is None:
            object.__setattr__(self, "base", self._default_base())
        else:
            base = np.array(real_array(self.base, "The tape base", "pass a 4x4 rigid transform"))
            ok = base.shape == (4, 4) and np.all(np.isfinite(base))
            if ok:
                R = base[:3, :3]
                ok = np.allclose(R.T @ R, np.eye(3), atol=1e-6) and np.linalg.det(R) > 0
                ok = ok and np.allclose(base[3], [0.0, 0.0, 0.0, 1.0])
            if not ok:
                raise KinematicsError(
                    "The tape base must be a 4x4 rigid transform (rotation columns u, n, b and the "
                    "start point); pass a valid homogeneous matrix."
                )
            object.__setattr__(self, "base", base)
        self.base.setflags(write=False)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, TapeConfig):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def _key(self) -> tuple:
        return (
            self.length,
            self.regions,
            self.shoulder_region,
            self.wrist_region,
            self.side,
            self.base.tobytes(),
        )

    @property
    def region_length(self) -> float:
        """Length of one region (m)."""
        return self.length / self.regions

    def _default_base(self) -> np.ndarray:
        # Frame at the start of the back: u up the back, n towards the arm side (the arc over
        # the shoulder bends u towards n), b = u x n.
        n = np.array([0.0, -1.0 if self.side == "right" else 1.0, 0.0])
        u = np.array([0.0, 0.0, 1.0])
        start = np.eye(4)
        start[:3, :3] = np.column_stack([u, n, np.cross(u, n)])
        bend, twist = _back_angles(self.shoulder_region)
        if self.shoulder_region == 0:
            return start
        positions, _ = _chain(bend, twist, start, self.region_length)
        start[:3, 3] = -positions[-1]  # the shoulder vertex lands on the origin
        return start


@dataclass(frozen=True)
class TapeShape:
    """The reconstructed tape.

    Attributes:
        positions: vertex positions, shape ``(..., regions + 1, 3)`` (m, arm base frame).
        frames: vertex frames, shape ``(..., regions + 1, 3, 3)``, columns u, n, b; ``frames[k]``
            is the frame after region ``k - 1``'s rotation (``frames[0]`` is the base), so
            region ``k`` runs along ``frames[k + 1][:, 0]``.
    """

    positions: np.ndarray
    frames: np.ndarray


@njit(nogil=True, cache=True)
def _chain_kernel(
    bend: np.ndarray,
    twist: np.ndarray,
    base: np.ndarray,
    step: float,
    positions: np.ndarray,
    frames: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """Fill ``positions (N, R+1, 3)`` and ``frames (N, R+1, 3, 3)`` from ``bend/twist (N, R)``."""
    N, R = bend.shape
    for k in range(N):
        u0, u1, u2 = base[0, 0], base[1, 0], base[2, 0]
        n0, n1, n2 = base[0, 1], base[1, 1], base[2, 1]
        b0, b1, b2 = base[0, 2], base[1, 2], base[2, 2]
        p0, p1, p2 = base[0, 3], base[1, 3], base[2, 3]
        for r in range(3):
            frames[k, 0, r, 0] = base[r, 0]
            frames[k, 0, r, 1] = base[r, 1]
            frames[k, 0, r, 2] = base[r, 2]
        positions[k, 0, 0], positions[k, 0, 1], positions[k, 0, 2] = p0, p1, p2
        for i in range(R):
            cb, sb = np.cos(bend[k, i]), np.sin(bend[k, i])
            ct, st = np.cos(twist[k, i]), np.sin(twist[k, i])
            # F @ Rx(twist) @ Rz(bend): twist about u, then bend about the new b.
            m0, m1, m2 = ct * n0 + st * b0, ct * n1 + st * b1, ct * n2 + st * b2
            b0, b1, b2 = ct * b0 - st * n0, ct * b1 - st * n1, ct * b2 - st * n2
            n0, n1, n2, u0, u1, u2 = (
                cb * m0 - sb * u0,
                cb * m1 - sb * u1,
                cb * m2 - sb * u2,
                cb * u0 + sb * m0,
                cb * u1 + sb * m1,
                cb * u2 + sb * m2,
            )
            p0, p1, p2 = p0 + step * u0, p1 + step * u1, p2 + step * u2
            j = i + 1
            positions[k, j, 0], positions[k, j, 1], positions[k, j, 2] = p0, p1, p2
            frames[k, j, 0, 0], frames[k, j, 1, 0], frames[k, j, 2, 0] = u0, u1, u2
            frames[k, j, 0, 1], frames[k, j, 1, 1], frames[k, j, 2, 1] = n0, n1, n2
            frames[k, j, 0, 2], frames[k, j, 1, 2], frames[k, j, 2, 2] = b0, b1, b2


def _chain(
    bend: np.ndarray, twist: np.ndarray, base: np.ndarray, step: float
) -> tuple[np.ndarray, np.ndarray]:
    """Positions and frames from angles, over any leading dims (one compiled pass per frame)."""
    lead = bend.shape[:-1]
    regions = bend.shape[-1]
    count = math.prod(lead)  # explicit: reshape(-1, 0) is ambiguous for a tape with no regions
    flat_b = frozen(np.reshape(bend, (count, regions)))
    flat_t = frozen(np.reshape(twist, (count, regions)))
    positions = np.empty((flat_b.shape[0], regions + 1, 3))
    frames = np.empty((flat_b.shape[0], regions + 1, 3, 3))
    _chain_kernel(flat_b, flat_t, frozen(base), float(step), positions, frames)
    return positions.reshape(*lead, regions + 1, 3), frames.reshape(*lead, regions + 1, 3, 3)


def reconstruct(bend: object, twist: object, config: TapeConfig) -> TapeShape:
    """The tape's vertices and frames from its bend and twist angles.

    Args:
        bend: bend per region (rad), shape ``(..., regions)``.
        twist: twist per region (rad), shape ``(..., regions)``.
        config: the tape.

    Returns:
        A :class:`TapeShape` in the arm base frame.

    Raises:
        KinematicsError: wrong shapes or non-finite angles.
    """
    _check_config(config)
    bend_a, twist_a = _validate_angles(bend, twist, config.regions)
    positions, frames = _chain(bend_a, twist_a, config.base, config.region_length)
    return TapeShape(positions=positions, frames=frames)


def tape_angles(frames: object) -> tuple[np.ndarray, np.ndarray]:
    """Bend and twist from the tape's frames: the exact inverse of :func:`reconstruct`.

    Region i's rotation in its own frame is ``R = F_i^T F_{i+1} = Rx(twist) Rz(bend)``, whose
    entries give ``bend = atan2(-R[0, 1], R[0, 0])`` and ``twist = atan2(-R[1, 2], R[2, 2])``,
    so any angles in (-pi, pi] come back exactly (to rounding).

    Args:
        frames: shape ``(..., regions + 1, 3, 3)``, e.g. ``reconstruct(...).frames``.

    Returns:
        ``(bend, twist)``, each of shape ``(..., regions)``.

    Raises:
        KinematicsError: wrong shape or non-finite values, frames that are not rotations, or
            consecutive frames that no twist-then-bend turns into each other (not a tape's).
    """
    F = real_array(frames, "frames", "pass reconstruct(...).frames, shape (..., regions + 1, 3, 3)")
    if F.ndim < 3 or F.shape[-2:] != (3, 3) or F.shape[-3] < 2:
        raise KinematicsError(
            f"frames must have shape (..., regions + 1, 3, 3); got {F.shape}; "
            "pass reconstruct(...).frames."
        )
    if not np.all(np.isfinite(F)):
        raise KinematicsError("frames contain NaN or infinite values; pass finite rotations.")
    gram = np.einsum("...ji,...jk->...ik", F, F)
    if np.abs(gram - np.eye(3)).max() > FRAME_ATOL or np.any(np.linalg.det(F) <= 0):
        raise KinematicsError(
            "frames are not all rotation matrices (orthonormal columns u, n, b); "
            "pass reconstruct(...).frames."
        )
    A, B = F[..., :-1, :, :], F[..., 1:, :, :]
    # R[r, c] = A[:, r] . B[:, c]
    r00 = np.einsum("...k,...k->...", A[..., :, 0], B[..., :, 0])
    r01 = np.einsum("...k,...k->...", A[..., :, 0], B[..., :, 1])
    r02 = np.einsum("...k,...k->...", A[..., :, 0], B[..., :, 2])
    r12 = np.einsum("...k,...k->...", A[..., :, 1], B[..., :, 2])
    r22 = np.einsum("...k,...k->...", A[..., :, 2], B[..., :, 2])
    # Rx(twist) @ Rz(bend) never moves b out of the n-b plane: R[0, 2] is zero for a tape.
    if r02.size and np.abs(r02).max() > FRAME_ATOL:
        raise KinematicsError(
            "consecutive frames differ by a turn that no twist-then-bend makes, so they are not a "
            "tape's; pass reconstruct(...).frames."
        )
    return np.arctan2(-r01, r00), np.arctan2(-r12, r22)


def _walk_chords(
    path: np.ndarray, directions: np.ndarray, lengths: np.ndarray, step: float, count: int
) -> np.ndarray:
    """Vertices of a chain of equal chords laid along a polyline, from its start.

    Each new vertex is the first point further along the path at distance ``step`` from the
    previous vertex (the tape cuts the path's corners with straight chords). The last segment
    extends without end.

    Args:
        path: segment start points, shape ``(N, S, 3)``.
        directions: unit segment directions, ``(N, S, 3)``.
        lengths: segment lengths, ``(N, S)`` (the last is ignored: infinite).
        step: chord length.
        count: vertices after the start.

    Returns:
        Vertices ``(N, count + 1, 3)``.
    """
    N, S, _ = path.shape
    out = np.empty((N, count + 1, 3))
    v = path[:, 0].copy()
    seg = np.zeros(N, dtype=int)
    along = np.zeros(N)  # position of v along its segment
    rows = np.arange(N)
    lengths = lengths.copy()
    lengths[:, -1] = np.inf
    out[:, 0] = v
    for i in range(1, count + 1):
        found = np.zeros(N, dtype=bool)
        new_v = np.empty((N, 3))
        new_seg = seg.copy()
        new_along = np.empty(N)
        # On the current segment: a straight step.
        here = along + step <= lengths[rows, seg]
        new_v[here] = v[here] + step * directions[rows[here], seg[here]]
        new_along[here] = along[here] + step
        found |= here
        for k in range(1, S):
            todo = ~found & (seg < k)
            if not np.any(todo):
                continue
            w = path[todo, k] - v[todo]
            d = directions[todo, k]
            wd = np.einsum("ij,ij->i", w, d)
            disc = wd**2 - np.einsum("ij,ij->i", w, w) + step**2
            t = -wd + np.sqrt(np.maximum(disc, 0.0))
            ok = t <= lengths[todo, k]
            idx = rows[todo][ok]
            new_v[idx] = path[idx, k] + t[ok, None] * directions[idx, k]
            new_seg[idx] = k
            new_along[idx] = t[ok]
            found[idx] = True
        v, seg, along = new_v, new_seg, new_along
        out[:, i] = v
    return out


def _angles_along(
    start: np.ndarray, vertices: np.ndarray, step: float
) -> tuple[np.ndarray, np.ndarray]:
    """Bend/twist that make the tape follow ``vertices`` from the frame ``start``, least twist.

    Each region's twist is the one that puts the next direction in the frame's u-n plane, chosen
    in (-pi/2, pi/2] with a signed bend (a flat strap bends both ways without twisting); a
    straight region has zero twist.

    Args:
        start: frames at the first vertex, ``(N, 3, 3)``.
        vertices: ``(N, k + 1, 3)``.
        step: region length.

    Returns:
        ``(bend, twist)``, each ``(N, k)``.
    """
    N, count = vertices.shape[0], vertices.shape[1] - 1
    bend = np.empty((N, count))
    twist = np.empty((N, count))
    F = start.copy()
    for i in range(count):
        d = (vertices[:, i + 1] - vertices[:, i]) / step
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        c = np.einsum(
            "nki,nk->ni", F, d
        )  # d in frame coordinates: (cos k, cos t sin k, sin t sin k)
        s = np.hypot(c[:, 1], c[:, 2])
        tw = np.where(s > _STRAIGHT, np.arctan2(c[:, 2], c[:, 1]), 0.0)
        k = np.arctan2(s, c[:, 0])
        flip = tw > math.pi / 2
        flip_neg = tw <= -math.pi / 2
        tw = np.where(flip, tw - math.pi, np.where(flip_neg, tw + math.pi, tw))
        k = np.where(flip | flip_neg, -k, k)
        bend[:, i], twist[:, i] = k, tw
        ck, sk, ctw, stw = np.cos(k), np.sin(k), np.cos(tw), np.sin(tw)
        zero = np.zeros_like(k)
        R = np.stack(  # Rx(tw) @ Rz(k), row by row
            [
                np.stack([ck, -sk, zero], -1),
                np.stack([ctw * sk, ctw * ck, -stw], -1),
                np.stack([stw * sk, stw * ck, ctw], -1),
            ],
            -2,
        )
        F = F @ R
    return bend, twist


def _in_time(
    bend: np.ndarray,
    twist: np.ndarray,
    first: int,
    previous: tuple[np.ndarray, np.ndarray] | None,
) -> tuple[np.ndarray, np.ndarray]:
    """Readings ``(N, regions)`` of frames in time order, each region's chosen continuous with the
    frame before (``previous``: the readings of the frame before the first, if any).

    A region whose twist sits at +-90 degrees reads (b, 90) or (-b, -90) with the next frame's
    slightest change, and every region after it flips its bend's sign with it: the same shape,
    two readings. A real tape twists continuously. So from region ``first`` on, each region takes
    whichever of its reading and the other one (bend negated, twist turned by 180 degrees; the
    regions after it then read with their bends negated) lies nearer its reading in the frame
    before. (A region passing through straight, where the twist says little of the shape, may
    still choose the reading that flips the small bends after it: tenths of a radian, where the
    canonical readings jump by up to 190 degrees.)
    """
    bend, twist = bend.copy(), twist.copy()
    last = None if previous is None else (np.asarray(previous[0]), np.asarray(previous[1]))
    for n in range(bend.shape[0]):
        if last is not None:
            sign = 1.0  # the bends' sign from the regions chosen so far in this frame
            for r in range(first, bend.shape[1]):
                b, t = sign * bend[n, r], twist[n, r]
                other_t = t - math.pi if t > last[1][r] else t + math.pi
                here = (b - last[0][r]) ** 2 + (t - last[1][r]) ** 2
                there = (b + last[0][r]) ** 2 + (other_t - last[1][r]) ** 2
                if there < here:
                    sign, b, t = -sign, -b, other_t
                bend[n, r], twist[n, r] = b, t
        last = (bend[n], twist[n])
    return bend, twist


def tape_from_arm(
    arm: HumanArm,
    q_human: object,
    config: TapeConfig,
    rng: np.random.Generator | None = None,
    noise: float | None = None,
    *,
    in_time: bool = False,
    previous: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Bend and twist of a tape strapped on ``arm`` at pose ``q_human``: the forward model.

    The model:

    - Regions before ``shoulder_region`` follow a fixed path (the default: straight up the back,
      then an arc over the top of the shoulder), so their angles do not depend on the pose.
    - From the shoulder vertex on, the tape lies along the arm's polyline shoulder -> elbow ->
      wrist -> hand centre, continuing straight beyond the hand. Vertices are equal chords
      along that path: straight along each limb, cutting the corner at the elbow and the wrist.
      The bend at the shoulder vertex (the shoulder crossing) turns the back path's direction
      into the upper arm's, so the tape stays continuous for every pose.
    - Frames carry the least twist that follows that path (the strap bends, it does not
      twist), so forearm rotation shows up only through the hand's direction.

    With ``config.base`` not the default, the back path still starts at ``config.base``, and
    the shoulder vertex lands wherever that puts it: a badly placed tape, which the fitter
    reports as a residual.

    Args:
        arm: the operator's arm (its lengths set where the tape bends).
        q_human: arm pose(s) (rad), shape ``(..., 7)``.
        config: the tape.
        rng: random generator for ``noise`` (required when ``noise > 0``).
        noise: standard deviation of Gaussian sensor noise added to every angle (rad); None
            or 0 for none.
        in_time: the poses are consecutive frames (``q_human`` of shape ``(N, 7)``): each
            region's reading stays continuous from frame to frame, as a real tape's does, where
            a region at +-90 degrees of twist would otherwise jump between its two readings of
            the same shape (see ``_in_time``). Default: each pose on its own, its twist in
            (-90, 90] degrees.
        previous: with ``in_time``, the noiseless ``(bend, twist)`` of the frame before the
            first, to continue from (a stream made in chunks).

    Returns:
        ``(bend, twist)``, each of shape ``(..., regions)``.

    Raises:
        KinematicsError: bad ``q_human``, or noise without a generator.
    """
    from ._human import _as_q

    q = _as_q(q_human, arm.nq, "q_human")
    noise = 0.0 if noise is None else noise
    if isinstance(noise, bool) or not isinstance(noise, int | float | np.integer | np.floating):
        raise KinematicsError(f"noise must be a number of radians; got {noise!r}.")
    if not (math.isfinite(noise) and noise >= 0):
        raise KinematicsError(
            f"noise must be a standard deviation in radians, finite and >= 0; got {noise!r}."
        )
    _check_config(config)
    lead = q.shape[:-1]
    flat = q.reshape(-1, arm.nq)
    s, step = config.shoulder_region, config.region_length
    back_bend, back_twist = _back_angles(s)
    positions, frames = _chain(back_bend, back_twist, config.base, step)
    shoulder_start, shoulder_frame = positions[-1], frames[-1]

    points = arm.points(flat)  # (N, 4, 3): shoulder, elbow, wrist, hand
    path = points - points[:, :1] + shoulder_start  # the arm hangs from the tape's shoulder
    seg = np.diff(path, axis=1)
    lengths = np.linalg.norm(seg, axis=-1)
    directions = seg / lengths[..., None]
    arm_vertices = _walk_chords(path[:, :3], directions, lengths, step, config.regions - s)
    start = np.broadcast_to(shoulder_frame, (flat.shape[0], 3, 3))
    arm_bend, arm_twist = _angles_along(start, arm_vertices, step)

    bend = np.concatenate([np.broadcast_to(back_bend, (flat.shape[0], s)), arm_bend], axis=1)
    twist = np.concatenate([np.broadcast_to(back_twist, (flat.shape[0], s)), arm_twist], axis=1)
    if in_time:
        bend, twist = _in_time(bend, twist, s, previous)
    if noise:
        if not isinstance(rng, np.random.Generator):
            raise KinematicsError("tape_from_arm with noise needs rng=np.random.default_rng(seed).")
        bend = bend + rng.normal(0.0, noise, bend.shape)
        twist = twist + rng.normal(0.0, noise, twist.shape)
    return bend.reshape(*lead, config.regions), twist.reshape(*lead, config.regions)
