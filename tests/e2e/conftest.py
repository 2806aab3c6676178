"""Browser-test set-up: the real ``studio serve`` in a subprocess and Debian's Chromium.

The server gets random free ports and a temporary data directory (with the repo's sample
recordings copied in); one browser and one page serve the whole session of a worker, so the
stories run in order like a user's visit (the files that take the shared ``page`` all run on one
worker: ``tests/conftest.py`` hands them out as one unit). Pages leave the 3D scene out unless
a test looks at it (:func:`live_scene`, ``own_page(scene=True)``). Screenshots of each step go to
``test-artifacts/e2e/``.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import pytest

from studio.samples import SAMPLES_DIR
from tests.conftest import free_port, require

REPO = Path(__file__).resolve().parents[2]
ARTIFACTS = REPO / "test-artifacts" / "e2e"
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
]
SERVER_START_TIMEOUT_S = 90.0
LEFT_OUT_SCENE = "<!doctype html><title>3D scene left out of this test</title>"
"""What a page whose test does not look at the 3D scene gets in its place (:func:`leave_out_scene`)."""


class Studio:
    """A running ``studio serve`` and small helpers to ask its API directly."""

    def __init__(self, base: str, data_dir: Path, proc: subprocess.Popen[bytes], log: Path) -> None:
        self.base = base
        self.data_dir = data_dir
        self.proc = proc
        self.log = log

    def get(self, path: str) -> Any:
        with urllib.request.urlopen(self.base + path, timeout=10) as r:
            return json.loads(r.read() or b"null")

    def send(self, method: str, path: str, body: Any = None) -> Any:
        data = None if body is None else json.dumps(body).encode()
        req = urllib.request.Request(
            self.base + path, data=data, method=method, headers={"Content-Type": "application/json"}
        )
        with urllib.request.urlopen(req, timeout=30) as r:
            raw = r.read()
            return json.loads(raw) if raw else None

    def log_tail(self, n: int = 40) -> str:
        try:
            return "\n".join(self.log.read_text(errors="replace").splitlines()[-n:])
        except OSError:
            return ""


# package scope: closed with tests/e2e, so the sync Playwright loop does not outlive it
@pytest.fixture(scope="package")
def studio_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Studio]:
    """``studio serve`` on random free ports with a fresh data directory."""
    data_dir = tmp_path_factory.mktemp("studio-data")
    (data_dir / "recordings").mkdir()
    for sample in sorted(SAMPLES_DIR.glob("sample-*")):
        shutil.copy(sample, data_dir / "recordings" / sample.name)
    port, viser_port = free_port(), free_port()
    while viser_port == port:
        viser_port = free_port()
    log = data_dir / "server.log"
    cmd = [
        sys.executable,
        "-m",
        "studio",
        "serve",
        "--data-dir",
        str(data_dir),
        "--port",
        str(port),
        "--viser-port",
        str(viser_port),
        "--no-browser",
    ]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    with log.open("wb") as out:
        proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, cwd=data_dir, env=env)
    studio = Studio(f"http://127.0.0.1:{port}", data_dir, proc, log)
    deadline = time.monotonic() + SERVER_START_TIMEOUT_S
    while True:
        if proc.poll() is not None:
            pytest.fail(f"studio serve exited with {proc.returncode}:\n{studio.log_tail()}")
        try:
            studio.get("/api/config")
            break
        except (urllib.error.URLError, ConnectionError, TimeoutError):
            if time.monotonic() > deadline:
                proc.kill()
                pytest.fail(
                    f"studio serve did not answer in {SERVER_START_TIMEOUT_S} s:\n{studio.log_tail()}"
                )
            time.sleep(0.25)
    try:
        yield studio
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


# package scope: closed with tests/e2e, so the sync Playwright loop does not outlive it
@pytest.fixture(scope="package")
def browser() -> Iterator[Any]:
    """Debian's Chromium, headless, driven by Playwright (never ``playwright install``)."""
    require(
        os.path.exists(CHROMIUM), f"Chromium is not installed at {CHROMIUM} (apt install chromium)"
    )
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:  # pragma: no cover - the test extra installs it
        require(False, "playwright is not installed (pip install -e .[test])")
        raise
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_FLAGS, headless=True)
        try:
            yield b
        finally:
            b.close()


