"""Hostile files and datagrams through the API (issue 13, items 2, 3, 8, 13, 15): each file is
refused with a 4xx at a cost of a few MB and never hides the good files in a listing; a stray
datagram never ends a capture.

Memory is measured with ``tracemalloc`` around the request: the TestClient runs the app in this
process, and numpy and zlib allocations are traced, so decompressing or sizing anything from a
hostile header shows up as a peak of tens of MB or more.
"""

from __future__ import annotations

import io
import json
import socket
import tracemalloc
import zipfile
from pathlib import Path

import numpy as np
from numpy.lib import format as npy_format

from studio.capture import RecordingWriter, read_recording
from studio.capture._network import FrameSender
from studio.learning import ArmGrid, DynaQConfig
from studio.learning.tabular._policy import save_policy
from tests.capture.conftest import synthetic_frames
from tests.web.conftest import wait_for

PEAK_BYTES = 16 * 1024 * 1024
"""Most a refused upload may make the server allocate at once (the upload itself is < 1 MB)."""
BOMB_BYTES = 64 * 1024 * 1024
"""Zero bytes hidden in a bomb (they compress about 1000 to 1)."""
DEEP = 50_000


def _peak(send):
    tracemalloc.start()
    try:
        response = send()
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return response, peak


def _upload(client, route: str, name: str, content: bytes):
    return client.post(route, files={"file": (name, content, "application/octet-stream")})


def _recording(path: Path, frames: int = 50) -> Path:
    with RecordingWriter(path, 16, source="test") as writer:
        writer.write_many(synthetic_frames(frames))
    return path


