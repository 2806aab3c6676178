"""A slow live stream (pose estimation without a GPU) reaches the scene at a bounded rate, and a
still scene is drawn rarely.

viser's page redraws for a quarter of a second after every push. A camera whose pose model runs
at a few frames a second in software WebGL would make the page redraw most of the time, in the
browser process that also runs the model. So a slow stream's poses are pushed at most
``slow_live_rate_hz`` times a second (latest wins), while a fast one (the tape, a camera with a
GPU, a dragged hand) is pushed as it comes, and while a slow stream drives the scene viser's
page is asked to draw fewer frames (``studio/web/scene/_frames.py``).
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import threading
import time
from collections.abc import Iterator

import msgspec
import numpy as np
import pytest
import viser
import websockets
import zstandard

from studio.kinematics import HumanBody
from studio.web.scene import _frames as _scene_frames
from studio.web.scene._frames import SLOW_FRAME_GAP_MS, STILL_FRAME_GAP_MS
from studio.web.scene._scene import STREAM_STOPPED_S, SceneLayout, StudioScene
from tests.conftest import free_port
from tests.web.conftest import wait_for

SLOW = {"slow_live_s": 0.04, "slow_live_rate_hz": 5.0, "rate_hz": 100.0}
"""Scaled down so the test is short: poses 0.04 s apart or more are slow, pushed at 5 Hz."""


@pytest.fixture(scope="module")
def scene():
    """A scene a browser shows (one that no browser shows is pushed at ``unviewed_rate_hz``)."""
    port = free_port()
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    sc = StudioScene(server, body=HumanBody("right"), layout=SceneLayout(**SLOW))
    viewer = _ScriptWatch(port)
    assert wait_for(lambda: len(server.get_clients()) == 1), "the viewer never connected"
    yield sc
    viewer.stop.set()
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


CAMERA = {
    "type": "ViewerCameraMessage",
    "wxyz": (1.0, 0.0, 0.0, 0.0),
    "position": (3.0, 0.0, 1.5),
    "fov": 1.0,
    "near": 0.01,
    "far": 100.0,
    "image_height": 480,
    "image_width": 640,
    "look_at": (0.0, 0.0, 1.0),
    "up_direction": (0.0, 0.0, 1.0),
}
"""What a browser sends first: viser counts a client as connected from its first camera."""


class _ScriptWatch:
    """A viser client of the scene, in a thread: the scripts (``RunJavascriptMessage``) it gets."""

    def __init__(self, port: int) -> None:
        self.scripts: list[str] = []
        self.connected = threading.Event()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=lambda: asyncio.run(self._run(port)), daemon=True)
        self.thread.start()
        assert self.connected.wait(20), "could not connect to the scene"

    async def _run(self, port: int) -> None:
        unzip = zstandard.ZstdDecompressor()
        async with websockets.connect(
            f"ws://127.0.0.1:{port}",
            subprotocols=[f"viser-v{viser.__version__}"],
            max_size=None,
            origin=f"http://127.0.0.1:{port}",
        ) as ws:
            await ws.send(msgspec.msgpack.encode(CAMERA))  # viser counts a client from its camera
            self.connected.set()
            while not self.stop.is_set():
                try:
                    raw = await asyncio.wait_for(ws.recv(), 0.1)
                except TimeoutError:
                    continue
                except websockets.ConnectionClosed:
                    return  # the scene stopped
                size, packed = (int.from_bytes(raw[k : k + 8], "little") for k in (0, 8))
                inner = unzip.decompress(raw[16 : 16 + packed], max_output_size=size)
                for m in msgspec.msgpack.decode(inner)["messages"]:
                    if m.get("type") == "RunJavascriptMessage":
                        self.scripts.append(m["source"])

    def gaps(self) -> list[float]:
        """The frame gap each script set, in order."""
        return [float(s.split("p.gapMs = ")[1].split(";")[0]) for s in self.scripts]

    def gap(self) -> float | None:
        """The frame gap the last script set, or None before any script."""
        return self.gaps()[-1] if self.scripts else None


@contextlib.contextmanager
def _unviewed_scene(unviewed_hz: float) -> Iterator[tuple[StudioScene, int]]:
    """A scene no browser shows yet, pushed at most ``unviewed_hz`` times a second; its port."""
    port = free_port()
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    layout = SceneLayout(**SLOW, unviewed_rate_hz=unviewed_hz)
    sc = StudioScene(server, body=HumanBody("right"), layout=layout)
    try:
        yield sc, port
    finally:
        sc.close()
        server.stop()


def test_a_scene_no_browser_shows_is_pushed_rarely_and_kept_current():
    hz = SceneLayout().unviewed_rate_hz
    with _unviewed_scene(hz) as (sc, _):
        pushed, took, last = _stream(sc, count=200, gap_s=0.002)
        assert pushed <= took * hz + 2, f"{pushed} pushes in {took:.2f} s"
        assert wait_for(lambda: np.allclose(sc.current_q_robot(), last))


def test_a_browser_connecting_is_shown_the_latest_pose_at_once():
    """The first browser to connect wakes the scene: it does not wait out the slow period."""
    with _unviewed_scene(0.01) as (sc, port):  # a push every 100 s
        _stream(sc, count=1, gap_s=0.0)
        assert wait_for(lambda: sc.pushes >= 1)  # the first pose: the slow period starts
        q = np.full(6, 0.42)
        sc.update_live(np.zeros(7), q, None)
        viewer = _ScriptWatch(port)
        try:
            assert wait_for(lambda: np.allclose(sc.current_q_robot(), q)), "the browser waits"
        finally:
            viewer.stop.set()


def test_a_slow_stream_limits_the_browsers_frames_and_a_fast_one_lifts_the_limit():
    """While a slow stream drives the scene, every browser showing it (and one that connects
    then) is asked to draw a frame at most every SLOW_FRAME_GAP_MS; a fast stream, or the slow
    one stopping, lifts the limit."""
    port = free_port()
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    sc = StudioScene(server, body=HumanBody("right"), layout=SceneLayout(**SLOW))
    early = _ScriptWatch(port)
    try:
        _stream(sc, count=200, gap_s=0.002)
        assert wait_for(lambda: early.gap() in (None, 0.0)), "a fast stream draws freely"
        slow = threading.Thread(target=_stream, args=(sc, 60, 0.06))  # 3.6 s of a slow stream
        slow.start()
        assert wait_for(lambda: early.gap() == SLOW_FRAME_GAP_MS), early.scripts[-1:]
        late = _ScriptWatch(port)  # connects while the slow stream drives the scene
        assert wait_for(lambda: late.gap() == SLOW_FRAME_GAP_MS)
        slow.join()
        _stream(sc, count=200, gap_s=0.002)
        assert wait_for(lambda: early.gap() == 0.0 and late.gap() == 0.0)
        _stream(sc, count=12, gap_s=0.06)
        assert wait_for(lambda: early.gap() == SLOW_FRAME_GAP_MS)
        # the slow stream stops: its last pose stays, the slow limit goes (the scene, still by
        # then, may already have been given the still gap instead)
        assert wait_for(
            lambda: early.gap() in (0.0, STILL_FRAME_GAP_MS), timeout=STREAM_STOPPED_S + 5
        )
        _stream(sc, count=5, gap_s=0.002)  # (after a pause it starts as a slow stream)
        assert wait_for(lambda: early.gap() in (0.0, SLOW_FRAME_GAP_MS)), "the next pose wakes it"
        late.stop.set()
    finally:
        early.stop.set()
        sc.close()
        server.stop()


def test_a_still_scene_is_drawn_rarely_and_the_next_update_frees_the_frames(monkeypatch):
    """Once nothing was sent to a loaded page for STILL_AFTER_S it is told the still gap; a page
    still loading is not; the next update (of the scene, or of one page's camera) first tells
    every still page the gap back, before the update itself reaches it."""
    monkeypatch.setattr(_scene_frames, "LOADING_S", 1.0)
    monkeypatch.setattr(_scene_frames, "STILL_AFTER_S", 0.5)
    port = free_port()
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    sc = StudioScene(server, body=HumanBody("right"), layout=SceneLayout(**SLOW))
    page = _ScriptWatch(port)
    try:
        assert wait_for(lambda: page.gap() == STILL_FRAME_GAP_MS), page.scripts[-1:]
        assert sc.frames.still_pages() == 1
        asked = threading.Event()

        class Loading(float):
            """LOADING_S, telling when the pacer's still pass weighs a page's age against it."""

            def __gt__(self, age: object) -> bool:  # `age < LOADING_S` asks this one first
                asked.set()
                return float.__gt__(self, age)

        monkeypatch.setattr(_scene_frames, "LOADING_S", Loading(60.0))
        loading = _ScriptWatch(port)  # connects to the still scene: it loads, drawing freely
        assert asked.wait(20), "the pacer never weighed the loading page"
        assert loading.gap() is None, loading.scripts
        _stream(sc, count=3, gap_s=0.002)  # a pose
        awake = (0.0, SLOW_FRAME_GAP_MS)  # (after a pause a stream starts as a slow one)
        assert wait_for(lambda: page.gap() in awake), "the update woke the still page"
        assert STILL_FRAME_GAP_MS not in loading.gaps(), "a loading page is never still"
        loading.stop.set()
        monkeypatch.setattr(_scene_frames, "LOADING_S", 1.0)
        assert wait_for(lambda: page.gap() == STILL_FRAME_GAP_MS), "still again after"
        for client in server.get_clients().values():  # one page's camera moves
            client.camera.position = (3.0, -1.0, 2.0)
        assert wait_for(lambda: page.gap() in awake), "a camera update wakes it too"
    finally:
        page.stop.set()
        sc.close()
        server.stop()


def test_between_a_slow_streams_poses_the_scene_is_still(monkeypatch):
    """A slow stream's poses 0.8 s apart (a camera without a GPU: about one a second): once a
    pose is drawn and settled (SLOW_STILL_AFTER_S without a message) the page is told the still
    gap, so viser's idle frame is not drawn between poses; each next pose wakes it to the slow
    gap first."""
    monkeypatch.setattr(_scene_frames, "LOADING_S", 0.0)  # the page counts as loaded at once
    monkeypatch.setattr(_scene_frames, "STILL_AFTER_S", 60.0)  # stills here come from the stream
    port = free_port()
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    sc = StudioScene(server, body=HumanBody("right"), layout=SceneLayout(**SLOW))
    page = _ScriptWatch(port)
    try:
        assert wait_for(lambda: len(server.get_clients()) == 1), "the page never connected"
        _stream(sc, count=8, gap_s=0.8)
        gaps = page.gaps()
        assert SLOW_FRAME_GAP_MS in gaps, gaps
        during = gaps[gaps.index(SLOW_FRAME_GAP_MS) :]
        assert during.count(STILL_FRAME_GAP_MS) >= 4, during
        assert all(a != b for a, b in itertools.pairwise(during)), (
            f"still, woken, in turn: {during}"
        )
        assert set(during) == {SLOW_FRAME_GAP_MS, STILL_FRAME_GAP_MS}, during
    finally:
        page.stop.set()
        sc.close()
        server.stop()
