"""Recording in takes: start a take, stop it, review it on the robot, keep or redo it, and make
the kept takes of a session into demonstrations in one go.

Each take is an ordinary capture (:meth:`Capture.start`); each kept take becomes a
demonstration through :meth:`Demonstrations.cut`, the one cutting there is. The sessions
persist in ``recordings/takes.json`` (:func:`studio.capture.read_takes`).
"""

from __future__ import annotations

import threading
from datetime import UTC, datetime
from pathlib import Path

from studio._errors import StudioError
from studio._files import now_iso
from studio.capture import TAKES_FILE, Take, TakeSession, read_takes, write_takes

from .._errors import ConflictError
from ._capture import Capture
from ._demonstrations import Demonstrations
from ._review import Reviewer
from ._store import RecordingStore


class TakeFlow:
    """The take session of a studio (one at a time), kept in its data folder's takes file."""

    def __init__(
        self,
        folder: Path,
        recordings: RecordingStore,
        capture: Capture,
        demonstrations: Demonstrations,
        reviewer: Reviewer,
    ) -> None:
        self.recordings = recordings
        self.capture = capture
        self.demonstrations = demonstrations
        self.reviewer = reviewer
        self.path = folder / TAKES_FILE
        self._lock = threading.Lock()

    def _sessions(self) -> list[TakeSession]:
        return read_takes(self.path)

    def session(self) -> TakeSession | None:
        """The open session (None when every session was made into demonstrations)."""
        with self._lock:
            return _open(self._sessions())

    def start(self, operator: str | None = None) -> TakeSession:
        """Start the next take (409 while one is being recorded or waits to be kept or redone)."""
        with self._lock:
            sessions = self._sessions()
            session = _open(sessions)
            if session is None:
                session = TakeSession(started=now_iso())
                sessions.append(session)
            last = session.takes[-1] if session.takes else None
            if last is not None and last.state != "kept":
                raise ConflictError(
                    f"Take {last.recording} is still {'being recorded' if last.state == 'recording' else 'under review'}; stop it, then keep or redo it."
                )
            base = f"take-{datetime.now(UTC):%Y%m%d-%H%M%S}-{len(session.takes) + 1}"
            name = self.capture.start(self.recordings.new_name(base), operator, None)
            session.takes.append(Take(recording=name))
            write_takes(self.path, sessions)
            return session

    def _not_elsewhere(self, take: Take) -> None:
        """Refuse a take another studio on this data folder is recording (its own Stop ends it;
        stopped here, its recording would go on under a take made into demonstrations)."""
        if self.recordings.captured_elsewhere(take.recording):
            raise ConflictError(
                f"Take {take.recording} is being recorded by another studio on this data folder; "
                "stop, keep or redo it in that studio."
            )

    def stop(self) -> TakeSession:
        """Stop the take being recorded and play it on the robot for review."""
        with self._lock:
            sessions = self._sessions()
            take = _last(sessions, "recording", "No take is being recorded; start a take first.")
            self._not_elsewhere(take)
            if self.capture.recording == take.recording:
                self.capture.stop()
            take.state = "review"
            write_takes(self.path, sessions)
            session = _open(sessions)
        self.review()
        assert session is not None
        return session

    def review(self) -> None:
        """Play the last take again: its tool path drawn and the robot moving along it."""
        session = self.session()
        if session is None or not session.takes or session.takes[-1].state == "recording":
            raise ConflictError("There is no stopped take to review; record a take first.")
        self.reviewer.play(session.takes[-1].recording)

    def keep(self) -> TakeSession:
        """Keep the take under review."""
        with self._lock:
            sessions = self._sessions()
            _last(
                sessions, "review", "No take waits for review; record a take first."
            ).state = "kept"
            write_takes(self.path, sessions)
            session = _open(sessions)
            assert session is not None
            return session

    def redo(self) -> TakeSession:
        """Throw the last take away (its recording is deleted), stopping it first if it runs."""
        with self._lock:
            sessions = self._sessions()
            session = _open(sessions)
            if session is None or not session.takes or session.takes[-1].state == "kept":
                raise ConflictError("No take to redo: the last take is kept; start a new take.")
            take = session.takes[-1]
            self._not_elsewhere(take)
            if self.capture.recording == take.recording:
                self.capture.stop()
            self.recordings.delete(take.recording)
            session.takes.pop()
            write_takes(self.path, sessions)
            return session

    def make_demonstrations(self, goal_from_end: bool) -> TakeSession:
        """Cut each kept take, whole, into a demonstration and close the session.

        A take that cannot be cut keeps the reason in ``error`` (its recording stays, to be cut
        by hand on its timeline); the others become demonstrations all the same.
        """
        with self._lock:
            sessions = self._sessions()
            session = _open(sessions)
            if session is None or not session.takes:
                raise ConflictError(
                    "There are no takes to make demonstrations of; record takes first."
                )
            if session.takes[-1].state != "kept":
                raise ConflictError(
                    f"Take {session.takes[-1].recording} is not kept yet; keep or redo it first."
                )
            for take in session.takes:
                if take.demonstration is not None:
                    continue
                try:
                    entry = self.recordings.entry(take.recording)
                    duration = float((entry.value or {}).get("duration", 0.0))
                    take.demonstration = self.demonstrations.cut(
                        take.recording, 0.0, duration, goal_from_end
                    )
                    take.error = None
                except StudioError as err:
                    take.error = str(err)
            session.finished = now_iso()
            write_takes(self.path, sessions)
            return session


def _open(sessions: list[TakeSession]) -> TakeSession | None:
    return sessions[-1] if sessions and sessions[-1].finished is None else None


def _last(sessions: list[TakeSession], state: str, missing: str) -> Take:
    session = _open(sessions)
    if session is None or not session.takes or session.takes[-1].state != state:
        raise ConflictError(missing)
    return session.takes[-1]
