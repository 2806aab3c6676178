"""Shared fixtures of the capture tests: small synthetic frames that need no kinematics."""

from __future__ import annotations

import numpy as np
import pytest

from studio.capture import TapeFrame

REGIONS = 16


def synthetic_frames(n: int, seed: int = 0, regions: int = REGIONS) -> list[TapeFrame]:
    """``n`` frames at 110 Hz with random angles and switch bits."""
    rng = np.random.default_rng(seed)
    return [
        TapeFrame(
            i / 110.0,
            i,
            rng.normal(0, 0.5, regions),
            rng.normal(0, 0.5, regions),
            int(rng.integers(0, 8)) << 4,
        )
        for i in range(n)
    ]


@pytest.fixture
def frames() -> list[TapeFrame]:
    return synthetic_frames(300)
