"""The API refuses changes from another site's page (Origin, else Referer), lets command-line
clients (no Origin) through, and requires the token when one is set; beyond loopback the studio
does not start without one."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from studio.web import Settings
from studio.web._guard import API_TOKEN_COOKIE, SiteRule
from studio.web._serve import ServeError, serve

EVIL = "http://evil.example"
SAMPLE = Path(__file__).resolve().parents[2] / "studio" / "samples"


def _recording_bytes() -> bytes:
    return next(SAMPLE.glob("*.tape.csv")).read_bytes()


@pytest.mark.parametrize(
    ("method", "path", "kwargs", "own_status"),
    [
        ("POST", "/api/capture/stop", {}, 409),
        ("POST", "/api/watch/stop", {}, 204),
        ("PUT", "/api/source/retarget", {"json": {"mode": "joint"}}, 200),
        ("DELETE", "/api/recordings/nothing-here", {}, 404),
        ("PATCH", "/api/recordings/nothing-here", {"json": {"notes": "x"}}, 404),
    ],
)
def test_a_change_from_another_site_is_refused(
    client: TestClient, method: str, path: str, kwargs: dict, own_status: int
) -> None:
    refused = client.request(method, path, headers={"Origin": EVIL}, **kwargs)
    assert refused.status_code == 403
    assert "another site" in refused.json()["detail"]
    by_referer = client.request(method, path, headers={"Referer": f"{EVIL}/page"}, **kwargs)
    assert by_referer.status_code == 403
    # the studio's own page, and a command-line client that sends neither header
    own = client.request(method, path, headers={"Origin": "http://testserver"}, **kwargs)
    assert own.status_code == own_status
    assert client.request(method, path, **kwargs).status_code == own_status


def test_a_cross_site_upload_stores_nothing(client: TestClient, tmp_path: Path) -> None:
    files = {"file": ("mine.tape.csv", _recording_bytes(), "text/csv")}
    refused = client.post("/api/recordings", files=files, headers={"Origin": EVIL})
    assert refused.status_code == 403
    assert list((tmp_path / "recordings").iterdir()) == []
    ok = client.post("/api/recordings", files=files, headers={"Origin": "http://testserver"})
    assert ok.status_code == 201
    assert [p.name for p in (tmp_path / "recordings").iterdir()] == ["mine.tape.csv"]


@pytest.mark.parametrize(
    "headers",
    [
        {"Origin": EVIL},
        {"Sec-Fetch-Site": "cross-site"},
        {"Origin": "http://127.0.0.1:1"},
        {"Sec-Fetch-Site": "same-site"},  # an <img> on another local port's page sends no Origin
    ],
)
def test_a_read_from_another_site_does_no_work(
    client: TestClient, headers: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """An export is minutes of CPU: any page could once start one with an ``<img>`` or a
    ``fetch`` (the sample names are always there to aim at). No CORS header is ever sent, so no
    other site's page could read an answer anyway: refusing it loses nothing."""
    from studio.web.routers import robots

    started: list[str] = []
    monkeypatch.setattr(robots, "export_for_robot", lambda *a, **k: started.append("export"))
    path = "/api/robot/export/recording/sample-reach-1?format=csv"
    refused = client.get(path, headers=headers)
    assert refused.status_code == 403 and "another site" in refused.json()["detail"]
    assert "access-control-allow-origin" not in refused.headers
    assert client.get("/api/capture", headers=headers).status_code == 403
    assert started == []
    # the studio's own page, a link typed into the address bar, a command-line client
    own_reads = (
        {"Origin": "http://testserver"},
        {"Sec-Fetch-Site": "same-origin"},
        {"Sec-Fetch-Site": "none"},
        {},
    )
    for own in own_reads:
        assert client.get("/api/capture", headers=own).status_code == 200
    assert client.get("/", headers={"Sec-Fetch-Site": "cross-site"}).status_code == 200


@pytest.mark.parametrize(
    ("origin", "ok"),
    [
        (None, True),
        ("http://127.0.0.1:8000", True),
        ("http://localhost:8000", True),
        ("http://[::1]:8000", True),
        ("http://testserver", True),  # the same host and port as the request (Jupyter's rule)
        ("https://127.0.0.1:8000", True),
        ("http://127.0.0.1:8080", False),  # another local program's page
        ("http://127.0.0.1", False),
        ("http://evil.example:8000", False),
        ("http://127.0.0.1.evil.example:8000", False),
        ("null", False),
        ("file://", False),
        ("http://127.0.0.1:notaport", False),
    ],
)
def test_origin_rule(origin: str | None, ok: bool) -> None:
    rule = SiteRule([*Settings().trusted_hosts(), "testserver"], {8000})
    assert rule.origin_ok(origin, host="testserver") is ok


