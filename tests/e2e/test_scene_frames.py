"""viser's page draws fewer frames while a slow live stream drives the scene, or while the scene
is still, and still shows every change.

``studio/web/scene/_frames.py`` wraps the page's ``requestAnimationFrame`` so that frames start
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
from studio.web.scene import _frames as _scene_frames
from studio.web.scene._frames import SLOW_FRAME_GAP_MS, pacing_js
from studio.web.scene._scene import SceneLayout, StudioScene
from tests.conftest import free_port
from tests.web.conftest import wait_for

pytestmark = pytest.mark.e2e

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


VIEWER_JS = """() => { window.__updates = 0;
  window.__viserMutable = { requestRender: () => { window.__updates += 1; } }; }"""
"""Stand in for viser's page: ``requestRender`` is what viser calls once it has applied a batch
of scene messages."""

WAKE_JS = pacing_js(SLOW_FRAME_GAP_MS, at_once=True, update_follows=True)
"""A still page woken for a pose of a slow stream, which comes in a batch of its own."""


@pytest.mark.parametrize("order", ["update after the wake", "update before the wake"])
def test_a_woken_page_lets_its_frame_go_once_the_update_is_applied(blank: Any, order: str) -> None:
    """The frame a still page held back is let go for the update that woke it, never before it
    is applied: not for the batch carrying the script that wakes the page (viser asks for a
    frame after that one too), but for the update's own, or at once if that came first."""
    blank.evaluate(VIEWER_JS)
    render = "window.__viserMutable.requestRender();"
    still = pacing_js(1e9, still=True, at_once=True)
    for _ in range(5):  # (a new page may get a resize of its own, which lifts the limit)
        blank.evaluate(f"() => {{ {pacing_js(SLOW_FRAME_GAP_MS, at_once=True)} }}")
        blank.evaluate(FRAMES_JS, 1)  # a frame just ran: the next one waits for its turn
        # the frame asked for, then the batch that makes the page still (viser asks for a
        # frame after it: that is no update)
        blank.evaluate(f"() => {{ ({HELD_JS})(); {still} {render} }}")
        blank.wait_for_timeout(300)
        if blank.evaluate("() => window.__held") is False:
            break
    assert blank.evaluate("() => window.__held") is False, "the frame is held back"
    if order == "update before the wake":
        blank.evaluate(f"() => {{ {render} }}")  # applied while still: no frame for it yet
        blank.wait_for_timeout(300)
        assert blank.evaluate("() => window.__held") is False, "held while still"
        blank.evaluate(f"() => {{ {WAKE_JS} {render} }}")
    else:
        blank.evaluate(f"() => {{ {WAKE_JS} {render} }}")  # the batch that wakes the page
        blank.wait_for_timeout(2 * SLOW_FRAME_GAP_MS)  # past the turn it had before the wake
        assert blank.evaluate("() => window.__held") is False, "let go before the update"
        blank.evaluate(f"() => {{ {render} }}")  # the update's batch, applied
    blank.wait_for_function("() => window.__held === true", timeout=10_000)
    assert blank.evaluate("() => window.__updates") >= 2, "viser's own requestRender still runs"


KEEP_DRAWN_JS = """(() => {
  const get = HTMLCanvasElement.prototype.getContext;
  HTMLCanvasElement.prototype.getContext = function (kind, options) {
    if (kind === "webgl2" || kind === "webgl") options = { ...options, preserveDrawingBuffer: true };
    return get.call(this, kind, options);
  };
})();"""
"""Keep each WebGL canvas's last drawn frame readable (``toDataURL``) between frames, so a
test can see what a frame drew without drawing one (a screenshot draws frames of its own)."""


@pytest.fixture
def scene_page(browser: Any) -> Iterator[tuple[StudioScene, Any]]:
    port = free_port()
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    scene = StudioScene(server, body=HumanBody("right"), layout=SceneLayout())
    page = browser.new_page(viewport={"width": 990, "height": 586})
    page.add_init_script(KEEP_DRAWN_JS)
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


def _drawn(page: Any) -> str:
    """What the scene's last frame drew (a hash), read without drawing a frame."""
    urls = page.evaluate("() => [...document.querySelectorAll('canvas')].map((c) => c.toDataURL())")
    return hashlib.sha256("".join(urls).encode()).hexdigest()


def _still(page: Any) -> bool:
    return bool(page.evaluate("() => window.__studioFramePacing?.still === true"))


def _pacing(page: Any) -> dict[str, Any] | None:
    return page.evaluate(
        "() => window.__studioFramePacing && "
        "({ gap: window.__studioFramePacing.gapMs, frames: window.__studioFramePacing.frames, "
        "slow: window.__studioFramePacing.atOnce })"
    )


def test_a_slow_stream_is_drawn_in_one_frame_a_pose(scene_page) -> None:
    """One pose a second (the camera without a GPU): the first frame after a pose shows it as it
    stays, and no other frame is drawn until the next pose (neither viser's settle frames nor
    its idle frame)."""
    scene, page = scene_page
    _pose(scene, 0)
    # (as long as the page may take to load: the script comes once it has connected; and the
    # scene may read as still by the time it is looked at)
    assert wait_for(lambda: (_pacing(page) or {}).get("slow") is True, timeout=60)
    pictures, frames = [_drawn(page)], []
    for k in range(1, 9):
        assert wait_for(lambda: _still(page)), "the scene is still between poses"
        start = _pacing(page)["frames"]
        _pose(scene, k)
        assert wait_for(lambda s=start: _pacing(page)["frames"] > s), f"pose {k} never drawn"
        first = _drawn(page)  # what the pose's first frame drew
        time.sleep(1.0)
        assert _drawn(page) == first, f"pose {k}: a later frame drew something else"
        assert first not in pictures, f"pose {k} is not what its frame shows"
        pictures.append(first)
        frames.append(_pacing(page)["frames"] - start)
    # (a busy machine may let one settle frame through before the scene reads as still)
    assert sum(frames) <= len(frames) + 2, f"frames a pose: {frames}"
    # a fast stream (the tape, a camera with a GPU) lifts the limit
    for k in range(200):
        _pose(scene, k % 7)
        time.sleep(0.005)
    assert wait_for(lambda: _pacing(page)["gap"] == 0)


def test_a_still_scene_draws_rarely_and_shows_the_next_pose_at_once(scene_page, monkeypatch):
    """Nothing sent to a loaded page for a while: it draws at most every STILL_FRAME_GAP_MS (here
    never). A pose sent then is drawn at once: the page applies the message lifting the limit
    without waiting for a frame (read without drawing one, so only the page's own frame can show
    it)."""
    monkeypatch.setattr(_scene_frames, "LOADING_S", 1.0)
    monkeypatch.setattr(_scene_frames, "STILL_AFTER_S", 0.5)
    monkeypatch.setattr(_scene_frames, "STILL_FRAME_GAP_MS", 1e9)  # no safety-net frame at all
    scene, page = scene_page
    assert wait_for(lambda: (_pacing(page) or {}).get("gap") == 1e9)
    start = _pacing(page)["frames"]
    page.wait_for_timeout(2000)
    assert _pacing(page)["frames"] - start <= 1, "no frame while still (but one in flight)"
    before = _drawn(page)
    _pose(scene, 3)
    assert wait_for(lambda: _drawn(page) != before), "the pose never showed"
