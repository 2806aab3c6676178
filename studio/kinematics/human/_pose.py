"""Fit the 7-DOF human arm to MediaPipe Pose landmarks, one frame at a time.

MediaPipe Pose gives 33 *world* landmarks (metres, hip-centred, x toward the image's right, y
down, z away from the camera) and the same 33 as *image* landmarks (normalised x, y). The
landmarks named "left" are the person's left. The fit reads, for the chosen side:

- the torso frame from the shoulders (11, 12) and hips (23, 24): left = from the right shoulder
  and hip to the left ones, up = from the hips' middle to the shoulders' middle, forward = left x
  up. Its axes are those of :class:`HumanArm`'s arm base frame (x forward, y to the person's
  left, z up), so a limb direction in the torso frame is a limb direction of the arm model;
- the upper arm (shoulder 11/12 -> elbow 13/14) and the forearm (elbow -> wrist 15/16);
- the hand (wrist -> the middle of the index 19/20 and pinky 17/18 knuckles) and the palm's
  width axis (pinky -> index), when both hand points are visible.

**Image plane and depth.** World landmarks read bent elbows 11-24 degrees too straight, while
the image landmarks are within 3-8 degrees in the image plane. Given the image landmarks, each
point's x, y are taken from the image (in pixels, scaled to metres by the least-squares scale
between the image and world positions of the shoulders and hips, and corrected for each point's
depth through a pinhole camera of field of view ``PoseConfig.camera_fov``), and only its depth z
from the world landmarks. Depth alone also bends straight arms: where the picture shows the
arm straight, an elbow less than ``PoseConfig.depth_bend_noise`` off the shoulder-wrist line in
depth is put back on it (a larger depth bend is kept, from twice that in full), so the picture
decides the elbow angle unless depth clearly says otherwise.

**Limb lengths.** MediaPipe's depth is several times noisier than its x and y. The shoulder,
elbow and wrist are moved to the nearest chain (depth weighed ``1 / PoseConfig.depth_noise``)
whose limbs have the person's lengths: one frame alone measures them on both arms (people are
nearly symmetric) and takes the mean; a stream takes the running median. A limb's known length
then pulls its depth toward what its image-plane length implies. A stream also knows the
person's hand shape (the index, pinky and thumb in the hand's own frame, the median of recent
frames': :func:`hand_shape`) and fits those three points as one rigid hand on the wrist, turned
freely, so they pin the wrist beside its own landmark (each weighed ``PoseConfig.hand_weight``).

**Closed form.** Shoulder flexion and abduction follow from the upper arm's direction, elbow
flexion from the angle between the limbs, humeral rotation from the forearm's direction about
the upper arm, and forearm rotation and the wrist from the hand's orientation in the forearm
frame (Y-Z-X angles about the joints' own axes). Angles are clamped at the arm's limits. The
shoulder's second branch, ``(Z - pi, pi - X, Y + pi)``, gives the same arm; among those meeting
the landmarks best, the first branch wins while its abduction is within
``PoseConfig.overhead_abduction`` (far from the shoulder's gimbal lock, where it is the natural
reading), else the one nearer the reference (the previous frame, or the neutral arm). So a
stream that passed overhead returns to the first branch once the arm comes down, rather than
keeping an equal arm at other angles.

**Observability.** Seven joints, and the landmarks do not always determine them all:

- shoulder flexion, abduction and elbow flexion: whenever the arm is seen;
- humeral rotation: only with the elbow bent by at least ``PoseConfig.bent_elbow`` (a straight
  arm looks the same however it is turned about its length);
- wrist flexion and deviation: only with both hand points visible;
- forearm rotation: only with the hand seen *and* its palm axis clearly across the hand's
  length (otherwise it trades with the wrist joints about the forearm).

``observable`` reports these flags. One frame alone still reads every joint the landmarks show
at all (a slightly bent elbow still turns the forearm's direction), so exact landmarks give the
exact arm; a joint the landmarks do not show at all (a perfectly straight elbow, a hand out of
view) keeps the reference's angle (the neutral arm here; the previous frame in a
:class:`PoseStreamFitter`, which also holds weakly observable joints smoothly).

The residual is the RMS distance (m) between the measured elbow, wrist and hand points and the
fitted arm's, drawn at the person's measured limb lengths from the measured shoulder: zero for
landmarks of any arm the model can take within its limits.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from .._checks import KinematicsError, check_side, positive_number, real_array, whole_number
from ._human import HumanArm

N_LANDMARKS = 33
"""MediaPipe Pose's landmark count."""