def test_a_593_byte_recording_claiming_a_billion_regions_is_refused(client):
    for regions in (300_000, 1_000_000_000):
        meta = {"format": "teach-studio-recording", "version": 1, "regions": regions}
        body = "# teach-studio-recording " + json.dumps(meta) + "\n" + "t,frame,status\n"
        body += "0.0,0,0\n" * ((593 - len(body)) // 8)
        response, peak = _peak(
            lambda body=body: _upload(client, "/api/recordings", "bomb.tape.csv", body.encode())
        )
        assert response.status_code == 422, response.text
        assert "regions" in response.json()["detail"] and peak < PEAK_BYTES
    assert client.get("/api/recordings").status_code == 200


def _policy_members(tmp_path: Path) -> tuple[ArmGrid, dict[str, bytes]]:
    grid = ArmGrid(bins=5)
    path = tmp_path / "good.policy.npz"
    save_policy(path, grid, np.zeros((grid.n_states, grid.n_actions)), DynaQConfig())
    with zipfile.ZipFile(path) as archive:
        return grid, {name: archive.read(name) for name in archive.namelist()}


def _npz(members: dict[str, bytes], q_shape: tuple[int, ...], q_bytes: int) -> bytes:
    """A deflated .npz with the given members and a ``q.npy`` of ``q_bytes`` zero bytes."""
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in members.items():
            if name != "q.npy":
                archive.writestr(name, data)
        with archive.open("q.npy", "w", force_zip64=True) as q:
            npy_format.write_array_header_1_0(
                q, {"descr": "<f8", "fortran_order": False, "shape": q_shape}
            )
            chunk = bytes(1024 * 1024)
            for _ in range(q_bytes // len(chunk)):
                q.write(chunk)
            q.write(bytes(q_bytes % len(chunk)))
    return out.getvalue()


def test_a_zip_bomb_policy_is_refused_by_its_headers_before_inflating(client, tmp_path):
    grid, members = _policy_members(tmp_path)
    table = grid.n_states * grid.n_actions * 8
    rows = BOMB_BYTES // (grid.n_actions * 8)
    bombs = {
        # a table far larger than the JSON header's grid
        "shape": _npz(members, (rows, grid.n_actions), rows * grid.n_actions * 8),
        # the right shape, then megabytes the header does not account for
        "more 'q' data": _npz(members, (grid.n_states, grid.n_actions), table + BOMB_BYTES),
    }
    for words, content in bombs.items():
        assert len(content) < BOMB_BYTES // 100  # a small upload
        response, peak = _peak(
            lambda c=content: _upload(client, "/api/policies", "b.policy.npz", c)
        )
        assert response.status_code == 422, response.text
        assert words in response.json()["detail"] and peak < PEAK_BYTES
    good = _npz(members, (grid.n_states, grid.n_actions), table)
    assert _upload(client, "/api/policies", "good.policy.npz", good).status_code == 201
    assert [p["name"] for p in client.get("/api/policies").json()] == ["good"]


def test_a_policy_with_a_deeply_nested_header_is_a_422(client):
    out = io.BytesIO()
    np.savez(out, header=np.array("[" * DEEP + "]" * DEEP), q=np.zeros(1), greedy=np.zeros(1))
    response = _upload(client, "/api/policies", "deep.policy.npz", out.getvalue())
    assert response.status_code == 422 and "nests JSON" in response.json()["detail"]


def test_deeply_nested_files_in_the_data_folder_do_not_break_listings(client, tmp_path):
    folder = tmp_path / "recordings"
    folder.mkdir(exist_ok=True)
    _recording(folder / "good.tape.csv")
    deep = "[" * DEEP + "]" * DEEP
    (folder / "deep.tape.csv").write_text("# teach-studio-recording " + deep + "\n")
    (folder / "deep.demo.json").write_text(deep)
    recordings = client.get("/api/recordings")
    assert recordings.status_code == 200
    by_name = {r["name"]: r for r in recordings.json()}
    assert by_name["good"]["frames"] == 50 and by_name["good"]["error"] is None
    assert "nests JSON" in (by_name["deep"]["error"] or "")
    assert client.get("/api/demonstrations").status_code == 200


def test_a_recording_being_written_downloads_up_to_its_last_complete_row(client, tmp_path):
    folder = tmp_path / "recordings"
    folder.mkdir(exist_ok=True)
    path = folder / "live.tape.csv"
    writer = RecordingWriter(path, 16)
    try:
        writer.write_many(synthetic_frames(40))
        writer.flush()
        with path.open("ab") as torn:
            torn.write(b"0.4,40,0,0.25")  # a row whose write is under way
        response = client.get("/api/recordings/live/file")
    finally:
        writer.close()
    assert response.status_code == 200
    body = response.content
    assert int(response.headers["content-length"]) == len(body) and body.endswith(b"\n")
    assert path.read_bytes().startswith(body)
    copy = tmp_path / "copy.tape.csv"
    copy.write_bytes(body)
    assert len(read_recording(copy)) == 40
    assert 'filename="live.tape.csv"' in response.headers["content-disposition"]


def test_one_datagram_of_another_tape_does_not_end_a_capture(client):
    """Issue 13 item 8: a well-formed 3-region datagram during a 16-region capture."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    assert client.put("/api/source", json={"kind": "network", "port": port}).status_code == 200
    frames = synthetic_frames(60)
    with FrameSender("127.0.0.1", port) as sender:
        # capture from before the first frame, so every one of the 60 good frames is recorded
        assert client.post("/api/capture/start", json={"name": "mixed"}).status_code == 200
        for frame in frames[:30]:  # the stream's width is fixed by its first frame
            sender.send(frame)
        sender.send(synthetic_frames(1, regions=3)[0])
        for frame in frames[30:]:
            sender.send(frame)
    assert wait_for(lambda: client.get("/api/capture").json()["frames"] >= 60)
    capture = client.get("/api/capture").json()
    source = client.get("/api/source").json()
    assert capture["active"] and capture["name"] == "mixed"
    assert source["rejected"] == 1 and "3 regions" in source["warning"]
    stopped = client.post("/api/capture/stop")
    assert stopped.status_code == 200 and stopped.json()["frames"] == 60
