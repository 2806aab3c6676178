"""Streams of MediaPipe Pose landmarks: the human arm fitted to a camera's stream, and the
landmarks of a known arm (the ground truth the fit is judged against).

Each frame's landmarks pass a constant-velocity Kalman filter (:class:`ConstantVelocityFilter`)
before the fit of :func:`fit_pose_landmarks`: it predicts each landmark with its velocity, so it
smooths the jitter without the lag of a low-pass filter. Its noise is set per axis: the world
landmarks' depth, several times noisier than x and y in MediaPipe's output, is smoothed most;
the image landmarks, steady to a few pixels, least. The limb lengths the fit refines the arm at are the running
median of the lengths measured in recent frames. Joints the landmarks show weakly (humeral
rotation with a nearly straight elbow, forearm rotation with the palm's axis along the hand) move
toward their reading only by a fraction that shrinks with how weakly they are seen; joints not
seen at all (the wrist with the hand out of view) hold the previous frame's angle. So the arm
never jumps where the landmarks say little.

The torso moves far more slowly than the arm, and every arm angle is read from the shoulder: the
torso's shape (its shoulders and hips about their centre) is filtered with the much lower
``StreamConfig.torso_acceleration``, while the body's place in the picture (that centre) keeps
the arm's pace, so a person who steps aside is followed at once and one who turns, leans or
shrugs within :attr:`PoseStreamFitter.torso_lag_s`. The torso's frame is read from a second,
slower filter of the same landmarks: its yaw, read from depth differences across the shoulders
and hips, is noisy. The hand's index, pinky and thumb are fitted as one rigid hand in the
person's own shape (the median over recent frames, as the limb lengths), which pins the wrist.

Lag: a steady motion passes without delay; a change of speed is taken up within the depth
filter's time constant, :attr:`PoseStreamFitter.lag_s` (0.38 s at 30 Hz by default). Measured on
the benchmark's motion, the fitted elbow trails the true one by about 0.03 s (0.13 s with the One
Euro filter this replaced).

The landmarks of a known arm pose: :func:`landmarks_from_arm` places a simple body (shoulders,
hips, a face, the other arm hanging, legs) around :class:`HumanArm`'s forward kinematics of one arm, turns it into MediaPipe's world
axes (hip-centred, x toward the image's right, y down, z away from the camera, the person facing
the camera) and projects it through a pinhole camera into normalised image landmarks. Tests,
benchmarks and simulated camera sources use it, so the fit is judged against the studio's own arm
model, at any limb lengths the caller's arm has.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from .._checks import (
    KinematicsError,
    check_side,
    instance_of,
    positive_number,
    real_array,
    whole_number,
)
from ._filter import ConstantVelocityFilter, OneEuroFilter, smooth_constant_velocity
from ._human import HumanArm
from ._pose import (
    FOREARM_ROTATION,
    HIPS,
    HUMERAL_ROTATION,
    LANDMARKS,
    N_LANDMARKS,
    PoseConfig,
    PoseFit,
    _check_landmarks,
    _read,
    check_arm_seen,
    default_arm,
    fit_reading,
)


@dataclass(frozen=True)
class StreamConfig:
    """Defaults of the landmark stream's filtering, documented once.

    Attributes:
        xy_noise_m: the world landmarks' jitter in x and y (s.d., m) the Kalman filter assumes.
        depth_noise_m: their jitter in depth (s.d., m): MediaPipe's depth is several times
            noisier than x and y, so it is smoothed more.
        image_noise_px: the image landmarks' jitter (s.d., pixels): a few pixels, so the image
            decides x and y.
        acceleration: how fast a landmark's velocity may change (m/s^2 per sqrt(Hz)), the
            filter's motion model; lower smooths more and takes up a change of speed later.
        image_acceleration_px: the same in the picture (pixels/s^2 per sqrt(Hz)); about
            ``acceleration`` times the pixels per metre at the person (220 at 2 m with a
            640-pixel, 60-degree camera).
        torso_cutoff_hz: the One Euro cutoff of the landmarks the torso's frame is read from
            (the body turns slowly; its yaw, read from depth differences across the shoulders,
            is noisy).
        d_cutoff_hz: cutoff of that filter's speed estimate.
        torso_acceleration: ``acceleration`` for the torso's shape, its shoulders and hips about
            their centre (in the picture, that centre, the body's place, keeps the arm's
            ``acceleration``): the torso turns, leans and shrugs far more slowly than the arm
            swings, and every arm angle is read from the shoulder. Its lag is
            :attr:`PoseStreamFitter.torso_lag_s`.
        rigid_hand: fit the index, pinky and thumb as one rigid hand on the wrist, in the
            person's own hand shape (the median of recent frames'), so the hand's points pin the
            wrist as well as its own landmark does.
        max_gap_s: a gap between frames longer than this restarts the filter (the person left
            and came back: no smoothing across).
        length_frames: the limb lengths are the median over this many recent frames.
        weak_gain: a weakly seen joint moves this fraction of the way to its reading per frame
            at the edge of observability, less the more weakly it is seen.
        pose: the per-frame fit's defaults.
    """

    xy_noise_m: float = 0.03
    depth_noise_m: float = 0.08
    image_noise_px: float = 3.0
    acceleration: float = 0.1
    image_acceleration_px: float = 22.0
    torso_cutoff_hz: float = 0.3
    d_cutoff_hz: float = 1.0
    torso_acceleration: float = 0.005
    rigid_hand: bool = True
    max_gap_s: float = 1.0
    length_frames: int = 90
    weak_gain: float = 0.2
    pose: PoseConfig = field(default_factory=PoseConfig)

    def __post_init__(self) -> None:
        for name in (
            "xy_noise_m",
            "depth_noise_m",
            "image_noise_px",
            "acceleration",
            "image_acceleration_px",
            "torso_cutoff_hz",
            "d_cutoff_hz",
            "torso_acceleration",
            "max_gap_s",
        ):
            positive_number(getattr(self, name), f"StreamConfig.{name}")
        value = self.weak_gain
        if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
            raise KinematicsError(f"StreamConfig.weak_gain must be a number >= 0; got {value!r}.")
        whole_number(self.length_frames, "StreamConfig.length_frames", 1)
        if not isinstance(self.rigid_hand, bool):
            raise KinematicsError(
                f"StreamConfig.rigid_hand must be True or False; got {self.rigid_hand!r}."
            )
        instance_of(self.pose, PoseConfig, "StreamConfig.pose")


TORSO = (
    LANDMARKS["left"]["shoulder"],
    LANDMARKS["right"]["shoulder"],
    HIPS["left"],
    HIPS["right"],
)
"""MediaPipe Pose's indices of the torso's landmarks: the shoulders and the hips."""


def _filter_model(cfg: StreamConfig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The landmark filters' model: the world landmarks' noise (33, 3) and acceleration (33, 1),
    and the image landmarks' acceleration (34, 1), for the image landmarks about the torso's
    centre and that centre last (:func:`_about_torso`).

    World landmarks are hip-centred already, so a body that steps aside does not move them; in
    the picture it moves every landmark at once, so there only the torso's shape about its
    centre is slow and the centre keeps the arm's pace.
    """
    noise = np.empty((N_LANDMARKS, 3))
    noise[:, :2] = cfg.xy_noise_m
    noise[:, 2] = cfg.depth_noise_m
    slow = cfg.torso_acceleration / cfg.acceleration
    world = np.full((N_LANDMARKS, 1), cfg.acceleration)
    world[list(TORSO)] *= slow
    image = np.full((N_LANDMARKS + 1, 1), cfg.image_acceleration_px)
    image[list(TORSO)] *= slow
    return noise, world, image