LANDMARKS = {
    "left": {"shoulder": 11, "elbow": 13, "wrist": 15, "pinky": 17, "index": 19, "thumb": 21},
    "right": {"shoulder": 12, "elbow": 14, "wrist": 16, "pinky": 18, "index": 20, "thumb": 22},
}
"""MediaPipe Pose's indices of each side's arm points (the person's left and right)."""

HIPS = {"left": 23, "right": 24}
"""MediaPipe Pose's hip indices."""

ARM_POINTS = ("shoulder", "elbow", "wrist")
"""The points a side's arm needs to be fitted at all."""

LIMBS = (("shoulder", "elbow"), ("elbow", "wrist"))
"""The upper arm and the forearm, by their end points."""

HUMERAL_ROTATION, FOREARM_ROTATION = 2, 4
"""Indices of ``shoulder_Y`` and ``elbow_Y`` in ``q_human``."""

BRANCH_NOISE = 0.01
"""While the wrist lies this near the upper arm's line (m), the arm reads straight and the
shoulder's second branch is taken for meeting the wrist better only when it does by more than
this: a few millimetres there is noise."""

_SEEN = 1e-6  # sine below which a rotation about a limb is not seen at all (held)


@dataclass(frozen=True)
class PoseConfig:
    """Defaults of the landmark fit, documented once.

    Attributes:
        min_visibility: a shoulder, elbow or wrist seen with a lower visibility is missing (the
            arm is out of the picture); also the bar for the hips and the hand points.
        bent_elbow: humeral rotation is observable from this elbow flexion on (rad): below it
            the forearm's direction about the upper arm is lost in landmark noise.
        palm_axis: forearm rotation is observable only when the palm's width axis (pinky ->
            index) keeps at least this sine against the hand's length axis.
        min_segment: a limb shorter than this (m) between its two landmarks gives no direction.
        camera_fov: the camera's horizontal field of view (rad), to undo perspective when
            combining image and world landmarks (a laptop camera's is 55-70 degrees; an error
            here changes the result little, the body's depth is much larger than the arm's).
        depth_noise: how many times noisier the landmarks' depth is than their x and y
            (MediaPipe's published depth errors exceed 10 cm): the limbs are refined at their
            known lengths weighing depth that much less.
        refine_iterations: Gauss-Newton iterations of that refinement (0: plain geometry).
        depth_bend_noise: with image landmarks, how far (m) MediaPipe's depth alone puts an
            elbow off the shoulder-wrist line when the arm is straight (it reads flat arms bent
            by 20 degrees and more). An elbow that the image shows on that line is bent in
            depth only by what exceeds this: nothing up to it, in full from twice it on.
        hand_weight: with the person's hand shape known (a stream), how much each of the rigid
            hand's points counts against the wrist's own landmark: below 1, as filtered hand
            points, swinging on a longer radius than the wrist, trail it by more.
        overhead_abduction: the shoulder's first branch (abduction within +-90 degrees) is
            taken whenever it meets the landmarks as well as the second and its abduction is
            within this (rad); beyond it, near the gimbal lock at 90, the branch nearer the
            previous frame is kept, so an arm passing overhead does not flip.
        straight_image: the image shows the arm straight when the shoulder-wrist distance in
            the picture is at least this fraction of the two limbs' lengths in the picture;
            from there down to halfway to 1 - 2 (1 - straight_image), depth bends it less
            and less doubted.
    """

    min_visibility: float = 0.5
    bent_elbow: float = math.radians(20.0)
    palm_axis: float = 0.5
    min_segment: float = 0.01
    camera_fov: float = math.radians(60.0)
    depth_noise: float = 3.0
    refine_iterations: int = 4
    depth_bend_noise: float = 0.04
    straight_image: float = 0.95
    overhead_abduction: float = math.radians(60.0)
    hand_weight: float = 0.5

    def __post_init__(self) -> None:
        whole_number(self.refine_iterations, "PoseConfig.refine_iterations", 0)
        for name in (
            "min_visibility",
            "bent_elbow",
            "palm_axis",
            "min_segment",
            "camera_fov",
            "depth_noise",
            "depth_bend_noise",
            "straight_image",
            "overhead_abduction",
            "hand_weight",
        ):
            positive_number(getattr(self, name), f"PoseConfig.{name}")
        if self.straight_image >= 1.0:
            raise KinematicsError(
                f"PoseConfig.straight_image must be below 1; got {self.straight_image!r}."
            )


