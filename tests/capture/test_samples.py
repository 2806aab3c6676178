"""The shipped samples: readable recordings whose demonstrations reach the default goal."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from studio.capture import load_demonstration, read_recording
from studio.learning import ArmGrid

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"


def test_every_sample_demo_reaches_the_default_goal_of_arm_grid():
    demos = sorted(RECORDINGS.glob("sample-*.demo.json"))
    assert len(demos) >= 2
    grid = ArmGrid()
    total = 0
    for path in demos:
        demo = load_demonstration(path)
        rec = read_recording(demo.recording)
        total += path.stat().st_size + demo.recording.stat().st_size
        assert not rec.recovered and rec.problems == []
        assert demo.arm_grid() == grid and demo.grid_path[-1] == grid.goal_state
        bins = np.array([grid.bins_of(s) for s in demo.grid_path])
        assert np.all(np.abs(np.diff(bins, axis=0)) <= 1)
        assert 0 <= demo.t0 < demo.t1 <= rec.duration + 1e-9
    assert total < 500_000  # small enough to ship