def _about_torso(points: np.ndarray) -> np.ndarray:
    """Landmarks ``(..., 33, k)`` about the torso landmarks' mean, and that mean as a 34th row.

    A linear change of variables: the arm's landmarks, filtered at the centre's pace, come
    back exactly as filtered on their own (:func:`_from_torso`); only the torso's rows change.
    """
    centre = points[..., TORSO, :].mean(axis=-2, keepdims=True)
    return np.concatenate([points - centre, centre], axis=-2)


def _from_torso(about: np.ndarray) -> np.ndarray:
    """The landmarks back from :func:`_about_torso`'s rows."""
    return about[..., :-1, :] + about[..., -1:, :]


def _kalman_lag_s(noise: float, acceleration: float, dt: float) -> float:
    """:meth:`ConstantVelocityFilter.lag_s` of one element of that noise and acceleration."""
    return ConstantVelocityFilter(noise, acceleration).lag_s(dt)


class PoseStreamFitter:
    """Fits one side's arm to landmark frames as they arrive, filtered and held smoothly.

    Args:
        side: the person's arm to fit, ``"right"`` or ``"left"``.
        config: filtering defaults.

    Raises:
        KinematicsError: a bad side or config.
    """

    def __init__(self, side: str = "right", config: StreamConfig | None = None) -> None:
        self.side = check_side(side, "PoseStreamFitter's side")
        instance_of(config, StreamConfig, "PoseStreamFitter's config", optional=True)
        self.config = config or StreamConfig()
        self.arm = default_arm(self.side)
        self._data = self.arm.model.createData()
        cfg = self.config
        world_noise, world_acceleration, image_acceleration = _filter_model(cfg)
        self._world = ConstantVelocityFilter(world_noise, world_acceleration)
        self._image = ConstantVelocityFilter(cfg.image_noise_px, image_acceleration)
        self._torso = OneEuroFilter(cfg.torso_cutoff_hz, 0.0, cfg.d_cutoff_hz)
        self._lengths: deque[np.ndarray] = deque(maxlen=cfg.length_frames)
        self._hands: deque[np.ndarray] = deque(maxlen=cfg.length_frames)
        self.reset()

    @property
    def lag_s(self) -> float:
        """The time (s) in which the filter takes up a change of the arm's speed.

        The world depth's Kalman time constant at the frame interval last seen (30 Hz before
        two frames): 0.38 s with the defaults. A steady motion passes without delay, and over a
        smooth one the arm trails far less (about 0.03 s on the benchmark's motion). The
        torso's frame, filtered more, follows a turning body with ``1 / (2 pi
        torso_cutoff_hz)`` (0.53 s); the arm's own motion is not delayed by it.
        """
        return _kalman_lag_s(self.config.depth_noise_m, self.config.acceleration, self._dt)

    @property
    def torso_lag_s(self) -> float:
        """The same for the torso's shape (its shoulders and hips about their centre):
        ``StreamConfig.torso_acceleration``'s time constant in the world landmarks' depth, the
        slowest (1.7 s with the defaults; 0.71 s in the picture, whose landmarks decide the
        shoulder's place when the page sends them). A body that steps aside is followed as fast
        as the arm; one that turns, leans or shrugs within about this time.
        """
        cfg = self.config
        return _kalman_lag_s(cfg.depth_noise_m, cfg.torso_acceleration, self._dt)

    def reset(self) -> None:
        """Forget the past frames: a new person, a new source."""
        self._world.reset()
        self._image.reset()
        self._torso.reset()
        self._lengths.clear()
        self._hands.clear()
        self._t: float | None = None
        self._dt = 1.0 / 30.0
        self._q: np.ndarray | None = None
        self._had_image = False

    def update(
        self,
        t: float,
        landmarks: object,
        image_landmarks: object = None,
        image_size: tuple[float, float] | None = None,
        *,
        smoothed: bool = False,
    ) -> PoseFit:
        """Fit one frame.

        Args:
            t: the frame's time (s), increasing from frame to frame.
            landmarks: world landmarks, as :func:`fit_pose_landmarks` takes them.
            image_landmarks: optional image landmarks of the same frame.
            image_size: ``(width, height)`` in pixels, with image landmarks.
            smoothed: the landmarks come from :func:`smooth_landmarks` (a recording, smoothed
                with the future): the landmark filters are passed by, the rest is the same.

        Returns:
            A :class:`PoseFit` of the filtered landmarks; ``observable`` is this frame's.

        Raises:
            KinematicsError: bad landmarks, a missing arm or a time that does not increase;
                the fitter's state is unchanged then.
        """
        if not (isinstance(t, int | float) and math.isfinite(t)):
            raise KinematicsError(
                f"The frame's time must be a finite number of seconds; got {t!r}."
            )
        world, pixels, size, visibility = _check_landmarks(landmarks, image_landmarks, image_size)
        cfg = self.config
        check_arm_seen(visibility, self.side, cfg.pose)
        if self._t is not None and t <= self._t:
            raise KinematicsError(
                f"The frame's time {t} s does not follow the previous frame's {self._t} s; "
                "give increasing times (or reset the fitter for a new source)."
            )
        if self._t is not None and t - self._t > cfg.max_gap_s:
            self.reset()
        if (pixels is not None) != self._had_image:
            self._image.reset()
            self._had_image = pixels is not None
        torso = self._torso(t, world)
        if not smoothed:
            world = self._world(t, world)
            if pixels is not None:
                pixels = _from_torso(self._image(t, _about_torso(pixels)))
        if self._t is not None:
            self._dt = float(t) - self._t
        self._t = float(t)
        lengths = np.median(self._lengths, axis=0) if self._lengths else None
        hand = np.median(self._hands, axis=0) if self._hands and cfg.rigid_hand else None
        reading = _read(world, pixels, size, visibility, self.side, cfg.pose, lengths, torso, hand)
        self._lengths.append(reading.lengths)
        if reading.hand_shape is not None:
            self._hands.append(reading.hand_shape)
        q_hold = self.arm.neutral.copy() if self._q is None else self._q
        fit = fit_reading(reading, self.arm, self._data, cfg.pose, q_hold)
        q = fit.q_human.copy()
        if self._q is not None:
            gains = self._weak_gains(reading, fit.observable)
            q = self._q + gains * (q - self._q)
        self._q = q
        return PoseFit(
            q_human=q.copy(),
            observable=fit.observable,
            residual=fit.residual,
            points=fit.points,
            hand_seen=fit.hand_seen,
        )

    def _weak_gains(self, reading: object, observable: np.ndarray) -> np.ndarray:
        """Per joint, the fraction of the way to this frame's reading the arm moves."""
        cfg, pose = self.config, self.config.pose
        gains = np.ones(len(observable))
        flexion = math.acos(float(np.clip(reading.upper @ reading.fore, -1.0, 1.0)))
        strength = {
            HUMERAL_ROTATION: (math.sin(flexion) / math.sin(pose.bent_elbow)) ** 2,
            FOREARM_ROTATION: (reading.palm_sine / pose.palm_axis) ** 2,
        }
        for joint, seen in strength.items():
            if not observable[joint]:
                gains[joint] = cfg.weak_gain * min(seen, 1.0)
        return gains


