"""The scene server answers only the studio's own Host and Origin, never opens viser's share
tunnel, answers its instance id, and requires the token when one is set. Real websocket and HTTP
clients against a real guarded viser server."""

from __future__ import annotations

import asyncio
import urllib.error
import urllib.request

import msgspec
import pytest
import viser
import websockets
from websockets.exceptions import InvalidStatus

from studio.web import Settings
from studio.web._serve import INSTANCE_PATH, TOKEN_COOKIE, SceneGuard, start_scene
from tests.conftest import free_port as _free_port
from tests.web.conftest import wait_for

SUBPROTOCOL = [f"viser-v{viser.__version__}"]


@pytest.fixture(scope="module", params=[None, "s3cret-token"], ids=["loopback", "token"])
def studio_scene(request):
    settings = Settings(
        port=_free_port(), viser_port=_free_port(), source=None, token=request.param
    )
    server, scene, guard = start_scene(settings)
    yield settings, server, guard
    scene.close()
    server.stop()


def _connect(port: int, origin: str | None, token: str | None = None, cookie: str | None = None):
    path = f"/?token={token}" if token else "/"
    headers = {"Cookie": cookie} if cookie else None
    return websockets.connect(
        f"ws://127.0.0.1:{port}{path}",
        origin=origin,
        subprotocols=SUBPROTOCOL,
        additional_headers=headers,
        open_timeout=5,
    )


def _get(url: str, headers: dict[str, str] | None = None):
    return urllib.request.urlopen(urllib.request.Request(url, headers=headers or {}), timeout=5)


def test_a_foreign_origin_cannot_open_the_websocket(studio_scene):
    settings, server, guard = studio_scene
    port = server.get_port()

    async def attempt() -> int:
        try:
            async with _connect(port, "http://evil.example", settings.token):
                return 101
        except InvalidStatus as err:
            return err.response.status_code

    before = guard.refused
    assert asyncio.run(attempt()) == 403
    assert guard.refused == before + 1


def test_a_share_request_opens_no_tunnel(studio_scene):
    settings, server, guard = studio_scene
    port = server.get_port()

    async def ask() -> None:
        async with _connect(port, f"http://localhost:{port}", settings.token) as ws:
            await ws.send(msgspec.msgpack.encode({"type": "ShareUrlRequest"}))
            assert await asyncio.to_thread(
                wait_for, lambda: guard.share_requests_refused >= 1, 5.0, 0.01
            )

    asyncio.run(ask())
    assert server._share_tunnel is None
    assert server.request_share_url() is None  # viser's own entry point refuses too
    assert server._share_tunnel is None


def test_a_foreign_host_is_refused_on_http(studio_scene):
    settings, server, _ = studio_scene
    q = f"?token={settings.token}" if settings.token else ""
    with pytest.raises(urllib.error.HTTPError) as err:
        _get(f"http://127.0.0.1:{server.get_port()}/{q}", {"Host": "evil.example"})
    assert err.value.code == 400
    with pytest.raises(urllib.error.HTTPError) as err:
        _get(f"http://127.0.0.1:{server.get_port()}/{q}", {"Origin": "http://evil.example:8000"})
    assert err.value.code == 403


def test_the_instance_id_is_answered_to_the_studio_page_only(studio_scene):
    settings, server, guard = studio_scene
    base = f"http://127.0.0.1:{server.get_port()}{INSTANCE_PATH}"
    url = f"{base}?token={settings.token}" if settings.token else base
    page = f"http://127.0.0.1:{settings.port}"
    with _get(url, {"Origin": page}) as r:
        assert r.headers["Access-Control-Allow-Origin"] == page
        assert msgspec.json.decode(r.read()) == {"instance": guard.instance}
    with pytest.raises(urllib.error.HTTPError) as err:
        _get(url, {"Origin": f"http://127.0.0.1:{_free_port()}"})  # another local page
    assert err.value.code == 403


@pytest.fixture(scope="module")
def token_scene():
    settings = Settings(port=_free_port(), viser_port=_free_port(), source=None, token="tok-3n")
    server, scene, guard = start_scene(settings)
    yield settings, server, guard
    scene.close()
    server.stop()


def test_the_token_is_required_when_set(token_scene):
    settings, server, _ = token_scene
    port = server.get_port()
    with pytest.raises(urllib.error.HTTPError) as err:
        _get(f"http://127.0.0.1:{port}/")
    assert err.value.code == 403
    with _get(f"http://127.0.0.1:{port}/?token={settings.token}") as r:
        assert r.status == 200
        cookie = r.headers["Set-Cookie"].split(";")[0]
    assert cookie == f"{TOKEN_COOKIE.format(port=min(port, settings.port))}={settings.token}"
    with _get(f"http://127.0.0.1:{port}/", {"Cookie": cookie}) as r:
        assert r.status == 200  # the page's files and websocket carry the cookie

    async def open_ws(token: str | None, cookie: str | None) -> int:
        try:
            async with _connect(port, f"http://localhost:{port}", token, cookie):
                return 101
        except InvalidStatus as err:
            return err.response.status_code

    assert asyncio.run(open_ws(None, None)) == 403
    assert asyncio.run(open_ws("wrong", None)) == 403
    assert asyncio.run(open_ws(None, cookie)) == 101


@pytest.mark.parametrize(
    ("origin", "ok"),
    [
        (None, True),
        ("http://127.0.0.1:8080", True),
        ("http://localhost:8000", True),
        ("http://[::1]:8080", True),
        ("http://127.0.0.1:9999", False),
        ("http://evil.example:8080", False),
        ("http://127.0.0.1.evil.example:8080", False),
        ("null", False),
        ("file://", False),
        ("http://127.0.0.1:notaport", False),
    ],
)
def test_origin_rule(origin, ok):
    guard = SceneGuard(Settings().trusted_hosts(), {8080, 8000}, instance="x")
    assert guard.origin_ok(origin) is ok


@pytest.mark.parametrize(
    ("host", "ok"),
    [
        ("127.0.0.1:8080", True),
        ("localhost:8080", True),
        ("[::1]:8080", True),
        ("LOCALHOST", True),
        ("evil.example:8080", False),
        ("", False),
        (None, False),
    ],
)
def test_host_rule(host, ok):
    guard = SceneGuard(Settings().trusted_hosts(), {8080}, instance="x")
    assert guard.host_ok(host) is ok