def test_the_token_is_required_when_set(open_client: Callable[..., TestClient]) -> None:
    client = open_client(token="t0k-en")
    assert client.get("/api/config").status_code == 403
    assert client.get("/").status_code == 403
    assert client.get("/api/config?token=wrong").status_code == 403
    assert client.get("/api/config", headers={"Authorization": "token wrong"}).status_code == 403
    assert client.get("/api/config", headers={"Authorization": "token t0k-en"}).status_code == 200
    assert client.get("/api/config", headers={"Authorization": "Bearer t0k-en"}).status_code == 200
    page = client.get("/?token=t0k-en")
    assert page.status_code == 200
    cookie = API_TOKEN_COOKIE.format(port=8000)
    assert page.cookies.get(cookie) == "t0k-en"
    assert "HttpOnly" in page.headers["set-cookie"]
    # the client keeps the cookie: the page's later requests carry the token
    assert client.get("/api/config").status_code == 200
    assert client.post("/api/watch/stop").status_code == 204
    client.cookies.clear()
    assert client.post("/api/watch/stop").status_code == 403
    # the page embeds the scene with the token
    client.cookies.set(cookie, "t0k-en")
    assert client.get("/api/config").json()["viser_url"].endswith("?token=t0k-en")


def test_the_origin_rule_holds_with_the_token(open_client: Callable[..., TestClient]) -> None:
    client = open_client(token="t0k-en")
    r = client.post("/api/watch/stop?token=t0k-en", headers={"Origin": EVIL})
    assert r.status_code == 403


def test_serving_beyond_loopback_needs_a_token(tmp_path: Path) -> None:
    for host in ("0.0.0.0", "192.0.2.7"):
        with pytest.raises(ServeError, match="needs a token"):
            serve(Settings(host=host, data_dir=tmp_path, source=None), open_browser=False)
        with pytest.raises(ServeError, match="needs a token"):
            serve(Settings(host=host, data_dir=tmp_path, token=""), open_browser=False)


def _free_udp_port() -> int:
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_the_network_bridge_stays_on_loopback_in_token_mode(
    open_client: Callable[..., TestClient],
) -> None:
    """A studio served beyond loopback (with its token) still listens for bridge frames on
    loopback only, unless --bridge-host asks otherwise."""
    client = open_client(host="0.0.0.0", token="t0k-en")
    auth = {"Authorization": "token t0k-en"}
    r = client.put("/api/source", json={"kind": "network", "port": _free_udp_port()}, headers=auth)
    assert r.status_code == 200 and r.json()["error"] is None, r.text
    assert client.app.state.studio.pipeline.source.address[0] == "127.0.0.1"


def test_a_bridge_host_beyond_loopback_takes_only_signed_frames(
    open_client: Callable[..., TestClient],
) -> None:
    from studio.capture import simulate
    from studio.capture._network import FrameSender
    from tests.web.conftest import wait_for

    client = open_client(token="t0k-en", bridge_host="0.0.0.0")
    auth = {"Authorization": "token t0k-en"}
    r = client.put("/api/source", json={"kind": "network", "port": _free_udp_port()}, headers=auth)
    assert r.status_code == 200 and r.json()["error"] is None, r.text
    source = client.app.state.studio.pipeline.source
    host, port = source.address
    assert host == "0.0.0.0"
    frames = simulate(0.1, seed=2).frames
    with FrameSender("127.0.0.1", port) as stranger:  # no token: nothing reaches the tape
        for frame in frames:
            stranger.send(frame)
    assert wait_for(lambda: source.status().rejected >= len(frames))
    assert source.status().frames == 0
    with FrameSender("127.0.0.1", port, token="t0k-en") as owner:
        owner.send(frames[0])
    assert wait_for(lambda: source.status().frames == 1)


def test_a_bridge_beyond_loopback_needs_a_token(tmp_path: Path) -> None:
    with pytest.raises(ServeError, match="--bridge-host 0.0.0.0 .* needs a token"):
        serve(Settings(bridge_host="0.0.0.0", data_dir=tmp_path, source=None), open_browser=False)