def smooth_landmarks(
    times: object,
    landmarks: object,
    image_landmarks: object = None,
    image_size: object = None,
    config: StreamConfig | None = None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """A run of landmark frames smoothed with the past and the future, for a recording.

    The stream's own model (:class:`PoseStreamFitter`'s constant-velocity filters, their noise
    and acceleration from ``config``) run forward and back over the run
    (:func:`smooth_constant_velocity`): no lag, and each frame's jitter averaged with the frames
    on both sides. Fit the result with ``PoseStreamFitter.update(..., smoothed=True)``.

    Measured on ``benchmarks/bench_pose.py``'s synthetic streams (30 Hz, sigma 3 cm x, y and
    8 cm depth, with and without image landmarks), Puma560 joints 1-3 fall in the true arm's
    cell in 82-85% of frames, against 72-79% live.

    Args:
        times: the frames' times (s, increasing), shape (N,), one run of a person in view with
            no gap (split a recording where the person or the arm left the picture).
        landmarks: world landmarks, (N, 33, 3) or (N, 33, 4); visibility is kept as it is.
        image_landmarks: optional normalised image landmarks, (N, 33, 2) or (N, 33, 3).
        image_size: ``(width, height)`` in pixels, or one per frame (N, 2), with image
            landmarks.
        config: the stream's defaults.

    Returns:
        The smoothed world landmarks and image landmarks (None without), shaped as given.

    Raises:
        KinematicsError: shapes that do not fit, non-finite values, times that do not increase.
    """
    instance_of(config, StreamConfig, "smooth_landmarks' config", optional=True)
    cfg = config or StreamConfig()
    t = real_array(times, "The landmark frames' times", "pass seconds")
    world = real_array(landmarks, "The landmark frames", "pass (N, 33, 3 or 4) world landmarks")
    if world.ndim != 3 or world.shape[1:] not in ((N_LANDMARKS, 3), (N_LANDMARKS, 4)):
        raise KinematicsError(
            f"smooth_landmarks takes world landmarks of shape (N, 33, 3) or (N, 33, 4); got "
            f"{world.shape}."
        )
    if t.shape != (len(world),) or not np.all(np.isfinite(world)):
        raise KinematicsError(
            f"smooth_landmarks needs one time per frame ({len(world)}) and finite landmarks; "
            f"got {t.shape[0] if t.ndim else 0} times."
        )
    noise, world_acceleration, image_acceleration = _filter_model(cfg)
    world = world.copy()
    world[..., :3] = smooth_constant_velocity(t, world[..., :3], noise, world_acceleration)
    if image_landmarks is None:
        return world, None
    image = real_array(image_landmarks, "The image landmark frames", "pass (N, 33, 2 or 3)")
    size = real_array(image_size, "image_size", "pass (width, height) in pixels")
    size = np.broadcast_to(size, (len(image), 2)) if size.shape == (2,) else size
    if (
        image.ndim != 3
        or image.shape[:2] != (len(world), N_LANDMARKS)
        or image.shape[2] not in (2, 3)
        or size.shape != (len(world), 2)
        or not (np.all(np.isfinite(image)) and np.all(size > 0))
    ):
        raise KinematicsError(
            f"smooth_landmarks takes image landmarks (N, 33, 2 or 3) and sizes (2,) or (N, 2) "
            f"for {len(world)} frames; got {image.shape} and {size.shape}."
        )
    image = image.copy()
    pixels = image[..., :2] * size[:, None, :]
    pixels = _from_torso(
        smooth_constant_velocity(t, _about_torso(pixels), cfg.image_noise_px, image_acceleration)
    )
    image[..., :2] = pixels / size[:, None, :]
    return world, image


# ------------------------------------------------------------- landmarks of a known arm

BASE_TO_MEDIAPIPE = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]])
"""Rotation from the arm base frame's axes (x forward, y left, z up) to MediaPipe's world axes
for a person facing the camera (x toward the image's right = the person's left, y down, z away
from the camera)."""

