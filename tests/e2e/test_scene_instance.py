"""In a real browser, the page embeds only its own studio's scene (issue 10, "one studio, one
scene"): when the scene URL it is given answers another instance id (a second studio's scene
server) or is not a studio scene at all (a plain web server on that port), the page says so and
embeds nothing; when the scene is its own, it embeds it and says nothing.

The page is the studio app served in this process (no scene of its own); the scene port holds a
guarded viser server (:class:`studio.web._serve.SceneGuard`, as ``studio serve`` starts it) with
the page's instance id or another one, or a plain HTTP server.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import pytest

from studio.web import Settings, create_app
from studio.web._serve import SceneGuard
from tests.conftest import free_port
from tests.e2e.conftest import shot
from tests.web.conftest import make_settings, wait_for

pytestmark = pytest.mark.e2e

OUR_INSTANCE = "0123456789abcdef"
"""The instance id the page is told its scene answers."""
PAGE_READY_TIMEOUT_MS = 15_000


class _NotAScene(BaseHTTPRequestHandler):
    """Some other program on the scene's port: a web page for every path."""

    def do_GET(self) -> None:  # noqa: N802 - the http.server hook's name
        body = b"<!doctype html><title>Someone else</title><h1>Not a studio</h1>"
        self.send_response(200)
        self.send_header("Content-Type", "text/html")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, format: str, *args: Any) -> None:  # quiet
        return


def _plain_server(port: int) -> tuple[str, Any]:
    httpd = ThreadingHTTPServer(("127.0.0.1", port), _NotAScene)
    threading.Thread(target=httpd.serve_forever, daemon=True).start()

    def stop() -> None:
        httpd.shutdown()
        httpd.server_close()

    return f"http://127.0.0.1:{port}", stop


def _scene_server(port: int, api_port: int, instance: str) -> tuple[str, Any]:
    """A studio's guarded scene server (no drawing: the page only asks its instance id)."""
    import viser

    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    guard = SceneGuard(Settings().trusted_hosts(), {server.get_port(), api_port}, instance)
    guard.install(server)
    return f"http://127.0.0.1:{server.get_port()}", server.stop


@pytest.fixture
def studio_page(tmp_path, browser) -> Iterator[Any]:
    """Open the page of a studio whose scene URL points at the server ``kind`` starts there."""
    import uvicorn

    stops: list[Any] = []

    def open_page(kind: str) -> Any:
        api_port, scene_port = free_port(), free_port()
        if kind == "plain":
            scene_url, stop = _plain_server(scene_port)
        else:
            instance = OUR_INSTANCE if kind == "ours" else "fedcba9876543210"
            scene_url, stop = _scene_server(scene_port, api_port, instance)
        stops.append(stop)
        settings = make_settings(
            tmp_path, port=api_port, viser_url=scene_url, scene_instance=OUR_INSTANCE
        )
        http = uvicorn.Server(
            uvicorn.Config(
                create_app(settings), host="127.0.0.1", port=api_port, log_level="warning"
            )
        )
        thread = threading.Thread(target=http.run, daemon=True)
        thread.start()

        def stop_http() -> None:
            http.should_exit = True
            thread.join(30)

        stops.append(stop_http)
        assert wait_for(lambda: http.started, 30), "the studio page server did not start"
        context = browser.new_context(viewport={"width": 1280, "height": 800})
        stops.append(context.close)
        page = context.new_page()
        errors: list[str] = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(f"http://127.0.0.1:{api_port}/")
        page.wait_for_selector("body[data-ready='1']", timeout=PAGE_READY_TIMEOUT_MS)
        page.errors = errors  # type: ignore[attr-defined]
        page.scene_port = scene_port  # type: ignore[attr-defined]
        return page

    yield open_page
    for stop in reversed(stops):
        stop()


@pytest.mark.parametrize("kind", ["other-studio", "plain"])
def test_the_page_says_when_the_scene_is_not_its_own(studio_page, kind):
    page = studio_page(kind)
    message = page.locator("#scene-msg")
    assert message.is_visible()
    text = message.inner_text()
    assert "does not belong to this studio" in text
    assert str(page.scene_port) in text  # names the scene it found there
    assert not page.locator("#scene").get_attribute("src")  # nothing embedded
    assert page.errors == []
    shot(page, f"scene-not-ours-{kind}")


def test_the_page_embeds_its_own_scene_without_a_message(studio_page):
    page = studio_page("ours")
    assert not page.locator("#scene-msg").is_visible()
    src = page.locator("#scene").get_attribute("src") or ""
    assert f":{page.scene_port}" in src
    assert page.errors == []