def _serve_args(**given: object) -> argparse.Namespace:
    from studio.commands import serve as command

    parser = argparse.ArgumentParser()
    command.add_arguments(parser)
    argv = [f"--{k.replace('_', '-')}={v}" for k, v in given.items()]
    return parser.parse_args([*argv, "--no-browser"])


def test_the_command_generates_a_token_beyond_loopback(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    import studio.web
    from studio.commands import serve as command

    started: list[Settings] = []
    monkeypatch.setattr(
        studio.web, "serve", lambda settings, open_browser: started.append(settings)
    )
    monkeypatch.delenv(command.TOKEN_ENV, raising=False)
    command.run(_serve_args(host="0.0.0.0", data_dir=tmp_path))
    command.run(_serve_args(host="0.0.0.0", data_dir=tmp_path))
    first, second = started[0].token, started[1].token
    assert first and second and first != second and len(first) >= 32
    command.run(_serve_args(data_dir=tmp_path))
    assert started[-1].token is None  # loopback: no token unless asked
    monkeypatch.setenv(command.TOKEN_ENV, "from-env")
    command.run(_serve_args(host="0.0.0.0", data_dir=tmp_path))
    assert started[-1].token == "from-env"
    command.run(_serve_args(host="0.0.0.0", data_dir=tmp_path, token="given"))
    assert started[-1].token == "given"
    monkeypatch.delenv(command.TOKEN_ENV)
    command.run(_serve_args(data_dir=tmp_path, bridge_host="0.0.0.0"))  # the bridge signs with it
    assert started[-1].token and started[-1].bridge_host == "0.0.0.0"


def test_a_chunked_upload_is_stopped_at_the_limit(
    open_client: Callable[..., TestClient], tmp_path: Path
) -> None:
    """A body without Content-Length is counted as it streams in: 413 at the limit, and the
    server never reads (so never stores) more than the limit plus the multipart framing."""
    from studio.web._app import MULTIPART_OVERHEAD_BYTES

    limit = 200_000
    client = open_client(upload_limit_bytes=limit)
    chunk = b"0" * 65_536
    total = 20_000_000
    boundary = "studio-test-boundary"
    head = (
        f'--{boundary}\r\nContent-Disposition: form-data; name="file"; '
        'filename="big.tape.csv"\r\nContent-Type: text/csv\r\n\r\n'
    ).encode()
    read = 0
    messages: list[dict] = []

    async def receive() -> dict:
        nonlocal read
        if read == 0:
            read += len(head)
            return {"type": "http.request", "body": head, "more_body": True}
        if read >= total:
            return {"type": "http.request", "body": f"\r\n--{boundary}--\r\n".encode()}
        read += len(chunk)
        return {"type": "http.request", "body": chunk, "more_body": True}

    async def send(message: dict) -> None:
        messages.append(message)

    scope = {
        "type": "http",
        "asgi": {"version": "3.0"},
        "http_version": "1.1",
        "method": "POST",
        "scheme": "http",
        "path": "/api/recordings",
        "raw_path": b"/api/recordings",
        "root_path": "",
        "query_string": b"",
        "headers": [
            (b"host", b"testserver"),
            (b"content-type", f"multipart/form-data; boundary={boundary}".encode()),
            (b"transfer-encoding", b"chunked"),
        ],
        "client": ("127.0.0.1", 5000),
        "server": ("testserver", 80),
        "state": {},
    }
    client.portal.call(client.app, scope, receive, send)
    start = next(m for m in messages if m["type"] == "http.response.start")
    body = b"".join(m.get("body", b"") for m in messages if m["type"] == "http.response.body")
    assert start["status"] == 413, body
    assert "over the limit" in body.decode()
    assert read <= limit + MULTIPART_OVERHEAD_BYTES + len(chunk)
    assert list((tmp_path / "recordings").iterdir()) == []


def test_the_api_doc_gives_the_status_a_missing_token_gets(
    open_client: Callable[..., TestClient],
) -> None:
    client = open_client(token="t0k-en")
    status = client.get("/api/config").status_code
    doc = (Path(__file__).resolve().parents[2] / "docs" / "api.md").read_text()
    assert f"{status}: a missing or wrong token" in doc
    assert "401" not in doc  # no status the studio never answers
