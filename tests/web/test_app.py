"""The app shell: config, the host guard, the page and its vendored libraries served locally, error shapes."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from studio.web import Settings, create_app
from studio.web._app import STATIC_DIR
from studio.web._settings import get_settings, is_loopback
from tests.web.conftest import make_settings


def test_config_tells_the_page_the_scene_url_and_limit(client, tmp_path):
    config = client.get("/api/config").json()
    assert config["viser_url"] == "http://127.0.0.1:8080"
    assert config["upload_limit_bytes"] == 50_000_000
    assert Path(config["data_dir"]) == tmp_path.resolve()


def test_settings_are_served_through_an_overridable_dependency(tmp_path):
    app = create_app(make_settings(tmp_path))
    app.dependency_overrides[get_settings] = lambda: make_settings(
        tmp_path, viser_port=9999, upload_limit_bytes=123
    )
    with TestClient(app) as client:
        config = client.get("/api/config").json()
    assert config["viser_url"].endswith(":9999") and config["upload_limit_bytes"] == 123


@pytest.mark.parametrize(
    "host", ["evil.example", "evil.example:8000", "127.0.0.1.evil.example", "attacker:80"]
)
def test_requests_for_other_host_names_are_refused(client, host):
    assert client.get("/api/config", headers={"host": host}).status_code == 400
    assert client.get("/api/runs", headers={"host": host}).status_code == 400


@pytest.mark.parametrize("host", ["127.0.0.1:8000", "localhost:8000", "localhost", "testserver"])
def test_loopback_host_names_are_served(client, host):
    assert client.get("/api/config", headers={"host": host}).status_code == 200


def test_testserver_is_refused_unless_allowed(tmp_path):
    with TestClient(create_app(Settings(data_dir=tmp_path, source=None))) as client:
        assert client.get("/api/config").status_code == 400
        assert client.get("/api/config", headers={"host": "127.0.0.1:8000"}).status_code == 200


def test_an_opened_up_host_still_checks_names(tmp_path):
    settings = make_settings(tmp_path, host="0.0.0.0", allowed_hosts=("testserver", "lab-pc"))
    with TestClient(create_app(settings)) as client:
        assert client.get("/api/config", headers={"host": "lab-pc:8000"}).status_code == 200
        assert client.get("/api/config", headers={"host": "evil.example"}).status_code == 400
        assert client.get("/api/config").json()["viser_url"] == "http://127.0.0.1:8080"


def test_loopback_detection():
    assert is_loopback("127.0.0.1") and is_loopback("localhost") and is_loopback("::1")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.1.5")
    assert Settings().is_loopback and not Settings(host="0.0.0.0").is_loopback


def test_the_page_loads_only_local_files_and_they_are_served(client):
    """Every script and stylesheet of the page is served by the studio: nothing from a CDN."""
    html = (STATIC_DIR / "index.html").read_text()
    refs = re.findall(r'<(?:script|link)[^>]*\b(?:src|href)="([^"]+)"', html)
    assert any("uPlot" in ref for ref in refs), "the chart library is not loaded"
    for ref in refs:
        if ref.startswith("data:"):
            continue
        assert ref.startswith("/"), f"{ref} is not served by the studio"
        r = client.get(ref)
        assert r.status_code == 200, ref
        assert r.content == (STATIC_DIR / ref.removeprefix("/static/")).read_bytes()


def test_the_page_and_static_files(client):
    page = STATIC_DIR / "index.html"
    r = client.get("/")
    if page.is_file():
        assert r.status_code == 200 and r.content == page.read_bytes()
        assert "text/html" in r.headers["content-type"]
    else:
        assert r.status_code == 404 and "page is missing" in r.json()["detail"]
    assert client.get("/static/../../_app.py").status_code == 404
    assert client.get("/static/no-such-file.js").status_code == 404


@pytest.mark.parametrize("page", ["/docs", "/redoc"])
def test_the_api_docs_work_offline(client, page):
    """The API pages load their scripts and styles from the studio, not from a CDN."""
    html = client.get(page).text
    refs = re.findall(r"""(?:src|href|url)\s*[=:(]\s*['"]([^'"]+)['"]""", html)
    assert any(ref.endswith(".js") for ref in refs), refs
    for ref in refs:
        assert not ref.startswith(("http:", "https:", "//")), (
            f"{page} loads {ref} from the internet"
        )
        if ref.endswith((".js", ".css")):
            r = client.get(ref)
            assert r.status_code == 200 and len(r.content) > 10_000, ref


def test_openapi_docs_list_every_resource(client):
    assert client.get("/docs").status_code == 200
    paths = client.get("/openapi.json").json()["paths"]
    for path in (
        "/api/config",
        "/api/source",
        "/api/source/playback",
        "/api/source/retarget",
        "/api/capture/start",
        "/api/capture/stop",
        "/api/recordings",
        "/api/recordings/{name}",
        "/api/demonstrations",
        "/api/demonstrations/mark",
        "/api/runs",
        "/api/runs/{run_id}/curve",
        "/api/runs/{run_id}/policy",
        "/api/policies",
        "/api/watch",
        "/api/events",
    ):
        assert path in paths, path


TYPED_TAGS = {"recordings", "demonstrations", "policies", "source", "capture", "watch"}
"""Routers whose every JSON answer must be a declared ``*Public`` model."""


def test_json_answers_are_declared_models(client):
    """A route that answers JSON documents its model, so /docs shows every field (issue 9)."""
    checked = 0
    for path, methods in client.get("/openapi.json").json()["paths"].items():
        for method, op in methods.items():
            if not TYPED_TAGS & set(op.get("tags", [])):
                continue
            for status, answer in op["responses"].items():
                schema = answer.get("content", {}).get("application/json", {}).get("schema")
                if schema is None or not status.startswith("2"):
                    continue
                if path.endswith(("/file", ".csv")):  # downloads are files, not JSON
                    continue
                ref = schema.get("$ref") or schema.get("items", {}).get("$ref", "")
                assert ref.endswith("Public") or ref.endswith("Detail"), (method, path, schema)
                checked += 1
    assert checked >= 15


def test_malformed_bodies_get_one_sentence(client):
    r = client.post("/api/runs", content=b"{not json", headers={"content-type": "application/json"})
    assert r.status_code == 422 and isinstance(r.json()["detail"], str)
    r = client.post("/api/runs", json=[1, 2])
    assert r.status_code == 422 and "JSON object" in r.json()["detail"]
    r = client.put("/api/source", json={})
    assert r.status_code == 422 and r.json()["detail"] == "kind is missing; add it to the request."
    r = client.put("/api/source", json={"kind": "telepathy"})
    assert r.status_code == 422 and r.json()["detail"].startswith("kind is 'telepathy'")


def test_source_without_a_source(client):
    source = client.get("/api/source").json()
    assert source["kind"] is None and source["running"] is False
    assert source["q_robot"] == [0.0] * 6 and source["recording_active"] is False
    r = client.post("/api/source/playback", json={"action": "play"})
    assert r.status_code == 409 and "not a recording" in r.json()["detail"]
    r = client.put("/api/source/retarget", json={"mode": "cartesian", "mirror": False})
    assert r.status_code == 200 and r.json()["retarget"] == {"mode": "cartesian", "mirror": False}
    assert client.put("/api/source/retarget", json={"mode": "x"}).status_code == 422


def test_capture_needs_a_source(client):
    assert client.get("/api/capture").json() == {
        "active": False,
        "name": None,
        "seconds": 0.0,
        "frames": 0,
        "rejected": 0,
        "error": None,
    }
    r = client.post("/api/capture/start", json={})
    assert r.status_code == 409 and "no live source" in r.json()["detail"]
    r = client.post("/api/capture/stop")
    assert r.status_code == 409 and "No recording is running" in r.json()["detail"]
    r = client.post("/api/demonstrations/mark", json={"action": "start"})
    assert r.status_code == 409 and "press Record" in r.json()["detail"]


def test_events_stream_source_status(client):
    with client.stream("GET", "/api/events?max_seconds=0.8") as r:
        text = r.read().decode()
    assert text.count("event: source") >= 3
    assert "event: run" not in text


def test_events_report_list_changes(client):
    seen = []
    with client.stream("GET", "/api/events?max_seconds=2") as r:
        for line in r.iter_lines():
            if line.startswith("event: source") and not seen:
                seen.append("source")
                client.post("/api/runs", json={"planning": "zero", "experiments": 1, "episodes": 2})
            if line.startswith("data: ") and "changed" in line:
                seen.append(line)
    assert 'data: {"changed":"runs"}' in seen


def test_reach_needs_the_simulator(client):
    r = client.post("/api/source/reach", json={"goal_deg": [0, 45, -90]})
    assert r.status_code == 409 and "not the simulator" in r.json()["detail"]
    assert client.post("/api/source/reach", json={"action": "dance"}).status_code == 422


def test_the_page_listens_where_the_bridge_sends_by_default():
    """`studio bridge --to HOST:PORT` and the page's network source agree on the default port."""
    import inspect

    from studio.capture import NetworkSource

    html = (STATIC_DIR / "index.html").read_text()
    field = re.search(r'<input id="source-port"[^>]*>', html)
    assert field is not None
    default = inspect.signature(NetworkSource).parameters["port"].default
    assert re.search(r'value="(\d+)"', field.group(0)).group(1) == str(default)
