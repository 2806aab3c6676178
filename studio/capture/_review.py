"""A recording reviewed: its joints over time for a timeline, the segments its trigger marked,
and the takes file of a session.

The timeline holds the human arm's joints and the robot's, and what the recording itself holds
(its :class:`Signal` groups). Every kind of recording (tape, pose landmarks, hand poses) goes
through its own fitter (:func:`~studio.capture.fitter_for`,
:func:`~studio.capture._fitters.fit_frames`: camera landmarks smoothed with the future, as
demonstration extraction does), so the timeline shows the joints a demonstration cut from it
would hold. Beside them come the observations as recorded: a tape's bend and twist per region, a
camera's visibility of the arm's landmarks, a hand guide's hand position.

Segments an operator marked live (:func:`trigger_segments`): the ShapeTape has a trigger and two
switches; holding the trigger during a demonstration marks its start and stop in the recording
itself, with no one at the keyboard. The simulator holds it during :meth:`SimulatorSource.reach`.

Recording in takes: the file ``recordings/takes.json`` keeps each session's takes. A session is a
run of takes recorded one after another (LeRobot's recording loop: record, review, keep or redo,
next). Each take is a recording of its own; the file says which were kept and, once the session
is made into demonstrations, which demonstration each became. Its format is in
``recordings/README.md`` ("Takes").
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from studio._files import atomic_write_text
from studio._json import read_json

from ._errors import RecordingError
from ._fitters import ARM_LANDMARKS, fit_frames, fitter_for
from ._observation_recording import ObservationRecording, read_any_recording
from ._observations import TRIGGER_BIT
from ._recording_reader import Recording

DEFAULT_SERIES_POINTS = 400
"""How many samples a timeline gets by default: one per pixel of a wide panel, or fewer."""
MAX_SERIES_POINTS = 5000
"""The most samples a timeline may ask for."""


@dataclass(frozen=True)
class Signal:
    """One group of a recording's own values over time, as a timeline plots them together.

    Attributes:
        name: what it is (``"tape bend"``, ``"tape twist"``, ``"landmark visibility"``,
            ``"hand position"``).
        unit: the values' unit (``"deg"``, ``"0-1"``, ``"cm"``).
        labels: one per column (``"region 1"``, ``"shoulder"``, ``"x"``).
        values: ``(N, len(labels))`` at the series' times; NaN where the frame has none (a camera
            frame without a person).
    """

    name: str
    unit: str
    labels: tuple[str, ...]
    values: np.ndarray


def recording_signals(
    rec: Recording | ObservationRecording, rows: np.ndarray
) -> tuple[Signal, ...]:
    """The recording's own values at frames ``rows``: a tape's bend and twist per region
    (degrees), a camera's visibility of the teaching arm's shoulder, elbow and wrist (0-1), or a
    hand guide's hand position in the arm's frame (cm)."""
    rows = np.asarray(rows, dtype=np.int64)
    if isinstance(rec, Recording):
        labels = tuple(f"region {i + 1}" for i in range(rec.regions))
        return (
            Signal("tape bend", "deg", labels, np.degrees(rec.bend[rows])),
            Signal("tape twist", "deg", labels, np.degrees(rec.twist[rows])),
        )
    frames = [rec.frame_at(int(row)) for row in rows]
    if rec.kind_name == "pose":
        marks = ARM_LANDMARKS[rec.side]
        values = np.full((len(rows), len(marks)), np.nan)
        for i, frame in enumerate(frames):
            if frame.world is not None:  # type: ignore[union-attr]
                values[i] = frame.world[list(marks), 3]  # type: ignore[union-attr]
        labels = ("shoulder", "elbow", "wrist")
        return (Signal("landmark visibility", "0-1", labels, values),)
    position = np.array([f.position for f in frames]).reshape(len(rows), 3)  # type: ignore[union-attr]
    return (Signal("hand position", "cm", ("x", "y", "z"), position * 100.0),)


@dataclass(frozen=True)
class RecordingSeries:
    """A recording's joints at evenly spaced frames.

    Attributes:
        times: seconds after the recording's first frame ``(N,)``.
        q_human: the human arm's joints ``(N, 7)``, rad.
        q_robot: the Puma560's joints ``(N, 6)``, rad.
        residual: how far the fitted arm misses each observation ``(N,)``, m.
        duration: the whole recording's length, s.
        kind: ``"tape"``, ``"pose"`` or ``"hand"``.
        signals: the recording's own values at the same times (:func:`recording_signals`).
        frames: the recording's frame index of each sample ``(N,)`` (how many frames lie
            between two samples: a robot path retargeted from ``q_human`` moves that many
            frames' worth between them).
        side: the teaching arm, whose convention ``q_human`` is in.
    """

    times: np.ndarray
    q_human: np.ndarray
    q_robot: np.ndarray
    residual: np.ndarray
    duration: float
    kind: str
    signals: tuple[Signal, ...] = ()
    frames: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    side: str = "right"


def human_angles(
    recording: Recording | ObservationRecording, rows: slice | np.ndarray
) -> np.ndarray:
    """The human arm's angles ``(N, 7)`` at ``rows`` of a recording (a slice, or row indices in
    order), each frame fitted by the recording's own fitter seeded by the frame before
    (:func:`~studio.capture._fitters.fit_frames`: camera landmarks smoothed with the future too), ready to
    be retargeted onto any robot.
    """
    indices = range(*rows.indices(len(recording))) if isinstance(rows, slice) else rows
    if not len(indices):
        return np.zeros((0, 7))
    first = recording.frame_at(int(indices[0]))
    if isinstance(recording, Recording):
        fitter = fitter_for(first, tape=recording.config)
    else:
        fitter = fitter_for(first, side=recording.side)
    frames = [recording.frame_at(int(i)) for i in indices]
    return np.array([fitted.q_human for fitted in fit_frames(fitter, frames)])


def recording_series(
    recording: Recording | ObservationRecording | str | os.PathLike[str],
    points: int = DEFAULT_SERIES_POINTS,
    t0: float | None = None,
    t1: float | None = None,
    mode: str = "joint",
) -> RecordingSeries:
    """The joints of ``[t0, t1]`` (the whole recording by default) at about ``points`` frames.

    Frames are taken at an even stride and fitted in order, each fit seeded by the one before,
    so a long recording costs ``points`` fits, not one per frame.

    Args:
        recording: a recording of any kind, or its path.
        points: how many frames at most (1 to :data:`MAX_SERIES_POINTS`).
        t0: start, s after the first frame (default 0).
        t1: end, s after the first frame (default the end).
        mode: retargeting mode, ``"joint"`` or ``"cartesian"``.
    """
    rec = (
        recording
        if isinstance(recording, Recording | ObservationRecording)
        else read_any_recording(recording)
    )
    points = max(1, min(int(points), MAX_SERIES_POINTS))
    start, stop, _ = rec.segment(
        0.0 if t0 is None else t0, rec.duration if t1 is None else t1
    ).indices(len(rec))
    rows = np.unique(np.linspace(start, stop - 1, min(points, stop - start)).round().astype(int))
    rows = rows[(rows >= start) & (rows < stop)]
    q_human = np.zeros((len(rows), 7))
    q_robot = np.zeros((len(rows), 6))
    residual = np.zeros(len(rows))
    if len(rows):
        first = rec.frame_at(int(rows[0]))
        tape = rec.config if isinstance(rec, Recording) else None
        fitter = fitter_for(first, tape=tape, side=rec.side, mode=mode)
        frames = [first, *(rec.frame_at(int(row)) for row in rows[1:])]
        for i, fitted in enumerate(fit_frames(fitter, frames)):
            q_human[i], q_robot[i], residual[i] = fitted.q_human, fitted.q_robot, fitted.residual
    origin = float(rec.t[0]) if len(rec) else 0.0
    return RecordingSeries(
        times=rec.t[rows] - origin,
        q_human=q_human,
        q_robot=q_robot,
        residual=residual,
        duration=rec.duration,
        kind=rec.kind_name,
        signals=recording_signals(rec, rows),
        frames=rows,
        side=rec.side,
    )


def trigger_segments(recording: Recording, bit: int = TRIGGER_BIT) -> list[tuple[float, float]]:
    """``[(t0, t1), ...]`` (seconds from the first frame) of every run of frames with ``bit`` set.

    Args:
        recording: the recording.
        bit: the status bit that marks a segment (default: the trigger).

    Returns:
        The segments in order, ready for :func:`extract_demonstration`.
    """
    if len(recording) == 0:
        return []
    on = (recording.status & bit) != 0
    edges = np.diff(np.concatenate([[False], on, [False]]).astype(np.int8))
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1) - 1
    t = recording.t - recording.t[0]
    return [(float(t[a]), float(t[b])) for a, b in zip(starts, ends, strict=True)]


TAKES_FILE = "takes.json"
"""The takes file's name in a data folder's ``recordings/``."""
TAKES_FORMAT = "teach-studio-takes"
TAKES_VERSION = 1
TAKE_STATES = ("recording", "review", "kept")
"""A take is being recorded, waits to be kept or redone, or is kept."""


@dataclass
class Take:
    """One take of a session.

    Attributes:
        recording: the recording's name (``recordings/<name>.tape.csv`` or ``.pose.csv``/``.hand.csv``).
        state: one of :data:`TAKE_STATES`.
        demonstration: the demonstration cut from it, once the session is made into demonstrations.
        error: why it could not be cut (one sentence), if it could not.
    """

    recording: str
    state: str = "recording"
    demonstration: str | None = None
    error: str | None = None


@dataclass
class TakeSession:
    """Takes recorded one after another; ``finished`` is set once they became demonstrations."""

    started: str
    takes: list[Take] = field(default_factory=list)
    finished: str | None = None


def read_takes(path: str | os.PathLike[str]) -> list[TakeSession]:
    """Every session in a takes file, oldest first (none when the file does not exist yet).

    Raises:
        RecordingError: the file is damaged (one sentence naming it and the fix).
    """
    path = Path(path)
    if not path.exists():
        return []
    data = read_json(path, f"the takes file {path}")
    fix = f"fix it or move it aside (the recordings themselves are untouched): {path}"
    if not (isinstance(data, dict) and data.get("format") == TAKES_FORMAT):
        raise RecordingError(f"The takes file is not a {TAKES_FORMAT} file; {fix}.")
    if data.get("version") != TAKES_VERSION:
        raise RecordingError(
            f"The takes file has version {data.get('version')!r}; this studio reads version {TAKES_VERSION}. Update the studio, or {fix}."
        )
    try:
        return [
            TakeSession(
                started=str(s["started"]),
                finished=None if s.get("finished") is None else str(s["finished"]),
                takes=[_take(t) for t in s["takes"]],
            )
            for s in data["sessions"]
        ]
    except (KeyError, TypeError, ValueError) as err:
        raise RecordingError(f"The takes file has a malformed session ({err}); {fix}.") from None


def _take(raw: dict[str, object]) -> Take:
    take = Take(
        recording=str(raw["recording"]),
        state=str(raw["state"]),
        demonstration=None if raw.get("demonstration") is None else str(raw["demonstration"]),
        error=None if raw.get("error") is None else str(raw["error"]),
    )
    if take.state not in TAKE_STATES:
        raise ValueError(f"take state {take.state!r}")
    return take


def write_takes(path: str | os.PathLike[str], sessions: list[TakeSession]) -> Path:
    """Write every session to the takes file (an atomic replace)."""
    data = {
        "format": TAKES_FORMAT,
        "version": TAKES_VERSION,
        "sessions": [asdict(s) for s in sessions],
    }
    return atomic_write_text(path, json.dumps(data, indent=1) + "\n")
