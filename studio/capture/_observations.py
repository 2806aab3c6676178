"""Observations of the operator's arm: tape frames, pose landmarks and hand poses.

Every teacher yields observations with a time ``t`` (s) and a counter ``frame``, so everything
downstream is source-agnostic; each kind has its own fitter into the 7-joint human arm
(:mod:`._fitters`) and its own recording format (:mod:`._recording_format`):

- :class:`TapeFrame`: one sample of the ShapeTape (bend and twist per region, and its switch and
  trigger bits);
- :class:`LandmarkFrame`: one frame of MediaPipe Pose estimated in the page (33 world and 33
  image landmarks, the image's size), or a frame in which no person was seen;
- :class:`HandPose`: one pose of the operator's hand, dragged in the scene (the hand guide).

The constructors :func:`landmark_frame` and :func:`hand_pose` check what a page or a script sends
and refuse bad input with one sentence (:class:`CaptureError`); a recording reader builds them
from rows it has checked itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from ._errors import CaptureError

SWITCH0_BIT = 1 << 4
"""Status bit of switch 0 (ShapeTape status byte, bit 4)."""
TRIGGER_BIT = 1 << 5
"""Status bit of the trigger (bit 5)."""
SWITCH1_BIT = 1 << 6
"""Status bit of switch 1 (bit 6)."""
STATUS_BITS_MASK = SWITCH0_BIT | TRIGGER_BIT | SWITCH1_BIT
"""The status bits a frame keeps (the group count, bits 0-2, is the device's framing only)."""


@dataclass(frozen=True, slots=True, eq=False)
class TapeFrame:
    """One sample of the tape.

    Args:
        t: time in seconds since the source started (the device's clock when it has one).
        frame: the frame counter (consecutive from the source; gaps mean lost frames).
        bend: bend angle per region in radians, shape ``(regions,)``.
        twist: twist angle per region in radians, shape ``(regions,)``.
        status: the device's switch/trigger bits (:data:`SWITCH0_BIT`, ...).
    """

    t: float
    frame: int
    bend: np.ndarray
    twist: np.ndarray
    status: int = 0

    @property
    def regions(self) -> int:
        """Number of bend/twist regions."""
        return int(self.bend.shape[0])

    @property
    def switch0(self) -> bool:
        """Whether switch 0 is pressed."""
        return bool(self.status & SWITCH0_BIT)

    @property
    def trigger(self) -> bool:
        """Whether the trigger is pressed."""
        return bool(self.status & TRIGGER_BIT)

    @property
    def switch1(self) -> bool:
        """Whether switch 1 is pressed."""
        return bool(self.status & SWITCH1_BIT)

    def same_as(self, other: TapeFrame) -> bool:
        """Whether two frames hold exactly the same values (arrays compared element-wise)."""
        return (
            self.t == other.t
            and self.frame == other.frame
            and self.status == other.status
            and np.array_equal(self.bend, other.bend)
            and np.array_equal(self.twist, other.twist)
        )


def make_frame(
    t: float, frame: int, bend: np.ndarray, twist: np.ndarray, status: int = 0
) -> TapeFrame:
    """A :class:`TapeFrame` with its arrays as float64 copies (so no caller can change them later)."""
    return TapeFrame(
        float(t),
        int(frame),
        np.array(bend, dtype=np.float64),
        np.array(twist, dtype=np.float64),
        int(status),
    )


def frames_to_arrays(frames: list[TapeFrame]) -> tuple[np.ndarray, ...]:
    """Stack frames into ``(t (N,), frame (N,), status (N,), bend (N, R), twist (N, R))``."""
    if not frames:
        empty = np.zeros((0, 0))
        return np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), empty, empty
    t = np.fromiter((f.t for f in frames), dtype=np.float64, count=len(frames))
    counter = np.fromiter((f.frame for f in frames), dtype=np.int64, count=len(frames))
    status = np.fromiter((f.status for f in frames), dtype=np.int64, count=len(frames))
    bend = np.stack([f.bend for f in frames])
    twist = np.stack([f.twist for f in frames])
    return t, counter, status, bend, twist


POSE_LANDMARKS = 33
"""Landmarks per MediaPipe Pose (BlazePose) frame."""
WORLD_FIELDS = 4
"""x, y, z (m, hip-centred, x to the image's right, y down, z away from the camera), visibility."""
IMAGE_FIELDS = 3
"""x, y (normalised to the image's width and height), visibility."""
HUMAN_JOINTS = 7
"""Joints of the human arm every observation is fitted into."""
MAX_IMAGE_SIDE = 16384
"""Largest image width or height a landmark frame may state (pixels)."""
MAX_ABS_COORDINATE = 1000.0
"""Largest magnitude of a landmark or hand coordinate (m, or image widths): a sanity bound."""
MAX_OBSERVATION_TIME = 1.0e9
"""Largest time stamp (s) an observation may carry (31 years of page clock)."""


