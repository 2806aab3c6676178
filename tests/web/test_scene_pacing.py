"""A slow live stream (pose estimation without a GPU) reaches the scene at a bounded rate.

viser's page redraws for a quarter of a second after every push. A camera whose pose model runs
at a few frames a second in software WebGL would make the page redraw most of the time, in the
browser process that also runs the model. So a slow stream's poses are pushed at most
``slow_live_rate_hz`` times a second (latest wins), while a fast one (the tape, a camera with a
GPU, a dragged hand) is pushed as it comes.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
import viser

from studio.kinematics import HumanBody
from studio.web._scene import SceneLayout, StudioScene
from tests.conftest import free_port
from tests.web.conftest import wait_for

SLOW = {"slow_live_s": 0.04, "slow_live_rate_hz": 5.0, "rate_hz": 100.0}
"""Scaled down so the test is short: poses 0.04 s apart or more are slow, pushed at 5 Hz."""


@pytest.fixture(scope="module")
def scene():
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    sc = StudioScene(server, body=HumanBody("right"), layout=SceneLayout(**SLOW))
    yield sc
    sc.close()
    server.stop()


def _stream(
    scene: StudioScene, count: int, gap_s: float, jitter_s: float = 0.0
) -> tuple[int, float, np.ndarray]:
    """Send ``count`` distinct live poses ``gap_s`` apart on average (``gap_s`` -+ ``jitter_s``
    in turn); the pushes made meanwhile, the time it took and the last robot pose sent."""
    start, t0 = scene.pushes, time.perf_counter()
    for i in range(count):
        q_robot = np.full(6, 1e-3 * (i + 1) + 0.1 * gap_s)
        scene.update_live(np.zeros(7), q_robot, None)
        time.sleep(gap_s + (jitter_s if i % 2 else -jitter_s))
    return scene.pushes - start, time.perf_counter() - t0, q_robot


def test_a_slow_stream_reaches_the_scene_at_its_rate_and_latest_wins(scene):
    pushed, took, last = _stream(scene, count=25, gap_s=0.06)
    allowed = took * SLOW["slow_live_rate_hz"] + 1
    assert 1 <= pushed <= allowed, f"{pushed} pushes of 25 poses in {took:.2f} s"
    assert wait_for(lambda: np.allclose(scene.current_q_robot(), last))


def test_a_slow_stream_with_jitter_is_still_slow(scene):
    """Poses 0.01 and 0.11 s apart in turn (a loaded machine): slow on average, so paced."""
    pushed, took, last = _stream(scene, count=30, gap_s=0.06, jitter_s=0.05)
    allowed = took * SLOW["slow_live_rate_hz"] + 1
    assert 1 <= pushed <= allowed, f"{pushed} pushes of 30 poses in {took:.2f} s"
    assert wait_for(lambda: np.allclose(scene.current_q_robot(), last))


def test_a_fast_stream_is_pushed_as_it_comes(scene):
    pushed, took, last = _stream(scene, count=200, gap_s=0.002)
    assert pushed > took * SLOW["slow_live_rate_hz"] + 2, f"{pushed} pushes in {took:.2f} s"
    assert wait_for(lambda: np.allclose(scene.current_q_robot(), last))