@dataclass(frozen=True)
class PoseFit:
    """The arm fitted to one frame of landmarks.

    Attributes:
        q_human: joint angles (rad, (7,)) in :class:`HumanArm`'s convention for the side,
            within its limits.
        observable: (7,) bool, which joints this frame's landmarks determine; the others hold
            the reference's angle (see the module docstring).
        residual: RMS distance (m) between the measured elbow, wrist (and hand) points and the
            fitted arm's at the person's measured limb lengths.
        points: shoulder, elbow, wrist and hand-centre points the fit read ((4, 3), m, in the
            arm base frame: shoulder at the origin, x forward, y left, z up); the hand point is
            the wrist's when the hand is not seen.
        hand_seen: both hand points were visible, so the wrist was fitted.
    """

    q_human: np.ndarray
    observable: np.ndarray
    residual: float
    points: np.ndarray = field(default_factory=lambda: np.zeros((4, 3)))
    hand_seen: bool = False


@dataclass(frozen=True)
class _Reading:
    """The limb directions of one frame in the arm base frame (unit vectors, or None)."""

    upper: np.ndarray
    fore: np.ndarray
    hand: np.ndarray | None
    palm: np.ndarray | None
    palm_sine: float  # how clearly the palm's width axis lies across the hand (0 to 1)
    points: np.ndarray  # shoulder, elbow, wrist, hand centre (arm base frame, m)
    lengths: np.ndarray  # this frame's upper-arm and forearm lengths (m, both arms' mean)
    hand_shape: np.ndarray | None = None  # this frame's hand_shape(), None with a hand unseen


