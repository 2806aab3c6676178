"""Preparing the learner: its compiled kernels, loaded from numba's disk cache or compiled.

The learners' kernels are numba functions cached on disk (``cache=True``). The first run of a
task on a machine (or after an update of the studio) compiles them, which takes tens of seconds
(:data:`PREPARE_SECONDS`); every later run, in any process, loads them in about a second. So that
such a run does not look stuck, :func:`prepare_learner` compiles them before the first episode
and sets the run's :attr:`LiveProgress.note` meanwhile (:func:`preparing_note`), and
:func:`prepare_in_background` lets a studio compile them at start in a child process
(a child, so the compiler, which holds the GIL, never slows the studio's own threads; one
child per task, so a run waits only for its own task's).

:func:`learner_ready` tells whether a task's kernels are compiled in this process or cached on
disk for this machine, without loading them: from the dispatchers' signatures and numba's cache
index (the entries whose code and CPU match this process's).
"""

from __future__ import annotations

import contextlib
import logging
import os
import subprocess
import sys
import threading
import time

from ._config import TASK_KINDS
from ._learner import LiveProgress
from ._registry import learner

log = logging.getLogger(__name__)

PREPARE_SECONDS = {kind: learner(kind).prepare_seconds for kind in TASK_KINDS}
"""Seconds a task's kernels take to compile, the estimate a first run shows (each learner's
``prepare_seconds``: the CPU seconds ``python benchmarks/bench_prepare.py`` measured, 5.5 s for
the arm grid and 19.7 s for the continuous task on a 2-core x86-64 machine, rounded up, which is
the wall time where nothing else competes for the core; a busy machine takes longer, 38 s and
256 s of wall time at a load average of 26 there)."""
BACKGROUND_NICENESS = 0
"""How much lower the background compilation's CPU priority is (Linux ``nice``): none. It runs in
its own process, so it never holds the studio's GIL; and a first run may wait for it, which must
not put the user behind the machine's other work (measured with ``bench_prepare.py`` at a load
average of 26: a first run waited 157 s for a child at nice 10, against 28 s compiling itself)."""
BACKGROUND_WAIT_SECONDS = 600.0
"""A run waits at most this long for the background compilation before compiling itself."""

_lock = threading.Lock()
_background: tuple[subprocess.Popen | None, str | None] = (None, None)  # child, its task


def _kernels(kind: str) -> list:
    """The task's compiled entry points (their callees are compiled into them)."""
    return learner(kind).kernels()


def _cached_on_disk(dispatcher: object) -> bool:
    """Whether numba's cache index holds a build of this function's current code for this CPU."""
    try:
        cache = dispatcher._cache  # type: ignore[attr-defined]
        probe = cache._index_key(None, dispatcher.targetctx.codegen())  # type: ignore[attr-defined]
        index = cache._cache_file._load_index()  # empty when the source changed since
    except Exception:  # numba's internals moved, an unreadable cache: assume it must compile
        return False
    return any(key[1:] == probe[1:] for key in index)


def learner_ready(kind: str) -> bool:
    """Whether a run of task ``kind`` starts learning at once: its kernels are compiled in this
    process or cached on disk for this machine (else its first run compiles them)."""
    return all(k.signatures or _cached_on_disk(k) for k in _kernels(kind))


def preparing_note(kind: str) -> str:
    """What a run says while its kernels compile (the page's run list, the CLI)."""
    seconds = PREPARE_SECONDS.get(kind, max(PREPARE_SECONDS.values()))
    return f"preparing the learner (first run on this machine, about {seconds:.0f} s)"


def _warm(kind: str) -> None:
    """Compile (or load) every kernel a run of ``kind`` uses, with a one-episode run."""
    learner(kind).warm()


def prepare_learner(kind: str, live: LiveProgress | None = None) -> float:
    """Make a run of task ``kind`` ready to learn; returns the seconds it took (0 when its
    kernels are compiled in this process or cached on disk already).

    When the kernels must be compiled, ``live.note`` says so (:func:`preparing_note`) until they
    are. When the background child (:func:`prepare_in_background`) is compiling this very task,
    the run waits for it, then loads its result; otherwise it compiles here, at once.
    """
    if learner_ready(kind):  # compiled here, or cached: the run loads them in about a second
        return 0.0
    start = time.perf_counter()
    if live is not None:
        live.note = preparing_note(kind)
    try:
        with _lock:
            child, child_kind = _background
        if child is not None and child_kind == kind:
            with contextlib.suppress(subprocess.TimeoutExpired):  # else compile it here
                child.wait(BACKGROUND_WAIT_SECONDS)
        _warm(kind)
    finally:
        if live is not None:
            live.note = None
    seconds = time.perf_counter() - start
    log.info("prepared the %s learner in %.1f s", kind, seconds)
    return seconds


def prepare_in_background() -> threading.Thread | None:
    """Compile the tasks' kernels into the disk cache, one task at a time in a child process,
    unless they are there already; returns the thread that starts the
    children (None when there was nothing to do).

    The arm grid comes first: most first runs are the paper's task. A run of the task being
    compiled waits for its child; a run of another task compiles its own at once.
    """
    kinds = [kind for kind in TASK_KINDS if not learner_ready(kind)]
    if not kinds:
        return None
    thread = threading.Thread(
        target=_compile_children, args=(kinds,), name="studio-prepare", daemon=True
    )
    thread.start()
    return thread


def _compile_children(kinds: list[str]) -> None:
    global _background
    for kind in kinds:
        if learner_ready(kind):  # a run compiled it meanwhile
            continue
        code = f"from studio.learning._prepare import _warm; _warm({kind!r})"
        try:
            child = subprocess.Popen(
                [sys.executable, "-c", code],
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
        except OSError as err:  # no harm: the first run compiles them itself
            log.info("could not prepare the learner in the background: %s", err)
            return
        if BACKGROUND_NICENESS:
            with contextlib.suppress(OSError, AttributeError):
                os.setpriority(os.PRIO_PROCESS, child.pid, BACKGROUND_NICENESS)
        with _lock:
            _background = (child, kind)
        child.wait()
        with _lock:
            _background = (None, None)
