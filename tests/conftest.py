"""Shared test set-up.

In CI (``CI=true``) nothing may be skipped for a missing browser or package: :func:`require`
turns such a skip into a failure there.
"""

from __future__ import annotations

import os
import socket
import threading

import pytest

IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")


def require(condition: bool, reason: str) -> None:
    """Skip the calling test when ``condition`` is false, or fail it in CI."""
    if condition:
        return
    if IN_CI:
        pytest.fail(f"{reason} (required in CI)")
    pytest.skip(reason)


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
