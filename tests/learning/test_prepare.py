"""Preparing the learner: whether the kernels are compiled, the word a first run shows, live CPU."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
import threading
import time

import numpy as np

from studio.learning import ArmGrid, DynaQConfig, LiveProgress, RunFolder, RunRecord, _prepare
from studio.learning._prepare import PREPARE_SECONDS, learner_ready, preparing_note
from tests.conftest import hold_preparation
from tests.web.conftest import wait_for

KERNEL = """
from numba import njit


@njit(cache=True)
def twice(x):
    return 2 * x
"""


def test_a_kernel_counts_as_ready_once_compiled_here_or_cached_on_disk(tmp_path, monkeypatch):
    (tmp_path / "tiny_kernel.py").write_text(KERNEL)
    monkeypatch.syspath_prepend(str(tmp_path))
    module = importlib.import_module("tiny_kernel")
    assert not module.twice.signatures and not _prepare._cached_on_disk(module.twice)
    assert module.twice(3) == 6
    assert _prepare._cached_on_disk(module.twice)  # compiled, and its cache index written
    # another process has nothing compiled, yet finds it on disk without compiling
    code = (
        "import tiny_kernel; from studio.learning._prepare import _cached_on_disk; "
        "print(bool(tiny_kernel.twice.signatures), _cached_on_disk(tiny_kernel.twice))"
    )
    env_path = [str(tmp_path), *sys.path]
    out = subprocess.run(
        [sys.executable, "-c", f"import sys; sys.path[:0] = {env_path!r}; {code}"],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    ).stdout.split()
    assert out == ["False", "True"]
    # edited source: the cache is stale, the next call compiles again
    (tmp_path / "tiny_kernel.py").write_text(KERNEL + "\n# edited\n")
    stat = (tmp_path / "tiny_kernel.py").stat()

    os.utime(tmp_path / "tiny_kernel.py", ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))
    sys.modules.pop("tiny_kernel")
    assert not _prepare._cached_on_disk(importlib.import_module("tiny_kernel").twice)


def test_the_tasks_kernels_are_ready_after_a_run():
    from studio.learning import warm_up

    warm_up()
    assert learner_ready("arm-grid")


def test_a_first_run_says_it_prepares_the_learner_before_its_first_episode(tmp_path, monkeypatch):
    compiling, compiled = hold_preparation(monkeypatch)
    record = RunRecord.for_arm_grid(ArmGrid(), DynaQConfig(planning="zero"), 2, 5, seed=0)
    run = RunFolder.create(tmp_path, record)
    live = LiveProgress(2, 5)
    thread = threading.Thread(target=run.train, args=(live,), kwargs={"workers": 1})
    thread.start()
    assert compiling.wait(30)
    assert live.note == preparing_note("arm-grid")
    assert live.note.startswith("preparing the learner (first run on this machine, about ")
    assert f"about {PREPARE_SECONDS['arm-grid']:.0f} s" in live.note
    assert live.completed == 0 and run.status == "running"
    compiled.set()
    thread.join(60)
    assert live.note is None and live.completed == 10 and run.status == "done"


def test_an_experiments_cpu_time_is_counted_while_it_runs():
    live = LiveProgress(1, 1)
    inside, leave = threading.Event(), threading.Event()

    def experiment() -> None:
        with live.counting_cpu():
            inside.set()
            deadline = time.thread_time() + 0.2
            while time.thread_time() < deadline and not leave.is_set():
                np.sum(np.arange(1000))
            leave.wait(30)

    thread = threading.Thread(target=experiment)
    thread.start()
    assert inside.wait(30)
    assert wait_for(lambda: live.cpu_seconds >= 0.1, 60)  # counted before the experiment ends
    leave.set()
    thread.join(30)
    done = live.cpu_seconds
    assert done >= 0.1 and live.cpu_seconds == done  # kept once the thread is gone


class _Compiling:
    """Stands for the background child compiling a task: ``wait`` returns once ``done`` is set."""

    def __init__(self) -> None:
        self.done, self.waited = threading.Event(), threading.Event()

    def wait(self, timeout: float | None = None) -> int:
        self.waited.set()
        assert self.done.wait(timeout)
        return 0


def test_a_run_waits_for_the_background_child_only_when_it_compiles_its_own_task(monkeypatch):
    warmed: list[str] = []
    child = _Compiling()
    monkeypatch.setattr(_prepare, "learner_ready", lambda kind: False)
    monkeypatch.setattr(_prepare, "_warm", warmed.append)
    monkeypatch.setattr(_prepare, "_background", (child, "arm-reach"))
    _prepare.prepare_learner("arm-grid")  # another task: compiled here, no wait
    assert warmed == ["arm-grid"] and not child.waited.is_set()
    live = LiveProgress(1, 1)
    waiting = threading.Thread(target=_prepare.prepare_learner, args=("arm-reach", live))
    waiting.start()
    assert child.waited.wait(30)
    assert live.note == preparing_note("arm-reach") and warmed == ["arm-grid"]
    child.done.set()
    waiting.join(30)
    assert warmed == ["arm-grid", "arm-reach"] and live.note is None


def test_nothing_is_compiled_in_the_background_when_every_task_is_ready(monkeypatch):
    monkeypatch.setattr(_prepare, "learner_ready", lambda kind: True)
    monkeypatch.setattr(subprocess, "Popen", None)  # a child would fail the test
    assert _prepare.prepare_in_background() is None
