"""Sources fed from outside: the camera (landmarks from the page) and the hand guide (a pose
dragged in the scene).

They have no device and no producer thread: each observation is handed in by a call
(:meth:`CameraSource.submit`, :meth:`HandSource.submit`), checked (one sentence for NaN, wrong
sizes), counted towards ``frames`` and ``rate_hz`` like a device's frames, and returned for the
caller to fit and record at once, so the answer can say what the fit made of it. A flood (more
than :data:`MAX_OBSERVATIONS_PER_SECOND` in one second) is refused with :class:`FloodError` and
counted as dropped: the studio, and a recording in progress, carry on.

Each page stamps its frames by its own clock and names itself (``sender``, an id it picks once
per load). One page at a time sends: a frame from another page (a second tab with the camera) is
refused with :class:`SecondSenderError` while the live one sends; once that one has been quiet for
:data:`SENDER_QUIET_S` (closed, reloaded), the next page takes over, its times continuing by the
studio's own clock across the gap. So a recording's time is never a difference of two clocks. A
client that sends no id is told apart by its clock instead: a frame whose time does not run with
the live sender's (within :data:`CLOCK_TOLERANCE_S`) is another's. The page names itself because
its frames' times are the camera's capture times: while a busy machine takes a second or more to
estimate one frame and not the next, its own clock would seem to jump.
"""

from __future__ import annotations

import collections
import threading
import time
from typing import TypeVar

import numpy as np
import viser.transforms as vtf

from ._errors import CaptureError
from ._observations import (
    HUMAN_JOINTS,
    HandPose,
    LandmarkFrame,
    hand_pose,
    landmark_frame,
)
from ._source import ThreadedSource

FedT = TypeVar("FedT", LandmarkFrame, HandPose)
"""What a fed source takes: landmark frames (the camera) or hand poses (the hand guide)."""

MAX_OBSERVATIONS_PER_SECOND = 120
"""Most observations a fed source takes in one second (4x a 30 Hz camera, 2x the scene's 60 Hz
handle updates); more are refused as a flood."""
RESTART_STEP_S = 1.0 / 30.0
"""When a page's clock goes back (a reload), its times continue this long after the last one."""
SENDER_QUIET_S = 1.0
"""A page that sent no frame for this long is gone (closed, reloaded): another may take over."""
CLOCK_TOLERANCE_S = 1.0
"""How far a frame's time may stray from the live page's clock (as the studio's clock measures
the time between their arrivals) and still be that page's: a page's own delays are far shorter,
while two pages' clocks differ by the time between their openings."""
MODELS = ("lite", "full", "heavy")
"""BlazePose models the page may report."""


class FloodError(CaptureError):
    """More observations in one second than a fed source takes (the API answers 429)."""


class SecondSenderError(CaptureError):
    """A frame from a second page while another one sends (the API answers 409)."""


class PushSource(ThreadedSource[FedT]):
    """A source whose observations are handed in by calls (no producer thread, no queue).

    Args:
        side: the teaching arm, ``"right"`` or ``"left"``.

    Raises:
        CaptureError: a side that is neither.
    """

    kind = "push"
    observation_kind = "tape"

    def __init__(self, side: str = "right") -> None:
        if side not in ("right", "left"):
            raise CaptureError(f"side is {side!r}; give 'right' or 'left'.")
        super().__init__(1)
        self.side = side
        self._started = False
        self._counter = 0
        self._last_t: float | None = None
        self._offset = 0.0
        # the live page: (its last time, that frame's arrival, its id or None)
        self._sender: tuple[float, float, str | None] | None = None
        self._admitted: collections.deque[float] = collections.deque(
            maxlen=MAX_OBSERVATIONS_PER_SECOND
        )
        self._admit_lock = threading.Lock()

    def start(self) -> None:
        """Take observations from now on."""
        self._started = True

    def stop(self) -> None:
        """Refuse further observations."""
        self._started = False

    @property
    def running(self) -> bool:
        """Whether the source takes observations."""
        return self._started

    def read(self, timeout: float | None = 0.0) -> list[FedT]:
        """Nothing: a fed source hands its observations to the caller of ``submit``."""
        if timeout:
            self._stop_event.wait(min(timeout, 0.05))
        return []

    def _admit(self) -> tuple[int, float]:
        """Count one observation in (its counter), or refuse a flood.

        Raises:
            CaptureError: the source is stopped.
            FloodError: more than :data:`MAX_OBSERVATIONS_PER_SECOND` in the last second.
        """
        if not self._started:
            raise CaptureError(f"The {self.kind} source is stopped; select it again.")
        now = time.monotonic()
        with self._admit_lock:
            if len(self._admitted) == self._admitted.maxlen and now - self._admitted[0] < 1.0:
                self._count_dropped()
                raise FloodError(
                    f"More than {MAX_OBSERVATIONS_PER_SECOND} {self.observation_kind} updates in one second; send at most one per camera frame or handle move (this one was dropped)."
                )
            self._admitted.append(now)
            counter = self._counter
            self._counter += 1
        self._record_arrival()
        return counter, now

    @staticmethod
    def _same_sender(
        live: tuple[float, float, str | None], t: float, now: float, sender: str | None
    ) -> bool:
        """Whether a frame (its time ``t``, arrival ``now`` and id) is the ``live`` page's: by
        their ids when both have one, else by their clocks."""
        last_t, arrived, live_id = live
        if sender is not None and live_id is not None:
            return sender == live_id
        return abs(t - (last_t + now - arrived)) <= CLOCK_TOLERANCE_S

    def _check_sender(self, t: float, now: float, sender: str | None = None) -> None:
        """Refuse a frame from another page than the live one (see the module docstring).

        Raises:
            SecondSenderError: another page sent within the last :data:`SENDER_QUIET_S`.
        """
        with self._admit_lock:
            live = self._sender
            if live is None or now - live[1] > SENDER_QUIET_S:
                return
            if not self._same_sender(live, t, now, sender):
                raise SecondSenderError(
                    f"Another page is sending {self.observation_kind} frames to this studio "
                    "already; close the other tab (or stop its camera), then start the camera "
                    "here again."
                )

    def _stream_time(self, t: float, now: float | None = None, sender: str | None = None) -> float:
        """``t`` on a clock that always moves forward: a page that takes over from another
        (a reload) continues after the last time by the studio's own clock; a repeated time
        stamp moves on too, as the landmark filter needs."""
        now = time.monotonic() if now is None else now
        with self._admit_lock:
            live = self._sender
            if (
                live is not None
                and self._last_t is not None
                and not self._same_sender(live, t, now, sender)
            ):  # a new page: its time continues by the studio's clock
                self._offset = self._last_t + max(now - live[1], RESTART_STEP_S) - t
            if self._last_t is not None and t + self._offset <= self._last_t:
                self._offset = self._last_t + RESTART_STEP_S - t
            self._sender = (t, now, sender)
            self._last_t = t + self._offset
            return self._last_t