@functools.lru_cache(maxsize=2)
def default_arm(side: str) -> HumanArm:
    """The default-size arm of ``side``, built once (its model is immutable; use own data)."""
    return HumanArm(side)  # type: ignore[arg-type]


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _clamp(x: float, low: float = -1.0, high: float = 1.0) -> float:
    """``x`` within ``[low, high]``, a plain float (np.clip costs microseconds per scalar)."""
    return min(max(float(x), low), high)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The cross product of two 3-vectors (np.cross's axis handling is slow for one pair)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def _landmark_array(value: object, what: str, columns: str, fix: str) -> np.ndarray:
    """``value`` as a finite (33, k) float array, k the count of ``columns``, or an error."""
    array = real_array(value, what, fix)
    widths = (len(columns.split(",")) - 1, len(columns.split(",")))
    if array.shape not in ((N_LANDMARKS, widths[0]), (N_LANDMARKS, widths[1])):
        raise KinematicsError(
            f"{what} must have shape (33, {widths[0]}) or (33, {widths[1]}) ({columns}); got "
            f"{array.shape}; {fix}."
        )
    if not np.all(np.isfinite(array)):
        raise KinematicsError(f"{what} contain NaN or infinite values; {fix} with finite values.")
    return array


def _check_landmarks(
    landmarks: object, image_landmarks: object, image_size: object
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, np.ndarray | None]:
    """(world (33, 3), image pixels (33, 2), image size, visibility (33,)), or an error."""
    world = _landmark_array(
        landmarks,
        "The pose landmarks",
        "x, y, z, visibility",
        "pass MediaPipe Pose's world landmarks of one frame",
    )
    visibility = world[:, 3] if world.shape[1] == 4 else None
    if image_landmarks is None:
        return world[:, :3], None, None, visibility
    image = _landmark_array(
        image_landmarks,
        "The image landmarks",
        "x, y, visibility",
        "pass MediaPipe Pose's normalised landmarks of the same frame",
    )
    size = real_array(image_size, "image_size", "pass (width, height) in pixels")
    if size.shape != (2,) or not np.all(size > 0) or not np.all(np.isfinite(size)):
        raise KinematicsError(
            f"image_size must be (width, height) in pixels with image landmarks; got "
            f"{image_size!r}; pass the camera picture's size."
        )
    if visibility is None and image.shape[1] == 3:
        visibility = image[:, 2]
    return world[:, :3], image[:, :2] * size, size, visibility


def _merge_image(
    world: np.ndarray, pixels: np.ndarray, size: np.ndarray, cfg: PoseConfig
) -> np.ndarray:
    """World points whose x, y come from the image (scaled to metres) and z from the world.

    A pinhole camera with the principal point at the picture's centre and the horizontal field
    of view ``PoseConfig.camera_fov`` maps a point at depth ``D + z`` (``D``: the hips' depth) to
    ``pixel - centre = f * x / (D + z)``. The scale ``D / f`` (metres per pixel at the hips) is the
    least-squares fit of the shoulders' and hips' image positions to their world x, y.
    """
    ref = [LANDMARKS["left"]["shoulder"], LANDMARKS["right"]["shoulder"], *HIPS.values()]
    focal = size[0] / 2 / math.tan(cfg.camera_fov / 2)
    centred = pixels - size / 2
    w = world[ref, :2] - world[ref, :2].mean(axis=0)
    depth = math.inf
    for _ in range(2):  # weak perspective first, then with each point's depth
        stretched = centred * (1.0 + world[:, 2:3] / depth)
        p = stretched[ref] - stretched[ref].mean(axis=0)
        denom = float(np.sum(p * p))
        if denom <= 0.0:
            raise KinematicsError(
                "The image landmarks put both shoulders and hips on one pixel; pass the same "
                "frame's normalised landmarks with the picture's size."
            )
        scale = float(np.sum(w * p)) / denom  # metres per pixel at the hips' depth
        if not scale > 0.0:
            raise KinematicsError(
                "The image landmarks do not match the world landmarks (mirrored or another "
                "frame's); pass both from the same MediaPipe result."
            )
        depth = scale * focal
    merged = world.copy()
    merged[:, :2] = world[ref, :2].mean(axis=0) + scale * (stretched - stretched[ref].mean(axis=0))
    return merged


def _smoothstep(x: float) -> float:
    """0 below 0, 1 above 1, a smooth S between."""
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


def doubt_depth_bends(merged: np.ndarray, cfg: PoseConfig) -> np.ndarray:
    """``merged`` with each elbow's depth bend doubted where the image shows the arm straight.

    The depth bend is how far (m) the elbow's depth lies off the shoulder-wrist line (at the
    elbow's place along it in the picture). Where the picture shows the arm straight, MediaPipe's
    depth alone bends it by up to ``PoseConfig.depth_bend_noise``, so a bend that small is
    dropped and one up to twice it shrunk; the image plane then decides the elbow angle. Where
    the picture shows the arm bent, or the depth bend is large, depth is kept as it is.
    """
    out = merged
    for idx in LANDMARKS.values():
        S, E, W = (merged[idx[name]] for name in ARM_POINTS)
        chord = W[:2] - S[:2]
        limbs = float(np.linalg.norm(E[:2] - S[:2]) + np.linalg.norm(W[:2] - E[:2]))
        reach = float(chord @ chord)
        if limbs <= 0.0 or reach <= 0.0:
            continue
        straightness = math.sqrt(reach) / limbs
        doubt = _smoothstep(
            (straightness - (2 * cfg.straight_image - 1)) / (1 - cfg.straight_image)
        )
        if doubt == 0.0:
            continue
        along = min(max(float((E[:2] - S[:2]) @ chord) / reach, 0.0), 1.0)
        line = S[2] + along * (W[2] - S[2])
        bend = E[2] - line
        keep = _smoothstep(abs(bend) / cfg.depth_bend_noise - 1.0)
        if out is merged:
            out = merged.copy()
        out[idx["elbow"], 2] = line + bend * (1.0 - doubt * (1.0 - keep))
    return out


def _torso_rotation(points: np.ndarray, hips_seen: bool) -> np.ndarray:
    """Columns: the torso's forward, left and up axes in MediaPipe's axes."""
    ls, rs = points[LANDMARKS["left"]["shoulder"]], points[LANDMARKS["right"]["shoulder"]]
    lh, rh = points[HIPS["left"]], points[HIPS["right"]]
    left = ls - rs
    if hips_seen:
        left = left + (lh - rh)
        up = (ls + rs - lh - rh) / 2
    else:  # sitting close to the camera: assume an upright body (MediaPipe's y is down)
        up = np.array([0.0, -1.0, 0.0])
    if np.linalg.norm(left) < 1e-6:
        raise KinematicsError(
            "The pose landmarks put both shoulders on one point; pass a person's landmarks."
        )
    left = _unit(left)
    up = up - (up @ left) * left
    if np.linalg.norm(up) < 1e-6:
        raise KinematicsError(
            "The pose landmarks give no torso (the hips lie on the shoulder line); pass a "
            "person's landmarks."
        )
    up = _unit(up)
    return np.column_stack([np.cross(left, up), left, up])


def check_arm_seen(visibility: np.ndarray | None, side: str, cfg: PoseConfig) -> None:
    """Raise one sentence when ``side``'s shoulder, elbow or wrist is not visible enough."""
    if visibility is None:
        return
    for name in ARM_POINTS:
        i = LANDMARKS[side][name]
        if visibility[i] < cfg.min_visibility:
            raise KinematicsError(
                f"The person's {side} {name} is out of view (visibility {visibility[i]:.2f}); "
                f"show the whole {side} arm to the camera."
            )


HAND_SHAPE_POINTS = ("index", "pinky", "thumb")
"""The hand points the stream fits as one rigid hand with the wrist (:func:`hand_shape`)."""


def _skew(v: np.ndarray) -> np.ndarray:
    """The cross-product matrix of ``v``: ``_skew(v) @ w == v x w``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def hand_axes(wrist: np.ndarray, index: np.ndarray, pinky: np.ndarray) -> np.ndarray | None:
    """The hand's own frame from its points (columns: across the palm toward the index, from the
    knuckles toward the wrist, and their cross product), or None when they give none."""
    along = wrist - (index + pinky) / 2
    width = index - pinky
    if np.linalg.norm(along) < 1e-6:
        return None
    y = _unit(along)
    across = width - (width @ y) * y
    if np.linalg.norm(across) < 1e-6:
        return None
    x = _unit(across)
    return np.column_stack([x, y, _cross(x, y)])


def hand_shape(points: np.ndarray) -> np.ndarray | None:
    """Index, pinky and thumb in the hand's own frame (:func:`hand_axes`), (3, 3) m, from the
    wrist, index, pinky and thumb points ``(4, 3)``: one frame's measure of the person's hand."""
    axes = hand_axes(points[0], points[1], points[2])
    if axes is None:
        return None
    return (points[1:] - points[0]) @ axes


def _refine_limbs(
    points: np.ndarray,
    lengths: np.ndarray,
    weights: np.ndarray,
    iterations: int,
    hand: np.ndarray | None = None,
) -> np.ndarray:
    """Shoulder, elbow and wrist (and the hand points) on limbs of ``lengths``, nearest ``points``.

    The maximum-likelihood chain under anisotropic noise (``weights``: one over each point's
    noise per camera axis, (n, 3)): Gauss-Newton over the shoulder and the two limb directions,
    each direction moved in its tangent plane. With MediaPipe's depth several times noisier than
    x and y, the known limb lengths pull a limb's depth toward what its image-plane length implies.

    With ``hand`` (the index, pinky and thumb in the hand's own frame, :func:`hand_shape`, (3, 3)),
    ``points`` also holds the measured index, pinky and thumb (rows 3-5), and the hand is a rigid
    body on the wrist, turned freely: its three points pin the wrist as well as the wrist's own
    landmark does.

    Returns:
        ``(3, 3)``, or ``(6, 3)`` with ``hand``: the fitted points, in ``points``' order.
    """
    S = points[0].copy()
    dirs = [_unit(points[1] - points[0]), _unit(points[2] - points[1])]
    R = None if hand is None else hand_axes(points[2], points[3], points[4])
    if R is None:
        hand, points, weights = None, points[:3], weights[:3]
    n = len(points)
    J = np.zeros((3 * n, 7 if hand is None else 10))

    def chain() -> np.ndarray:
        E = S + lengths[0] * dirs[0]
        W = E + lengths[1] * dirs[1]
        fitted = [S, E, W] if R is None else [S, E, W, *(W + hand @ R.T)]
        return np.stack(fitted)

    for _ in range(iterations):
        fitted = chain()
        r = (fitted - points) * weights
        J[:] = 0.0
        for k in range(n):
            J[3 * k : 3 * k + 3, 0:3] = np.diag(weights[k])
        for d, u in enumerate(dirs):
            basis = np.linalg.svd(u[None, :])[2][1:]  # two unit vectors across u
            for k in range(d + 1, n):
                J[3 * k : 3 * k + 3, 3 + 2 * d : 5 + 2 * d] = (weights[k] * lengths[d])[
                    :, None
                ] * basis.T
        for k in range(3, n):  # a turn of the hand about the wrist moves its points
            J[3 * k : 3 * k + 3, 7:10] = -weights[k][:, None] * _skew(fitted[k] - fitted[2])
        step = np.linalg.lstsq(J, -r.reshape(-1), rcond=None)[0]
        S = S + step[:3]
        for d in range(2):
            basis = np.linalg.svd(dirs[d][None, :])[2][1:]
            dirs[d] = _unit(dirs[d] + step[3 + 2 * d : 5 + 2 * d] @ basis)
        if R is not None:
            R = pin.exp3(step[7:10]) @ R
    return chain()


def measured_lengths(points: np.ndarray, seen: Callable[[int], bool], side: str) -> np.ndarray:
    """Upper-arm and forearm lengths (m) in one frame: both arms' mean when the other is seen."""
    arms = [side] + [
        s for s in LANDMARKS if s != side and all(seen(LANDMARKS[s][n]) for n in ARM_POINTS)
    ]
    per_arm = [
        [np.linalg.norm(points[LANDMARKS[s][b]] - points[LANDMARKS[s][a]]) for a, b in LIMBS]
        for s in arms
    ]
    return np.mean(per_arm, axis=0)


def _read(
    world: np.ndarray,
    pixels: np.ndarray | None,
    size: np.ndarray | None,
    visibility: np.ndarray | None,
    side: str,
    cfg: PoseConfig,
    lengths: np.ndarray | None = None,
    torso: np.ndarray | None = None,
    hand: np.ndarray | None = None,
) -> _Reading:
    """The limb directions in the arm base frame, or a KinematicsError for a missing arm.

    ``lengths`` (m, upper arm and forearm) replace this frame's measured ones, and ``torso``
    (world landmarks, (33, 3)) this frame's points for the torso's frame: a stream smooths both
    more than the arm, as the body turns and the limbs change length slowly or never. ``hand``
    (the person's hand shape, :func:`hand_shape`, from recent frames) fits the index, pinky and
    thumb as one rigid hand on the wrist when all three are seen (:func:`_refine_limbs`).
    """
    idx = LANDMARKS[side]

    def seen(i: int) -> bool:
        return visibility is None or bool(visibility[i] >= cfg.min_visibility)

    check_arm_seen(visibility, side, cfg)
    if pixels is None:
        points = world
    else:
        points = doubt_depth_bends(_merge_image(world, pixels, size, cfg), cfg)
    for (a, b), what in zip(LIMBS, ("upper arm", "forearm"), strict=True):
        if np.linalg.norm(points[idx[b]] - points[idx[a]]) < cfg.min_segment:
            raise KinematicsError(
                f"The {side} {what}'s landmarks coincide, so its direction is unknown; pass "
                "a person's landmarks."
            )
    frame_lengths = measured_lengths(points, seen, side)
    hand_points = [idx[name] for name in ("wrist", *HAND_SHAPE_POINTS)]
    frame_hand = hand_shape(points[hand_points]) if all(map(seen, hand_points)) else None
    if frame_hand is None:
        hand = None
    names = ARM_POINTS if hand is None else (*ARM_POINTS, *HAND_SHAPE_POINTS)
    weights = np.tile([1.0, 1.0, 1.0 / cfg.depth_noise], (len(names), 1))
    weights[len(ARM_POINTS) :] *= cfg.hand_weight
    fitted = _refine_limbs(
        points[[idx[name] for name in names]],
        frame_lengths if lengths is None else lengths,
        weights,
        cfg.refine_iterations,
        hand,
    )
    if len(fitted) > len(ARM_POINTS):  # the hand's points as the rigid hand puts them
        points = points.copy()
        points[[idx[name] for name in HAND_SHAPE_POINTS]] = fitted[len(ARM_POINTS) :]
    R = _torso_rotation(
        points if torso is None else torso, seen(HIPS["left"]) and seen(HIPS["right"])
    )
    S, E, W = fitted[: len(ARM_POINTS)] @ R
    hand_dir = palm = None
    palm_sine = 0.0
    H = W
    if seen(idx["index"]) and seen(idx["pinky"]):
        index, pinky = R.T @ points[idx["index"]], R.T @ points[idx["pinky"]]
        knuckles = (index + pinky) / 2
        if np.linalg.norm(knuckles - W) >= cfg.min_segment:
            H = knuckles
            hand_dir = _unit(knuckles - W)
            width = index - pinky
            across = width - (width @ hand_dir) * hand_dir
            if np.linalg.norm(across) > _SEEN * np.linalg.norm(width):
                palm = _unit(across)
                palm_sine = float(np.linalg.norm(across) / np.linalg.norm(width))
    rel = np.stack([S, E, W, H]) - S
    return _Reading(
        _unit(E - S), _unit(W - E), hand_dir, palm, palm_sine, rel, frame_lengths, frame_hand
    )


def _axis_sign(model: pin.Model, data: pin.Data, joint: int, axis: int) -> float:
    """+1 or -1: whether ``joint`` turns about +``axis`` or -``axis`` of its own frame."""
    q = np.zeros(model.nq)
    pin.forwardKinematics(model, data, q)
    R0 = data.oMi[joint].rotation.copy()
    q[model.joints[joint].idx_q] = 0.1
    pin.forwardKinematics(model, data, q)
    return float(np.sign(pin.log3(R0.T @ data.oMi[joint].rotation)[axis]))


@functools.lru_cache(maxsize=2)
def _signs(side: str) -> tuple[float, float, float]:
    """Axis signs of humeral rotation (y), forearm rotation (y) and wrist deviation (x)."""
    arm = default_arm(side)
    data, joints = arm.model.createData(), arm.joints
    return (
        _axis_sign(arm.model, data, joints.shoulder_Y, 1),
        _axis_sign(arm.model, data, joints.elbow_Y, 1),
        _axis_sign(arm.model, data, joints.wrist_X, 0),
    )


def _closed_form(
    reading: _Reading,
    arm: HumanArm,
    data: pin.Data,
    q_hold: np.ndarray,
    overhead: bool,
) -> np.ndarray:
    """The arm angles that give ``reading``'s directions on one shoulder branch, clamped."""
    s2, s4, s6 = _signs(arm.side)
    model, lower, upper, joints = arm.model, arm.lower, arm.upper, arm.joints
    q = q_hold.copy()
    u = reading.upper
    lateral = -1.0 if arm.side == "right" else 1.0  # abduction moves the arm along -y / +y
    q[1] = math.asin(_clamp(lateral * u[1]))
    q[0] = math.atan2(u[0], -u[2])
    if overhead:
        q[1] = math.pi - q[1]
        q[0] -= math.copysign(math.pi, q[0])
    q[3] = math.acos(_clamp(u @ reading.fore))
    if math.sin(q[3]) > _SEEN:  # read even when weakly observable; a stream weighs it
        q[2] = 0.0
        pin.forwardKinematics(model, data, q)
        fA = data.oMi[joints.shoulder_X].rotation.T @ reading.fore
        q[2] = s2 * math.atan2(-fA[2], fA[0])
    elif overhead:
        q[2] += math.pi
    q[:4] = np.clip(q[:4], lower[:4], upper[:4])
    if reading.hand is None:
        return np.clip(q, lower, upper)
    pin.forwardKinematics(model, data, q)
    if reading.palm is not None:
        hand_axes = np.column_stack(
            [reading.palm, -reading.hand, _cross(reading.palm, -reading.hand)]
        )
        rel = data.oMi[joints.elbow_Z].rotation.T @ hand_axes  # = Ry(s4 q4) Rz(q5) Rx(s6 q6)
        q[5] = math.asin(_clamp(rel[1, 0]))
        q[6] = s6 * math.atan2(-rel[1, 2], rel[1, 1])
        q[4] = s4 * math.atan2(-rel[2, 0], rel[0, 0])
    else:  # the hand's direction only: forearm rotation held, the wrist follows
        q[4] = min(max(q[4], lower[4]), upper[4])
        pin.forwardKinematics(model, data, q)
        h = data.oMi[joints.elbow_Y].rotation.T @ reading.hand  # = Rz(q5) Rx(s6 q6) (0, -1, 0)
        q[6] = s6 * math.asin(_clamp(-h[2]))
        q[5] = math.atan2(h[0], -h[1])
    return np.clip(q, lower, upper)


def _fitted_points(arm: HumanArm, data: pin.Data, q: np.ndarray, reading: _Reading) -> np.ndarray:
    """The arm at ``q`` drawn at the measured limb lengths from the origin: (4, 3)."""
    pin.forwardKinematics(arm.model, data, q)
    elbow, wrist = data.oMi[arm.joints.elbow_Z], data.oMi[arm.joints.wrist_Z]
    E = elbow.translation / arm.upper_arm_length
    W = (wrist.translation - elbow.translation) / arm.forearm_length
    lengths = np.linalg.norm(np.diff(reading.points, axis=0), axis=1)
    out = np.zeros((4, 3))
    out[1] = lengths[0] * E
    out[2] = out[1] + lengths[1] * W
    out[3] = out[2]
    if reading.hand is not None:
        hand_axis = -data.oMi[arm.joints.wrist_X].rotation[:, 1]
        out[3] = out[2] + lengths[2] * hand_axis
    return out


def observable_joints(reading: _Reading, cfg: PoseConfig) -> np.ndarray:
    """Which of the seven joints ``reading`` determines (see the module docstring)."""
    flexion = math.acos(float(np.clip(reading.upper @ reading.fore, -1.0, 1.0)))
    hand = reading.hand is not None
    palm = reading.palm is not None and reading.palm_sine >= cfg.palm_axis
    return np.array([True, True, flexion >= cfg.bent_elbow, True, palm, hand, hand])


def _rms(gap: np.ndarray) -> float:
    """The RMS length (m) of the rows of ``gap``."""
    return math.sqrt(float(np.mean(np.sum(gap * gap, axis=1))))


def fit_reading(
    reading: _Reading,
    arm: HumanArm,
    data: pin.Data,
    cfg: PoseConfig,
    q_hold: np.ndarray,
) -> PoseFit:
    """The arm fitted to one frame's directions, unobservable joints held at ``q_hold``."""
    observable = observable_joints(reading, cfg)
    candidates = []
    for overhead in (False, True):
        q = _closed_form(reading, arm, data, q_hold, overhead)
        fitted = _fitted_points(arm, data, q, reading)
        gap = reading.points[1:] - fitted[1:]
        if reading.hand is None:
            gap = gap[:2]
        natural = not overhead and abs(q[1]) <= cfg.overhead_abduction
        candidates.append((q, fitted, gap, natural))
    # Humeral rotation read off a straight elbow is noise that one branch may clamp where the
    # other does not: a hanging arm's few millimetres at the wrist must not turn the shoulder
    # half round. So while the wrist lies within BRANCH_NOISE of the upper arm's line, the first
    # branch is the natural one and misses the wrist by no more than that beyond the second,
    # they are judged by the elbow alone.
    first, second = (_rms(c[2]) for c in candidates)
    forearm = float(np.linalg.norm(reading.points[2] - reading.points[1]))
    off_line = forearm * math.sqrt(max(0.0, 1.0 - float(reading.upper @ reading.fore) ** 2))
    elbow_only = off_line <= BRANCH_NOISE and candidates[0][3] and first - second <= BRANCH_NOISE
    best: tuple[float, bool, float, np.ndarray, np.ndarray] | None = None
    for q, fitted, gap, natural in candidates:
        residual = _rms(gap[:1] if elbow_only else gap)
        # Meet the landmarks first (to a tenth of a millimetre), then the first branch away from
        # the gimbal lock, then stay near the reference.
        key = (round(residual, 4), not natural, float(np.linalg.norm(q - q_hold)))
        if best is None or key < best[:3]:
            best = (*key, q, fitted)
    assert best is not None
    q, fitted = best[3], best[4]
    gap = reading.points[1:] - fitted[1:]
    if reading.hand is None:
        gap = gap[:2]
    residual = _rms(gap)
    return PoseFit(
        q_human=q,
        observable=observable,
        residual=residual,
        points=reading.points,
        hand_seen=reading.hand is not None,
    )


def read_landmarks(
    landmarks: object,
    image_landmarks: object,
    side: str,
    image_size: object,
    cfg: PoseConfig,
) -> _Reading:
    """Check one frame of landmarks and read the side's limb directions from it."""
    side = check_side(side, "The pose fit's side")
    world, pixels, size, visibility = _check_landmarks(landmarks, image_landmarks, image_size)
    return _read(world, pixels, size, visibility, side, cfg)


def fit_pose_landmarks(
    landmarks: object,
    image_landmarks: object = None,
    side: str = "right",
    *,
    image_size: tuple[float, float] | None = None,
    config: PoseConfig | None = None,
) -> PoseFit:
    """Fit one side's 7-DOF arm to one frame of MediaPipe Pose landmarks.

    Args:
        landmarks: the world landmarks, (33, 3) or (33, 4) with visibility: metres,
            hip-centred, x toward the image's right, y down, z away from the camera, the
            person facing the camera.
        image_landmarks: optional (33, 2) or (33, 3) normalised image x, y (and visibility) of
            the same frame; their x, y replace the world's (see the module docstring). A str
            here is taken as ``side``, so ``fit_pose_landmarks(landmarks, "left")`` works.
        side: the person's arm to fit, ``"right"`` or ``"left"``.
        image_size: ``(width, height)`` of the picture in pixels; needed with image landmarks.
        config: fit defaults.

    Returns:
        A :class:`PoseFit`; joints the landmarks do not show at all are at the neutral arm's.

    Raises:
        KinematicsError: wrong shapes, NaN, a missing arm (visibility below
            ``PoseConfig.min_visibility``) or landmarks that are not a person's.
    """
    if isinstance(image_landmarks, str):
        image_landmarks, side = None, image_landmarks
    cfg = config or PoseConfig()
    reading = read_landmarks(landmarks, image_landmarks, side, image_size, cfg)
    arm = default_arm(side)
    return fit_reading(reading, arm, arm.model.createData(), cfg, arm.neutral.copy())
