"""Shared fixtures of the export tests: a smooth recording of the human arm, short enough to fit
in a second, slow enough for the Puma560's limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from studio.capture import RecordingWriter, TapeFrame
from studio.kinematics import HumanArm, TapeConfig, tape_from_arm

RATE_HZ = 110.0


def write_arm_recording(path: Path, q_human: np.ndarray, side: str = "right") -> Path:
    """A tape recording at 110 Hz of the ``side`` arm moving through ``q_human`` (N, 7)."""
    config = TapeConfig(side=side)
    bend, twist = tape_from_arm(HumanArm(side=side), q_human, config)
    with RecordingWriter(path, config=config, source="simulator") as writer:
        writer.write_many(
            [TapeFrame(i / RATE_HZ, i, bend[i], twist[i]) for i in range(len(q_human))]
        )
    return path


def smooth_arm(frames: int = 165, speed: float = 1.0) -> np.ndarray:
    """The arm lifting forwards and bending the elbow, minimum-jerk, ``speed`` times as fast."""
    s = np.linspace(0.0, 1.0, frames)
    s = np.clip(s * speed, 0.0, 1.0)
    blend = 10 * s**3 - 15 * s**4 + 6 * s**5
    q = np.zeros((frames, 7))
    q[:, 0] = 0.25 * blend  # shoulder flexion
    q[:, 3] = 0.3 + 0.2 * blend  # elbow flexion
    return q


@pytest.fixture(scope="session")
def slow_recording(tmp_path_factory) -> Path:
    """1.5 s of a slow, smooth reach: within the Puma560's limits at the capture rate, the arm
    raised forward (1.2 rad) so that the Puma560, mirroring it joint by joint, keeps its arm above
    the floor it stands on (hanging, the arm drove the Puma560's wrist 42 cm into it)."""
    q = smooth_arm(165)
    q[:, 0] += 1.2  # shoulder flexion
    return write_arm_recording(tmp_path_factory.mktemp("rec") / "slow.tape.csv", q)