class CameraSource(PushSource[LandmarkFrame]):
    """Landmark frames estimated in the page (BlazePose), handed in by ``POST
    /api/source/landmarks``.

    Attributes:
        side: the teaching arm.
        person_detected: whether the last frame saw a person (None before the first).
        camera_fps: the frame rate the page reported last.
        model: the BlazePose model the page reported last.
    """

    kind = "camera"
    observation_kind = "pose"

    def __init__(self, side: str = "right") -> None:
        super().__init__(side)
        self.person_detected: bool | None = None
        self.camera_fps: float | None = None
        self.model: str | None = None

    def submit(
        self,
        t: float,
        world: object,
        image: object,
        width: object,
        height: object,
        fps: float | None = None,
        model: str | None = None,
        sender: str | None = None,
    ) -> LandmarkFrame:
        """Check and count one frame of landmarks; returns it for the caller to fit and record.
        ``sender`` is the page's id (None: the page is told apart by its clock).

        Raises:
            CaptureError: bad landmarks (NaN, wrong sizes, bad image size or time).
            FloodError: a flood.
        """
        frame = landmark_frame(t, 0, world, image, width, height)  # checked before it counts
        if fps is not None and not (isinstance(fps, int | float) and 0 <= fps <= 1000):
            raise CaptureError(f"fps is {fps!r}; send the page's frame rate (0 to 1000) or null.")
        if model is not None and model not in MODELS:
            raise CaptureError(f"model is {model!r}; send one of {', '.join(MODELS)} or null.")
        if sender is not None and not (isinstance(sender, str) and 0 < len(sender) <= 64):
            raise CaptureError(
                f"sender is {sender!r}; send the page's id (1 to 64 characters) or null."
            )
        self._check_sender(frame.t, time.monotonic(), sender)
        counter, now = self._admit()
        self.person_detected = frame.person
        self.camera_fps = None if fps is None else float(fps)
        self.model = model
        return LandmarkFrame(
            self._stream_time(frame.t, now, sender),
            counter,
            frame.world,
            frame.image,
            frame.width,
            frame.height,
        )


class HandSource(PushSource[HandPose]):
    """Hand poses from the scene's handle (or ``POST /api/source/hand``): the hand guide.

    Attributes:
        side: the teaching arm.
        wxyz: the hand's last orientation (kept when an update gives only a position).
    """

    kind = "hand"
    observation_kind = "hand"

    def __init__(self, side: str = "right") -> None:
        super().__init__(side)
        from studio.kinematics import HumanArm

        rest = HumanArm(side=side).forward(np.zeros(HUMAN_JOINTS)).hand  # the hanging hand
        self.wxyz = vtf.SO3.from_matrix(rest[:3, :3]).wxyz
        self._t0 = time.monotonic()

    def submit(self, position: object, wxyz: object | None = None) -> HandPose:
        """Check and count one hand pose (``wxyz`` None keeps the last orientation).

        Raises:
            CaptureError: NaN, wrong sizes or a zero quaternion.
            FloodError: a flood.
        """
        pose = hand_pose(0.0, 0, position, self.wxyz if wxyz is None else wxyz)
        counter, now = self._admit()
        self.wxyz = pose.wxyz
        return HandPose(now - self._t0, counter, pose.position, pose.wxyz)
