"""``studio export`` onto another robot keeps its built geometry in the data folder's cache, as
``studio serve`` does, and tells a person at a terminal that the first load builds it."""

from __future__ import annotations

import sys

from studio.cli import main
from studio.kinematics import robot_is_kept


class _Terminal:
    """A stderr that says it is a terminal and keeps what is written to it."""

    def __init__(self) -> None:
        self.text = ""

    def isatty(self) -> bool:
        return True

    def write(self, text: str) -> int:
        self.text += text
        return len(text)

    def flush(self) -> None:
        pass


def test_the_first_export_onto_a_robot_says_it_builds_it_and_keeps_it(tmp_path, monkeypatch):
    from studio.kinematics import _robot_load

    # as a fresh `studio export` process: no robot loaded yet (another test on this worker may
    # have loaded the SO-100 already)
    monkeypatch.setattr(_robot_load, "_arms", {})
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    monkeypatch.chdir(tmp_path)
    argv = ["export", "sample-reach-1", "--robot", "so100", "--format", "csv", "--unchecked"]
    assert main([*argv, "--out", "a.csv"]) == 0
    assert "the first time, its collision geometry is built" in terminal.text
    assert (tmp_path / "cache" / "robots").is_dir()
    assert any((tmp_path / "cache" / "robots").iterdir())
    assert robot_is_kept("so100")
    terminal.text = ""
    assert main([*argv, "--out", "b.csv"]) == 0
    assert "collision geometry is built" not in terminal.text