@runtime_checkable
class Observation(Protocol):
    """What every observation kind has: a time and a counter (and its kind's own fields)."""

    @property
    def t(self) -> float:
        """Seconds since the source started."""

    @property
    def frame(self) -> int:
        """Consecutive counter from the source."""


@dataclass(frozen=True, slots=True, eq=False)
class LandmarkFrame:
    """One frame of pose landmarks.

    Args:
        t: time (s, the page's clock for a live camera).
        frame: the counter (consecutive from the source).
        world: ``(33, 4)`` world landmarks and visibility, or None when no person was seen.
        image: ``(33, 3)`` normalised image landmarks and visibility, or None.
        width: the image's width in pixels.
        height: the image's height in pixels.
        observable: which of the 7 arm joints the fit could determine in this frame (set once
            fitted, as recordings keep it), or None before fitting.
    """

    t: float
    frame: int
    world: np.ndarray | None
    image: np.ndarray | None
    width: int
    height: int
    observable: np.ndarray | None = None

    @property
    def person(self) -> bool:
        """Whether a person was seen in this frame."""
        return self.world is not None


@dataclass(frozen=True, slots=True, eq=False)
class HandPose:
    """One pose of the operator's hand (the hand guide's observation).

    Args:
        t: time (s).
        frame: the counter.
        position: ``(3,)`` the hand centre in the operator's arm frame (``HumanArm``'s base frame:
            shoulder at the origin, z up), metres.
        wxyz: ``(4,)`` the hand's orientation in that frame, a unit quaternion.
    """

    t: float
    frame: int
    position: np.ndarray
    wxyz: np.ndarray


def _time(t: object) -> float:
    if isinstance(t, bool) or not isinstance(t, int | float) or not math.isfinite(t):
        raise CaptureError(f"t is {t!r}; send the frame's time in seconds as a finite number.")
    if abs(t) > MAX_OBSERVATION_TIME:
        raise CaptureError(
            f"t is {t:g} s; send the time since the page started (under {MAX_OBSERVATION_TIME:g} s)."
        )
    return float(t)


def _array(value: object, shape: tuple[int, ...], what: str, fix: str) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise CaptureError(f"{what} is not a list of numbers; {fix}.") from None
    if array.shape != shape:
        raise CaptureError(f"{what} has shape {array.shape}, not {shape}; {fix}.")
    if not np.isfinite(array).all():
        raise CaptureError(f"{what} holds NaN or infinite values; {fix}.")
    if np.abs(array).max(initial=0.0) > MAX_ABS_COORDINATE:
        raise CaptureError(f"{what} holds values beyond ±{MAX_ABS_COORDINATE:g}; {fix}.")
    return array


def _pixels(value: object, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_IMAGE_SIDE:
        raise CaptureError(
            f"{what} is {value!r}; send the camera image's {what} in pixels (1 to {MAX_IMAGE_SIDE})."
        )
    return int(value)


def landmark_frame(
    t: object,
    frame: int,
    world: object,
    image: object,
    width: object,
    height: object,
) -> LandmarkFrame:
    """A checked :class:`LandmarkFrame` from what the page sends.

    Args:
        t: the page's time stamp (s).
        frame: the counter the source gives it.
        world: 33 rows of ``[x, y, z, visibility]``, or None when no person is in view.
        image: 33 rows of ``[x, y, visibility]``, or None.
        width: the image's width (pixels).
        height: the image's height (pixels).

    Raises:
        CaptureError: NaN, a wrong size, image landmarks without world ones, or a bad time or
            size (one sentence with the fix).
    """
    fix = "send MediaPipe Pose's 33 landmarks as they come"
    w = None
    if world is not None:
        w = _array(
            world, (POSE_LANDMARKS, WORLD_FIELDS), "world", fix + " ([x, y, z, visibility] each)"
        )
    im = None
    if image is not None:
        if w is None:
            raise CaptureError(
                "image landmarks came without world landmarks; send both, or world: null when no person is in view."
            )
        im = _array(
            image, (POSE_LANDMARKS, IMAGE_FIELDS), "image", fix + " ([x, y, visibility] each)"
        )
    return LandmarkFrame(
        _time(t), int(frame), w, im, _pixels(width, "width"), _pixels(height, "height")
    )


def hand_pose(t: object, frame: int, position: object, wxyz: object) -> HandPose:
    """A checked :class:`HandPose` (the quaternion normalised).

    Raises:
        CaptureError: NaN, a wrong size, or a zero quaternion (one sentence with the fix).
    """
    p = _array(position, (3,), "position", "send the hand's [x, y, z] in metres")
    q = _array(wxyz, (4,), "wxyz", "send the hand's orientation as a quaternion [w, x, y, z]")
    norm = float(np.linalg.norm(q))
    if norm < 1e-9:
        raise CaptureError("wxyz is a zero quaternion; send a rotation, e.g. [1, 0, 0, 0].")
    return HandPose(_time(t), int(frame), p, q / norm)
