"""``python benchmarks/bench_teacher.py --quick``: one table, every baseline on the same split,
with the ratio against the teacher (issue 40)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ROWS = (
    "teacher (the demonstrations followed)",
    "behaviour cloning",
    "DMP (sample-reach-1)",
    "Dyna-Q, no demonstrations",
    "Dyna-Q, the paper's replay only",
    "Dyna-Q + follow option",
    "Dyna-Q + demonstration potential",
    "Dyna-Q + follow + potential (default)",
    "Dyna-Q + potential, any joints at once",
    "Dyna-Q + potential, any joints or follow",
)


def test_the_quick_benchmark_prints_every_row_beside_the_teacher():
    out = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "bench_teacher.py"), "--quick"],
        capture_output=True,
        text=True,
        check=True,
        timeout=900,
    ).stdout
    table = {
        line.split("|")[1].strip(): [cell.strip() for cell in line.split("|")[2:-1]]
        for line in out.splitlines()
        if line.startswith("| ") and not line.startswith("| row")
    }
    assert tuple(table) == ROWS
    assert "the paper's reward (+100 at the goal, -1 a step)" in out
    assert "collision-free starts of" in out  # a collision counted is one the motion makes
    teacher = table[ROWS[0]]
    assert teacher[0] == "100.0%" and teacher[3] == "1.00"  # its own ratio, and it always arrives
    for name, cells in table.items():
        success, collisions, seconds, ratio, _, cpu = cells
        assert success.endswith("%") and collisions.endswith("%") and float(cpu) >= 0
        if seconds != "-":  # the ratio is each row's mean time over the teacher's
            assert (
                float(ratio) == round(float(seconds) / float(teacher[2]), 2)
                or abs(float(ratio) - float(seconds) / float(teacher[2])) < 0.02
            ), name
    assert table["Dyna-Q, no demonstrations"][0] == "0.0%"  # the paper's reward, no help
    assert "Better than its teacher" in out
    assert "First 20 own episodes, Dyna-Q + follow option" in out
    assert "Dyna-Q + potential, any joints or follow: without the hand-over" in out
