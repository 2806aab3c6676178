"""Shared test set-up.

In CI (``CI=true``) nothing may be skipped for a missing browser or package: :func:`require`
turns such a skip into a failure there.

The suite runs on every core (pytest-xdist, ``-n auto`` in pyproject.toml), handed out by file
(:func:`pytest_xdist_make_scheduler`): a file's tests run on one worker, in order, so its module
fixtures are made once; the browser files on the studio's one shared page (the ``page`` fixture)
go to one worker together, as one visit, so that one studio and one live page serve them all.
Before the workers start, :func:`pytest_configure` compiles the learners' and the arm IK's numba
kernels into numba's disk cache (the studio's own start-up preparation), so the workers load them
instead of each compiling the same kernels at once. Every browser test is marked ``e2e``
(:func:`pytest_collection_modifyitems` refuses one that is not), so ``-m "not e2e"`` runs the fast
set; the browser files are handed out first, since they take the longest.

The suite keeps Python's bytecode caches (``__pycache__``, ignored by git) even where
``PYTHONDONTWRITEBYTECODE`` is set, as on the CI machines: every worker, every ``studio`` command a
test starts and every studio the browser tests serve would otherwise compile the studio's sources
again, and pytest rewrite every test module's asserts again (:func:`keep_bytecode`).
"""

from __future__ import annotations

import ast
import functools
import os
import socket
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")


def keep_bytecode() -> None:
    """Write and read bytecode caches in this process and every process it starts: on a 2-core
    machine, compiling the sources again cost the processes of ``tests/test_cli.py`` 14% of their
    CPU."""
    sys.dont_write_bytecode = False
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)


keep_bytecode()  # before pytest imports the test modules, and before xdist starts its workers
ROOT = Path(__file__).resolve().parent.parent
E2E_DIR = ROOT / "tests" / "e2e"
"""The browser tests' folder: every test in it drives Chromium."""
SHARED_PAGE = "tests/e2e (the shared page)"
"""The work unit of the browser files that use the studio's one shared page."""


def require(condition: bool, reason: str) -> None:
    """Skip the calling test when ``condition`` is false, or fail it in CI."""
    if condition:
        return
    if IN_CI:
        pytest.fail(f"{reason} (required in CI)")
    pytest.skip(reason)


def interruptible() -> None:
    """``preexec_fn`` of a child a test stops with Ctrl-C (SIGINT): the signal delivered and not
    ignored, as in a terminal. A blocked or ignored SIGINT is inherited across ``exec``, and a
    worker that ran other tests first may carry one; the child would then never see Ctrl-C."""
    import signal

    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def signal_masks(pid: int) -> str:
    """A process's blocked, ignored and caught signals (``/proc``), for a failure's message."""
    try:
        lines = Path(f"/proc/{pid}/status").read_text().splitlines()
    except OSError as err:
        return f"(no /proc status for {pid}: {err})"
    return " ".join(line for line in lines if line.startswith(("SigBlk", "SigIgn", "SigCgt")))


def free_port() -> int:
    """A TCP port on loopback that nobody listens on now (the OS picks it)."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def hold_preparation(monkeypatch: pytest.MonkeyPatch) -> tuple[threading.Event, threading.Event]:
    """Make every run's learner look uncompiled and its preparation wait until ``compiled`` is set
    (standing for numba compiling the kernels); ``compiling`` is set once one waits."""
    from studio.learning import _prepare

    compiling, compiled = threading.Event(), threading.Event()
    real_warm = _prepare._warm

    def slow_warm(kind: str) -> None:
        compiling.set()
        assert compiled.wait(60), "the test never let the preparation finish"
        real_warm(kind)

    monkeypatch.setattr(_prepare, "learner_ready", lambda kind: False)
    monkeypatch.setattr(_prepare, "_warm", slow_warm)
    return compiling, compiled


@pytest.fixture(autouse=True)
def _robots_load_in_this_process() -> Iterator[None]:
    """Each test starts as a fresh process would: robots built in this process. A command that
    tests call in-process (``studio export``) makes every later robot load of the process go
    through a child process (``isolate_robot_loading``) with that test's cache folder, so every
    robot first loaded by a later test on the worker would pay a child's start and write a cache
    nobody reads."""
    yield
    robot_load = sys.modules.get("studio.kinematics._robot_load")  # (not imported: nothing to undo)
    if robot_load is not None:
        robot_load._isolated.clear()
        robot_load._cache.clear()


def pytest_configure(config: pytest.Config) -> None:
    """On the controller of xdist workers, fill numba's disk cache before they start."""
    distributed = getattr(config.option, "dist", "no") != "no"
    if distributed and not hasattr(config, "workerinput") and not config.option.collectonly:
        warm_kernels()


def warm_kernels() -> None:
    """Compile (or, when cached, just check) the kernels every studio prepares at start: the
    learners' and the arm IK's, each in a child process, waiting for both.

    Without it each worker compiles a kernel its tests need at the same moment as the others
    (tens of CPU seconds each on a fresh clone), and numba's cache index of a function is
    rewritten by whichever finishes last."""
    from studio.kinematics import prepare_arm_ik_in_background
    from studio.learning import prepare_in_background

    for thread in (prepare_in_background(), prepare_arm_ik_in_background()):
        if thread is not None:
            thread.join()


@functools.cache
def _drives_chromium(path: Path) -> bool:
    """Whether the tests of file ``path`` drive Chromium: it is in ``tests/e2e``, or it starts
    Playwright itself."""
    return E2E_DIR in path.parents or "sync_playwright" in path.read_text(errors="replace")


@functools.cache
def _on_the_shared_page(path: Path) -> bool:
    """Whether a test or fixture of file ``path`` takes the shared ``page`` of tests/e2e."""
    if E2E_DIR not in path.parents:
        return False
    for node in ast.walk(ast.parse(path.read_text())):
        if not isinstance(node, ast.FunctionDef) or "page" not in [a.arg for a in node.args.args]:
            continue
        decorators = [ast.unparse(d) for d in node.decorator_list]
        if node.name.startswith("test_") or any("fixture" in d for d in decorators):
            return True
    return False


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """Hand the workers whole files, in collection order; the files on the shared page as one."""
    from xdist.scheduler import LoadScopeScheduling

    class ByFile(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            path = nodeid.split("::", 1)[0]
            return SHARED_PAGE if _on_the_shared_page((ROOT / path).resolve()) else path

    return ByFile(config, log)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Refuse a browser test not marked ``e2e``; put the shared page's files first, then the other
    browser files (stable otherwise: each file keeps its order), so the slowest work starts first
    and no worker idles at the end."""

    def browser(item: pytest.Item) -> bool:
        return _drives_chromium(item.path.resolve())

    unmarked = [i.nodeid for i in items if browser(i) and not i.get_closest_marker("e2e")]
    if unmarked:
        raise pytest.UsageError(
            f"{len(unmarked)} browser test(s) are not marked e2e ({unmarked[0]}, ...): add "
            "`pytestmark = pytest.mark.e2e` to the file, so that -m 'not e2e' leaves them out."
        )
    items.sort(key=lambda i: (not _on_the_shared_page(i.path.resolve()), not browser(i)))
