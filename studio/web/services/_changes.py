"""How the lists the page shows announce that they changed: one version number per list.

Every list's owner (the folder stores, the live capture, the run queue) is handed
:meth:`ListChanges.announce` as its ``on_change`` and calls it with the list's name whenever the
list changes; nothing else announces. The event stream compares versions, so a slow or vanished
client never holds anything up.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

LIST_NAMES = ("recordings", "demonstrations", "runs", "policies")
"""The lists whose changes are announced, by name."""

OnChange = Callable[[str], None]
"""Called with a list's name (one of :data:`LIST_NAMES`) when that list changed."""


class ListChanges:
    """A version number per list (recordings, demonstrations, runs, policies)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._versions = dict.fromkeys(LIST_NAMES, 0)

    def announce(self, name: str) -> None:
        """Record that list ``name`` changed."""
        with self._lock:
            self._versions[name] += 1

    def versions(self) -> dict[str, int]:
        """The current versions."""
        with self._lock:
            return dict(self._versions)
