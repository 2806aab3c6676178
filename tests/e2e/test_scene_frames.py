"""viser's page draws fewer frames while a slow live stream drives the scene, or while the scene
is still, and still shows every change.

``studio/web/_scene_frames.py`` wraps the page's ``requestAnimationFrame`` so that frames start
at least ``SLOW_FRAME_GAP_MS`` apart while a slow stream (pose estimation without a GPU) drives
the scene. These tests run the wrapper in Chromium: alone (it delays frames and never drops one,
and a cancelled request never runs), and in viser's own page beside a real scene (each pose is
drawn, in a few frames instead of a burst, and a fast stream lifts the limit).
"""

from __future__ import annotations

import contextlib
import hashlib
import time
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
import viser
from playwright.sync_api import TimeoutError as PlaywrightTimeout

from studio.kinematics import HumanBody
from studio.web import _scene_frames
from studio.web._scene import SceneLayout, StudioScene
from studio.web._scene_frames import SLOW_FRAME_GAP_MS, pacing_js
from tests.conftest import free_port
from tests.web.conftest import wait_for

FRAMES_JS = """(n) => new Promise((resolve, reject) => {
  const times = [];
  const step = (t) => { times.push(performance.now()); if (times.length < n) requestAnimationFrame(step); else resolve(times); };
  requestAnimationFrame(step);
  setTimeout(() => reject(new Error(`${times.length} of ${n} frames ran in 20 s`)), 20000);
})"""
"""A chain of ``n`` frames, each requested from the one before (as three.js does): their times
(an error after 20 s, so that a frame held back for good fails the test rather than hangs it)."""


@pytest.fixture
def blank(browser: Any) -> Iterator[Any]:
    page = browser.new_page()
    page.set_content("<!doctype html><title>frames</title><p>frames</p>")
    # A new page beside others gets its viewport a moment later, as a resize, which would lift
    # the limit under test for INPUT_LIFTS_MS: let it come first (it may not come at all).
    page.evaluate("() => addEventListener('resize', () => { window.__resized = true; })")
    with contextlib.suppress(PlaywrightTimeout):
        page.wait_for_function("() => window.__resized === true", timeout=1000)
    yield page
    page.close()


def test_the_limit_delays_frames_and_never_drops_one(blank: Any) -> None:
    blank.evaluate(f"() => {{ {pacing_js(SLOW_FRAME_GAP_MS)} }}")
    times = blank.evaluate(FRAMES_JS, 4)
    assert len(times) == 4, "every requested frame runs"
    gaps = np.diff(times)
    assert np.all(gaps >= SLOW_FRAME_GAP_MS - 5), f"frames {gaps} ms apart"
    assert blank.evaluate("() => window.__studioFramePacing.frames") >= 4


def test_a_cancelled_frame_never_runs_and_no_limit_passes_frames_through(blank: Any) -> None:
    blank.evaluate(f"() => {{ {pacing_js(SLOW_FRAME_GAP_MS)} }}")
    blank.evaluate(FRAMES_JS, 1)  # a frame just ran: the next request waits for its turn
    ran = blank.evaluate(
        """(gap) => new Promise((resolve) => {
          let ran = false;
          const id = requestAnimationFrame(() => { ran = true; });
          cancelAnimationFrame(id);
          setTimeout(() => resolve(ran), 2 * gap);
        })""",
        SLOW_FRAME_GAP_MS,
    )
    assert ran is False
    blank.evaluate(f"() => {{ {pacing_js(0)} }}")  # the same page, the limit lifted
    assert len(blank.evaluate(FRAMES_JS, 5)) == 5


HELD_JS = """() => { window.__held = false;
  requestAnimationFrame(() => { window.__held = true; }); }"""
"""Request a frame; ``window.__held`` turns true when it runs."""


@pytest.mark.parametrize("how", ["gap lowered", "resize", "pointer"])
def test_a_frame_held_back_runs_at_once_when_the_gap_drops_or_the_user_acts(
    blank: Any, how: str
) -> None:
    """A still page holds a frame back for seconds; lowering the gap (an update woke the page),
    or a pointer or resize in the page, hands it to the browser at once."""
    blank.evaluate(f"() => {{ {pacing_js(1e9)} }}")  # a gap no frame would ever outwait
    for _ in range(5):  # (a new page may get a resize of its own, which lifts the limit)
        blank.evaluate(FRAMES_JS, 1)  # a frame just ran: the next one waits for the gap
        blank.evaluate(HELD_JS)
        blank.wait_for_timeout(300)
        if blank.evaluate("() => window.__held") is False:
            break
    assert blank.evaluate("() => window.__held") is False, "the frame is held back"
    if how == "gap lowered":
        blank.evaluate(f"() => {{ {pacing_js(0)} }}")
    elif how == "resize":
        blank.evaluate("() => window.dispatchEvent(new Event('resize'))")
    else:
        blank.mouse.move(20, 20)
        blank.mouse.move(40, 30)
    blank.wait_for_function("() => window.__held === true", timeout=10_000)


