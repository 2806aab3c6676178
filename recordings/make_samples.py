"""Write the sample recordings and demonstrations shipped in ``studio/samples/`` (fixed seeds).

Each sample is a few seconds of the simulated operator (:func:`studio.capture.simulate`) reaching
the default goal of :class:`studio.learning.ArmGrid` (mirrored onto the Puma560, joint mode),
with one demonstration cut from the reach, so a new user can train supervised agents at once.
Every data folder offers them read-only (:data:`studio.samples.SAMPLES_DIR`)::

    python recordings/make_samples.py            # rewrites studio/samples/sample-*
    python recordings/make_samples.py --out /tmp/samples   # elsewhere, to compare
    studio train --demos sample-reach-1          # a sample by name, from any data folder

Angles are rounded to :data:`ANGLE_DECIMALS` decimals (0.1 mrad, a twentieth of the simulated
sensor noise) to keep the files small; the header and demonstrations carry a fixed creation time
so the files only change when the code does.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from studio.capture import (
    frames_to_arrays,
    goal_configuration,
    recording_meta,
    simulate,
    write_recording,
)
from studio.learning import ArmGrid
from studio.motion import extract_demonstration
from studio.samples import SAMPLES_DIR

SEEDS = (1, 2, 3)
"""One sample per seed."""
SECONDS = 3.5
"""Length of each sample: about one second of wandering, then the reach and a short hold."""
RATE_HZ = 110.0
"""The paper's frame rate."""
ANGLE_DECIMALS = 4
"""Angles are stored to 0.1 mrad."""
CREATED = "2026-11-22T00:00:00+00:00"
"""Fixed creation time, so regenerating gives identical files."""


def make_sample(seed: int, out_dir: Path, grid: ArmGrid) -> tuple[Path, Path]:
    """Write ``sample-reach-<seed>.tape.csv`` and its ``.demo.json``; return both paths."""
    sim = simulate(SECONDS, seed=seed, rate_hz=RATE_HZ, goal=goal_configuration(grid))
    t, counter, status, bend, twist = frames_to_arrays(sim.frames)
    name = f"sample-reach-{seed}"
    meta = recording_meta(
        sim.config.regions,
        tape=sim.config,
        operator="simulated operator",
        notes=f"Simulator seed {seed}: wanders, then reaches the default ArmGrid goal {list(grid.goal)} and holds.",
        name=name,
        rate_hz=RATE_HZ,
        source=f"simulator:{seed}",
        created=CREATED,
    )
    path = out_dir / f"{name}.tape.csv"
    path.unlink(missing_ok=True)
    write_recording(
        path,
        meta,
        t,
        counter,
        status,
        np.round(bend, ANGLE_DECIMALS),
        np.round(twist, ANGLE_DECIMALS),
        closed=CREATED,
    )
    t0 = sim.reach_start / RATE_HZ
    demo = extract_demonstration(path, t0, t[-1] - t[0], grid=grid, name=name)
    demo.created = CREATED
    return path, demo.save(out_dir / f"{name}.demo.json")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out",
        type=Path,
        default=SAMPLES_DIR,
        help="folder (default: the package's studio/samples/)",
    )
    args = parser.parse_args()
    grid = ArmGrid()
    for seed in SEEDS:
        path, demo = make_sample(seed, args.out, grid)
        print(f"{path.name} ({path.stat().st_size // 1024} KB) and {demo.name}")


if __name__ == "__main__":
    main()