# package scope: closed with tests/e2e, so the sync Playwright loop does not outlive it
@pytest.fixture(scope="package")
def page(browser: Any, studio_server: Studio) -> Iterator[Any]:
    """The studio page, loaded once for the whole session (stories follow one another). Its 3D
    scene is left out (:func:`leave_out_scene`); a test shows it with :func:`live_scene` for
    the part that looks at it."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    context = browser.new_context(viewport={"width": 1440, "height": 900}, accept_downloads=True)
    left_out = leave_out_scene(context, studio_server)
    pg = context.new_page()
    pg.left_out_scene = left_out  # type: ignore[attr-defined]
    errors: list[str] = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.goto(studio_server.base + "/")
    pg.wait_for_selector("body[data-ready='1']", timeout=30_000)
    pg.errors = errors  # type: ignore[attr-defined]
    try:
        yield pg
    finally:
        context.close()


class LeftOutScene:
    """The 3D scene of a browser context served as :data:`LEFT_OUT_SCENE` (its instance check
    still reaches the studio), until :meth:`let_in` lets the real one through again."""

    def __init__(self, context: Any, studio: Studio) -> None:
        self.context = context
        self.studio = studio
        port = urlsplit(studio.get("/api/config")["viser_url"]).port
        # a pattern, not a function: the browser then asks Playwright about the scene's
        # requests only, not about every request of the page
        self._scene = re.compile(rf"^[a-z]+://[^/]+:{port}/(?!studio-instance(?:$|[?#]))")
        self.left_out = False
        self.leave_out()

    @staticmethod
    def _blank(route: Any) -> None:
        route.fulfill(status=200, content_type="text/html", body=LEFT_OUT_SCENE)

    def leave_out(self) -> None:
        """Serve the blank page for the scene from now on."""
        if not self.left_out:
            self.context.route(self._scene, self._blank)
            self.left_out = True

    def let_in(self) -> None:
        """Let the real scene through from now on."""
        if self.left_out:
            self.context.unroute(self._scene, self._blank)
            self.left_out = False


def leave_out_scene(context: Any, studio: Studio) -> LeftOutScene:
    """Serve :data:`LEFT_OUT_SCENE` for the 3D scene's page and files in ``context`` (its
    instance check still reaches the studio). Here WebGL is drawn in software: a live scene
    costs the browser most of a core while the simulator streams, which a test that does not
    look at the scene only takes from the tests beside it."""
    return LeftOutScene(context, studio)


def _scene_clients(studio: Studio) -> int:
    """How many browsers show the studio's scene now (each reports its camera)."""
    return len(studio.get("/api/scene/views")["cameras"])


def _reload_scene_frame(page: Any) -> None:
    """Load the page's scene iframe again from the URL the page gave it, the page left as it is."""
    page.wait_for_function("() => document.querySelector('#scene').src !== ''")
    src = page.locator("#scene").get_attribute("src")
    page.locator("#scene").element_handle().content_frame().goto(src, wait_until="load")


@contextmanager
def live_scene(page: Any) -> Iterator[Any]:
    """The real 3D scene in the shared ``page`` (which leaves it out) while the block runs:
    its iframe alone is loaded again (the stories on the page keep their state), and the block
    starts once the scene is drawn (its canvas visible) and connected (the studio has its
    camera). Yields the scene's frame locator. Afterwards the scene is left out again and its
    iframe made blank, once the studio has seen it go."""
    from tests.web.conftest import wait_for

    left_out: LeftOutScene = page.left_out_scene
    studio = left_out.studio
    left_out.let_in()
    try:
        _reload_scene_frame(page)
        frame = page.frame_locator("#scene")
        frame.locator("canvas").first.wait_for(state="visible", timeout=60_000)
        assert wait_for(lambda: _scene_clients(studio) >= 1, 60), "the scene never connected"
        yield frame
    finally:
        left_out.leave_out()
        _reload_scene_frame(page)
    assert wait_for(lambda: _scene_clients(studio) == 0, 60), "the left-out scene stayed connected"