HAND_POINTS = {
    "index": (0.2, -0.6, 0.0),
    "pinky": (-0.2, -0.55, 0.0),
    "thumb": (0.3, -0.3, 0.0),
}
"""Knuckles and thumb in the hand (wrist) frame, in units of the arm's hand length: the
fingers point along -y, the palm's width axis (pinky -> index) along +x."""


@dataclass(frozen=True)
class BodyShape:
    """The body around the arm, in metres (defaults: an adult of average build).

    Attributes:
        shoulder_width: between the shoulder joints.
        hip_width: between the hip joints.
        torso_height: from the hips' middle up to the shoulders' middle.
        yaw: the body turned about the vertical (rad), + toward the person's left.
        camera_distance: from the camera to the hips (m).
        camera_fov: the camera's horizontal field of view (rad).
        image_size: the picture's (width, height) in pixels.
    """

    shoulder_width: float = 0.38
    hip_width: float = 0.26
    torso_height: float = 0.50
    yaw: float = 0.0
    camera_distance: float = 2.5
    camera_fov: float = math.radians(60.0)
    image_size: tuple[int, int] = (640, 480)

    def __post_init__(self) -> None:
        for name in ("shoulder_width", "hip_width", "torso_height", "camera_distance"):
            positive_number(getattr(self, name), f"BodyShape.{name}")
        positive_number(self.camera_fov, "BodyShape.camera_fov")


