"""MediaPipe Pose landmarks of a known arm pose: the ground truth for the landmark fit.

:func:`landmarks_from_arm` places a simple body (shoulders, hips, a face, the other arm hanging,
legs) around :class:`HumanArm`'s forward kinematics of one arm, turns it into MediaPipe's world
axes (hip-centred, x toward the image's right, y down, z away from the camera, the person facing
the camera) and projects it through a pinhole camera into normalised image landmarks. Tests,
benchmarks and simulated camera sources use it, so the fit is judged against the studio's own arm
model, at any limb lengths the caller's arm has.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._checks import instance_of, positive_number, real_array
from ._errors import KinematicsError
from ._human import HumanArm
from ._pose import HIPS, LANDMARKS, N_LANDMARKS

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