@contextmanager
def own_page(
    browser: Any,
    studio: Studio,
    width: int = 1440,
    height: int = 900,
    *,
    scene: bool = False,
    **options: Any,
) -> Iterator[Any]:
    """A page of its own on the studio, ready, at ``width`` x ``height``; ``page.errors`` holds
    its script errors. Its 3D scene is left out (:func:`leave_out_scene`) unless ``scene``. Its
    browser context is closed afterwards."""
    context = browser.new_context(viewport={"width": width, "height": height}, **options)
    if not scene:
        leave_out_scene(context, studio)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    try:
        page.goto(studio.base + "/")
        page.wait_for_selector("body[data-ready='1']", timeout=60_000)
        page.errors = errors
        yield page
    finally:
        context.close()


@contextmanager
def serve_app(app: Any, port: int) -> Iterator[str]:
    """Serve a studio app made in this process (so a test can reach inside it) with uvicorn on
    loopback ``port``, in a thread; yields its base URL, and stops it afterwards."""
    import uvicorn

    from tests.web.conftest import wait_for

    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning"))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    try:
        assert wait_for(lambda: server.started, 60), "the studio app did not start serving"
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(30)


@pytest.fixture
def blank_page(browser: Any) -> Iterator[Any]:
    """A page of its own (1440 x 900, downloads allowed) with nothing loaded yet; ``page.errors``
    holds its script errors. Its browser context is closed afterwards."""
    context = browser.new_context(viewport={"width": 1440, "height": 900}, accept_downloads=True)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.errors = errors
    try:
        yield page
    finally:
        context.close()


WATCH_RESULT = "[data-testid='watch-result']"
WATCH_ERROR = "[data-testid='watch-error']"


def watched(page: Any, click: Any, timeout_ms: float) -> str:
    """The Watch result line after ``click()`` (the Watch button, a policy row's Watch): a fresh
    one, not the line of the watch before, with no error beside it."""
    page.evaluate(f"document.querySelector({json.dumps(WATCH_RESULT)}).textContent = ''")
    click()
    page.wait_for_selector(f"{WATCH_RESULT}:has-text(' steps, ')", timeout=timeout_ms)
    assert not page.is_visible(WATCH_ERROR), page.inner_text(WATCH_ERROR)
    return page.inner_text(WATCH_RESULT)


def watch_policy(page: Any, key: str, seed: int, timeout_ms: float) -> str:
    """Watch the policy ``key`` (``run:ID``, or a listed policy's option) from the random start
    ``seed`` with the page's Watch controls, as a person would; its result line."""
    page.select_option("[data-testid='watch-policy']", key)
    page.select_option("[data-testid='watch-start']", "random")
    page.fill("[data-testid='watch-seed']", str(seed))
    return watched(page, lambda: page.click("[data-testid='watch-go']"), timeout_ms)


def shot(page: Any, name: str, section: str | None = None) -> Path:
    """Save a screenshot of the page under ``test-artifacts/e2e/``, ``section`` scrolled into view."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    if section:
        page.locator(f"#{section}").scroll_into_view_if_needed()
    path = ARTIFACTS / f"{name}.png"
    page.screenshot(path=str(path))
    return path


def pose_by_hand(page: Any, unfolded: bool = True) -> None:
    """Unfold (or fold) the Watch panel's "Pose by hand" as a person would: by clicking its title,
    only when it is not so already (stories share one page, and one may leave it open)."""
    details = page.get_by_test_id("jog")
    if (details.get_attribute("open") is not None) != unfolded:
        page.get_by_text("Pose by hand").click()
