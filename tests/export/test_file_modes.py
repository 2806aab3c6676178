"""Exported files and folders get the mode a plain ``open()`` or ``mkdir()`` gives (the umask's),
as recordings and runs do, not the private 0600 / 0700 of the temporary files they start as."""

from __future__ import annotations

import os
import stat

import pytest

from studio.export import demonstration_motion, export_motion
from studio.samples import SAMPLES_DIR


@pytest.fixture
def open_umask():
    old = os.umask(0o022)
    yield
    os.umask(old)


def _mode(path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


@pytest.mark.parametrize("fmt", ["csv", "mcap", "lerobot"])
def test_an_export_reads_like_a_recording(tmp_path, fmt, open_umask):
    motion = demonstration_motion(SAMPLES_DIR / "sample-reach-1.demo.json", "puma560", 30.0)
    out = tmp_path / f"reach.{fmt}"
    export_motion(motion, fmt, out, task="Reach the goal")
    plain = tmp_path / "plain"
    plain.write_text("")
    assert _mode(out) == (0o755 if out.is_dir() else 0o644)
    assert _mode(plain) == 0o644
    if out.is_dir():
        inner = [p for p in out.rglob("*")]
        assert inner
        assert all(_mode(p) == (0o755 if p.is_dir() else 0o644) for p in inner)