def test_a_frame_waiting_for_its_turn_waits_longer_when_the_gap_grows(blank: Any) -> None:
    """viser's once-a-second frame, asked for just before a slow stream's scene became still,
    is held until the next pose rather than drawn between poses."""
    blank.evaluate(f"() => {{ {pacing_js(SLOW_FRAME_GAP_MS)} }}")
    # a frame asked for, and the scene still, in one task: however slow the machine, the frame
    # is still waiting for its old turn when the gap grows
    held_then_still = f"() => {{ ({HELD_JS})(); {pacing_js(1e9, still=True)} }}"
    for _ in range(5):  # (a new page may get a resize of its own, which lifts the limit)
        blank.evaluate(f"() => {{ {pacing_js(SLOW_FRAME_GAP_MS)} }}")
        blank.evaluate(FRAMES_JS, 1)  # a frame just ran: the next one waits for its turn
        blank.evaluate(held_then_still)
        if blank.evaluate("() => window.__held") is False:
            break
    blank.wait_for_timeout(3 * SLOW_FRAME_GAP_MS)
    assert blank.evaluate("() => window.__held") is False, "held past its old turn"
    blank.evaluate(f"() => {{ {pacing_js(SLOW_FRAME_GAP_MS)} }}")  # the next pose woke the page
    blank.wait_for_function("() => window.__held === true", timeout=10_000)


@pytest.fixture
def scene_page(browser: Any) -> Iterator[tuple[StudioScene, Any]]:
    port = free_port()
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    scene = StudioScene(server, body=HumanBody("right"), layout=SceneLayout())
    page = browser.new_page(viewport={"width": 990, "height": 586})
    page.goto(f"http://127.0.0.1:{port}/?fixedDpr=0.5")
    page.wait_for_selector("canvas", timeout=60_000)
    try:
        yield scene, page
    finally:
        page.close()
        scene.close()
        server.stop()


def _pose(scene: StudioScene, k: int) -> None:
    """A live pose that differs visibly for each ``k``."""
    q_robot = scene.robot.qz + np.array([0.3 * k, 0.2, -0.2 * k, 0.0, 0.1 * k, 0.0])
    scene.update_live(np.array([0.1 * k, 0.3, 0.0, 0.5 + 0.1 * k, 0.0, 0.0, 0.0]), q_robot, None)


def _picture(page: Any) -> str:
    return hashlib.sha256(page.screenshot()).hexdigest()


def _pacing(page: Any) -> dict[str, float] | None:
    return page.evaluate(
        "() => window.__studioFramePacing && "
        "({ gap: window.__studioFramePacing.gapMs, frames: window.__studioFramePacing.frames })"
    )


def test_a_slow_stream_is_drawn_in_few_frames_each_pose_shown(scene_page) -> None:
    """One pose a second (the camera without a GPU): each pose reaches the picture, in two
    frames (the update and its settling) rather than a burst, and viser's idle frame is not drawn
    between poses."""
    scene, page = scene_page
    pictures, frames = [], []
    for k in range(6):
        _pose(scene, k)
        time.sleep(1.0)
        if k == 0:
            assert wait_for(lambda: (_pacing(page) or {}).get("gap") == SLOW_FRAME_GAP_MS)
            start = _pacing(page)["frames"]
        # every pose shows in the scene: wait for a picture unlike the poses' before (a busy
        # machine may draw it late), rather than take whatever is there after the second
        assert wait_for(lambda: _picture(page) not in pictures), f"pose {k} never showed"
        frames.append(_pacing(page)["frames"])
        pictures.append(_picture(page))
    assert len(set(pictures)) == len(pictures), "every pose shows in the scene"
    per_pose = (frames[-1] - start) / (len(frames) - 1)
    assert per_pose <= 4, f"{per_pose:.1f} frames a pose (screenshots draw frames too)"
    # without screenshots: the pose's frame and its settling, and none between poses (the scene
    # is still once a pose is settled, so viser's once-a-second frame waits for the next pose)
    start = _pacing(page)["frames"]
    for k in range(8):
        _pose(scene, k % 4 + 6)
        time.sleep(1.0)
    per_pose = (_pacing(page)["frames"] - start) / 8
    assert per_pose <= 2.4, f"{per_pose:.2f} frames a pose"
    # a fast stream (the tape, a camera with a GPU) lifts the limit
    for k in range(200):
        _pose(scene, k % 7)
        time.sleep(0.005)
    assert wait_for(lambda: _pacing(page)["gap"] == 0)


def test_a_still_scene_draws_rarely_and_shows_the_next_pose_at_once(scene_page, monkeypatch):
    """Nothing sent to a loaded page for a while: it draws at most every STILL_FRAME_GAP_MS (here
    never). A pose sent then is drawn at once, in viser's usual burst: the page applies the
    message lifting the limit without waiting for a frame."""
    monkeypatch.setattr(_scene_frames, "LOADING_S", 1.0)
    monkeypatch.setattr(_scene_frames, "STILL_AFTER_S", 0.5)
    monkeypatch.setattr(_scene_frames, "STILL_FRAME_GAP_MS", 1e9)  # no safety-net frame at all
    scene, page = scene_page
    assert wait_for(lambda: (_pacing(page) or {}).get("gap") == 1e9)
    start = _pacing(page)["frames"]
    page.wait_for_timeout(2000)
    assert _pacing(page)["frames"] - start <= 1, "no frame while still (but one in flight)"
    before = _picture(page)
    start = _pacing(page)["frames"]
    _pose(scene, 3)
    assert wait_for(lambda: _picture(page) != before), "the pose never showed"
    assert wait_for(lambda: _pacing(page)["frames"] - start >= 2), "drawn as a burst"