def _body_points(arm: HumanArm, q_human: np.ndarray, body: BodyShape) -> np.ndarray:
    """All 33 points in the arm base frame's axes, relative to the hips' middle."""
    side = arm.side
    other = "left" if side == "right" else "right"
    lateral = {"left": 1.0, "right": -1.0}
    h = body.torso_height
    pts = np.zeros((N_LANDMARKS, 3))
    shoulder = {s: np.array([0.0, lateral[s] * body.shoulder_width / 2, h]) for s in lateral}
    for s in lateral:
        pts[LANDMARKS[s]["shoulder"]] = shoulder[s]
        pts[HIPS[s]] = (0.0, lateral[s] * body.hip_width / 2, 0.0)
    pose = arm.forward(q_human)
    idx = LANDMARKS[side]
    pts[idx["elbow"]] = shoulder[side] + pose.elbow[:3, 3]
    pts[idx["wrist"]] = shoulder[side] + pose.wrist[:3, 3]
    for name, local in HAND_POINTS.items():
        offset = pose.wrist[:3, :3] @ (arm.hand_length * np.asarray(local))
        pts[idx[name]] = pts[idx["wrist"]] + offset
    # The other arm (the same lengths: people are nearly symmetric) hangs.
    down = np.array([0.0, 0.0, -1.0])
    o = LANDMARKS[other]
    pts[o["elbow"]] = shoulder[other] + arm.upper_arm_length * down
    pts[o["wrist"]] = pts[o["elbow"]] + arm.forearm_length * down
    for name, local in HAND_POINTS.items():
        pts[o[name]] = pts[o["wrist"]] + arm.hand_length * np.array([local[0], 0.0, local[1]])
    # Face: nose, eyes (inner, centre, outer), ears, mouth; legs: knees, ankles, heels, toes.
    head = np.array([0.06, 0.0, h + 0.2])
    pts[0] = head + (0.05, 0.0, 0.0)
    for k, (dy, dz) in enumerate(((0.02, 0.04), (0.035, 0.04), (0.05, 0.04))):
        pts[1 + k] = head + (0.04, -dy, dz)  # the person's right eye points (1-3) ...
        pts[4 + k] = head + (0.04, dy, dz)  # ... and left (4-6): MediaPipe's order
    pts[7], pts[8] = head + (0.0, 0.075, 0.02), head + (0.0, -0.075, 0.02)
    pts[9], pts[10] = head + (0.04, 0.025, -0.05), head + (0.04, -0.025, -0.05)
    for s, first in (("left", 25), ("right", 26)):
        hip = pts[HIPS[s]]
        for k, (dx, dz) in enumerate(((0.02, -0.45), (0.0, -0.88), (-0.05, -0.93), (0.15, -0.93))):
            pts[first + 2 * k] = hip + (dx, 0.0, dz)
    return pts


