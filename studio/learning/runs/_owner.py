"""Who owns a run folder: the process that holds its ``owner.lock``.

A queued or running run is only as alive as the process that will train it. A pid alone cannot
say so: after a crash or a reboot the pid may name an unrelated process, and on another host it
names nothing here. So the process that creates a run holds an advisory ``flock`` on
``<run>/owner.lock`` from the moment the folder appears until its status leaves ``queued`` or
``running``. The kernel drops the lock when that process ends, however it ends (``kill -9``, a
crash, a reboot), so any other process, a second studio on the same data folder included, reads
liveness from the lock and never has to guess, or rewrite the status.

Run folders written before owners locked have no ``owner.lock``; they are judged by their pid,
checked against the process's start time (:func:`process_started`), on their own host
(:func:`pid_alive`, :func:`this_host`).
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import socket
import stat
import sys
import time
from datetime import datetime
from pathlib import Path
from typing import cast

from ..._numbers import is_int
from .._errors import LearningError

OWNER_FILE = "owner.lock"
"""The file in a run folder whose ``flock`` the owning process holds while the run is queued or
running (empty; its content means nothing)."""
LOCK_RETRIES = 20
"""How many times taking a free owner lock is tried again while a reader's probe holds it."""


class OwnerLock:
    """The ``flock`` on ``<folder>/owner.lock`` that makes this process the run's owner.

    Args:
        folder: the run folder (the lock file is created in it if missing).

    Raises:
        LearningError: a live process owns the run already, or the lock cannot be taken.
    """

    def __init__(self, folder: Path) -> None:
        path = Path(folder) / OWNER_FILE
        flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
        try:
            self._fd: int | None = os.open(path, flags, 0o644)
        except OSError as err:
            raise LearningError(
                f"Cannot lock {path} ({err.strerror}); check the run folder's permissions."
            ) from None
        for _ in range(LOCK_RETRIES):  # a reader's probe holds it for microseconds
            try:
                fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                return
            except BlockingIOError:
                time.sleep(0.005)
        self.release()
        raise LearningError(
            f"Run {Path(folder).name} is owned by another live process (it holds {OWNER_FILE}); stop it there first."
        )

    @property
    def held(self) -> bool:
        """Whether this object still holds the lock."""
        return self._fd is not None

    def release(self) -> None:
        """Let the lock go (idempotent); other processes then read the run as not alive."""
        fd, self._fd = self._fd, None
        if fd is not None:
            with contextlib.suppress(OSError):
                os.close(fd)

    def __del__(self) -> None:
        self.release()


def owner_alive(folder: Path) -> bool | None:
    """Whether a live process owns the run in ``folder``: True or False from its ``owner.lock``,
    None when there is no lock file (a folder written before owners locked). A lock file that is
    a link or not a regular file counts as held by nobody."""
    path = Path(folder) / OWNER_FILE
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        return None
    except OSError:  # a link (ELOOP), unreadable: nobody can be holding it for the run
        return False
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return False
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            return True
        return False
    finally:
        os.close(fd)


def process_started(pid: int) -> float | None:
    """When process ``pid`` started (Unix time), or None where that cannot be read.

    A run records its pid and when it started; a live process with that pid that started later
    is another process that reused the pid (after a crash or a reboot).
    """
    try:
        with open(f"/proc/{int(pid)}/stat", "rb") as f:
            fields = f.read().rsplit(b")", 1)[1].split()
        ticks = int(fields[19])  # field 22, starttime, counted from the ')' after the name
        with open("/proc/stat", "rb") as f:
            boot = next(int(line.split()[1]) for line in f if line.startswith(b"btime"))
    except (OSError, ValueError, IndexError, StopIteration):
        return None
    return boot + ticks / os.sysconf("SC_CLK_TCK")


def this_host() -> dict[str, str | None]:
    """Where this process runs, recorded beside every ``pid`` a run or a sweep writes (a pid names
    a process only on its own host): ``hostname``, and ``node``, the Ray node id when this process
    is part of a Ray cluster (a sweep's driver or worker), else None. Ray is never imported here."""
    ray = sys.modules.get("ray")
    node = None
    if ray is not None and ray.is_initialized():
        node = ray.get_runtime_context().get_node_id()
    return {"hostname": socket.gethostname(), "node": node}


def on_this_host(host: object) -> bool:
    """Whether a record's ``host`` (:func:`this_host`) is this machine; a record without one (older
    runs, written before hosts were recorded) counts as this machine's."""
    hostname = host.get("hostname") if isinstance(host, dict) else None
    return not isinstance(hostname, str) or hostname == socket.gethostname()


def pid_alive(pid: object, host: object = None, started: object = None) -> bool:
    """Whether ``pid`` is a live process other than this one: a run or sweep whose status says
    it is training but whose process is gone (a crash, ``kill -9``) reads as stopped.

    ``host`` is the record's :func:`this_host`. A pid recorded on another host (a sweep's trial
    on another node of a cluster, seen through shared storage) names no process here, so this
    host cannot judge it: it counts as alive (its driver records a trial whose worker died).
    ``started`` is when the record says its process started the work (ISO 8601): a live process
    with that pid that started later reused the pid after the recorded one ended.
    """
    if not is_int(pid) or cast(int, pid) <= 0:
        return False
    pid = int(cast(int, pid))
    if not on_this_host(host):
        return True
    if pid == os.getpid():  # this process's only trainer, the page's queue, never reloads its own
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass
    return not _started_after(pid, started)


PID_CLOCK_SLACK_SECONDS = 2.0
"""How much later than a record's ``started`` (kept to the second) its process may seem to have
started before the pid counts as reused."""


def _started_after(pid: int, started: object) -> bool:
    """Whether process ``pid`` started after the ISO time ``started`` (unknown: False)."""
    if not isinstance(started, str):
        return False
    try:
        when = datetime.fromisoformat(started).timestamp()
    except ValueError:
        return False
    began = process_started(pid)
    return began is not None and began > when + PID_CLOCK_SLACK_SECONDS
