"""The shipped samples: readable recordings whose demonstrations reach the default goal."""

from __future__ import annotations

import json
import runpy
import sys
from pathlib import Path

import numpy as np

from studio.capture import (
    human_angles,
    load_demonstration,
    read_any_recording,
    read_recording,
    recording_series,
)
from studio.learning import ArmGrid
from studio.motion import demonstration_grid
from studio.samples import SAMPLES_DIR

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"
"""The repository folder of the recording format's README and the script that makes the samples."""


def test_every_sample_demo_reaches_the_default_goal_of_arm_grid():
    demos = sorted(SAMPLES_DIR.glob("sample-*.demo.json"))
    assert len(demos) >= 2
    grid = ArmGrid()
    total = 0
    for path in demos:
        demo = load_demonstration(path)
        assert demo.recording.parent == SAMPLES_DIR  # found next to it, wherever it is installed
        rec = read_recording(demo.recording)
        total += path.stat().st_size + demo.recording.stat().st_size
        assert not rec.recovered and rec.problems == []
        assert demonstration_grid(demo) == grid and demo.grid_path[-1] == grid.goal_state
        bins = np.array([grid.bins_of(s) for s in demo.grid_path])
        assert np.all(np.abs(np.diff(bins, axis=0)) <= 1)
        assert 0 <= demo.t0 < demo.t1 <= rec.duration + 1e-9
    assert total < 500_000  # small enough to ship


def test_the_committed_script_regenerates_the_samples(tmp_path):
    script = runpy.run_path(str(RECORDINGS / "make_samples.py"))
    argv = sys.argv
    sys.argv = ["make_samples.py", "--out", str(tmp_path)]
    try:
        script["main"]()
    finally:
        sys.argv = argv
    shipped = sorted(p.name for p in SAMPLES_DIR.glob("sample-*"))
    assert shipped == sorted(p.name for p in tmp_path.glob("sample-*"))
    for name in shipped:
        new, old = tmp_path / name, SAMPLES_DIR / name
        if name.endswith(".tape.csv"):
            assert new.read_bytes() == old.read_bytes(), name
        else:  # demonstrations: the same path; the fit's trajectory to its stored micro-radian
            a, b = json.loads(new.read_text()), json.loads(old.read_text())
            ta, tb = a.pop("trajectory"), b.pop("trajectory")
            assert a == b, name
            assert np.allclose(ta["q_robot"], tb["q_robot"], atol=2e-6) and ta["t"] == tb["t"]


def test_human_angles_are_the_frames_fitted_in_order_as_the_timeline_fits_them() -> None:
    rec = read_any_recording(SAMPLES_DIR / "sample-reach-1.tape.csv")
    every = human_angles(rec, slice(None))
    assert every.shape == (len(rec), 7) and np.all(np.isfinite(every))
    assert np.allclose(every, recording_series(rec, points=len(rec)).q_human)
    rows = rec.segment(1.0, 2.0)  # a segment's rows, as a slice or as indices
    assert np.allclose(human_angles(rec, rows), human_angles(rec, np.arange(rows.start, rows.stop)))
    assert human_angles(rec, slice(0, 0)).shape == (0, 7)