def landmarks_from_arm(
    q_human: object, arm: HumanArm, body: BodyShape | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """MediaPipe Pose world and image landmarks of ``arm`` at ``q_human``.

    Args:
        q_human: the arm's joint angles (rad, (7,)), in :class:`HumanArm`'s convention.
        arm: the arm (its side and limb lengths; the body's other arm hangs).
        body: the body around it and the camera (default: :class:`BodyShape`).

    Returns:
        ``(world (33, 4), image (33, 3))``: world x, y, z (m) and visibility 1; normalised
        image x, y and visibility 1, for a pinhole camera with ``body.image_size``.

    Raises:
        KinematicsError: wrong shapes or non-finite angles, or an arm or body of the wrong type.
    """
    instance_of(arm, HumanArm, "landmarks_from_arm's arm")
    instance_of(body, BodyShape, "landmarks_from_arm's body", optional=True)
    body = body or BodyShape()
    q = real_array(q_human, "q_human", "pass 7 angles in radians")
    if q.shape != (arm.nq,) or not np.all(np.isfinite(q)):
        raise KinematicsError(f"q_human must be 7 finite angles in radians; got shape {q.shape}.")
    c, s = math.cos(body.yaw), math.sin(body.yaw)
    yaw = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    points = _body_points(arm, q, body) @ (BASE_TO_MEDIAPIPE @ yaw).T
    world = np.column_stack([points, np.ones(N_LANDMARKS)])
    width, height = body.image_size
    focal = width / 2 / math.tan(body.camera_fov / 2)
    # The camera looks at the hips from camera_distance, its picture's centre a little above
    # them (a tenth of the picture), so that the head shows.
    camera = points + (0.0, 0.1 * height * body.camera_distance / focal, body.camera_distance)
    if np.any(camera[:, 2] <= 0.1):
        raise KinematicsError(
            "The body reaches behind the camera; give BodyShape a larger camera_distance."
        )
    pixel_x = width / 2 + focal * camera[:, 0] / camera[:, 2]
    pixel_y = height / 2 + focal * camera[:, 1] / camera[:, 2]
    image = np.column_stack([pixel_x / width, pixel_y / height, np.ones(N_LANDMARKS)])
    return world, image


MOTION_PERIODS_S = (7.0, 9.0, 11.0, 5.0, 6.0, 4.0, 5.0)
"""Period of each joint's swing in :func:`arm_motion` (s): all different, so the joints pass
through many combinations."""


def arm_motion(t: object, arm: HumanArm) -> np.ndarray:
    """A known, smooth arm motion within ``arm``'s limits: the ground truth of tests and benchmarks.

    The arm reaches forward and up (flexion 0 to 70 degrees), out to the side (abduction 0 to
    40), turns the upper arm (+-17), bends the elbow (11 to 115), turns the forearm (25 to 115)
    and moves the wrist, each joint on its own period (:data:`MOTION_PERIODS_S`); the elbow's
    fastest speed is about 65 degrees per second, a deliberate teaching motion.

    Args:
        t: times (s), any shape.
        arm: the arm whose limits bound the motion.

    Returns:
        ``q_human`` of shape ``t.shape + (7,)``.
    """
    times = real_array(t, "t", "pass times in seconds")
    centre = np.array([0.6, 0.35, 0.0, 1.1, 1.2, 0.0, 0.0])
    swing = np.array([0.6, 0.35, 0.3, 0.9, 0.8, 0.4, 0.3])
    phase = np.array([-math.pi / 2, 1.0, 0.0, 0.5, 0.0, 0.0, 0.0])
    angle = 2 * math.pi * times[..., None] / np.asarray(MOTION_PERIODS_S) + phase
    return np.clip(centre + swing * np.sin(angle), arm.lower, arm.upper)
