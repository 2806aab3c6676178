"""The live pipeline end to end: simulator -> kinematics -> status; capture and live marking."""

from __future__ import annotations

import time

from tests.web.conftest import wait_for


def test_the_simulator_drives_the_robot(open_client):
    client = open_client(source="simulator")
    assert wait_for(lambda: client.get("/api/source").json()["fit_residual_mm"] is not None)
    first = client.get("/api/source").json()
    assert first["kind"] == "simulator" and first["running"] and first["error"] is None
    assert wait_for(lambda: client.get("/api/source").json()["q_robot"] != first["q_robot"])
    # the page shows a live rate; its value is the source's own measurement (tested against a
    # fake clock in tests/capture/test_sources.py), and the pacing against the simulator's
    # deadlines in tests/capture/test_simulator.py, neither of which a busy machine can flake
    assert wait_for(lambda: client.get("/api/source").json()["rate_hz"] > 0)
    # frames keep coming: the count read at the first pose grows (awaited: on a busy machine the
    # rate can be measured before the next frame is counted)
    assert wait_for(lambda: client.get("/api/source").json()["frames"] > first["frames"])
    later = client.get("/api/source").json()
    assert later["fit_residual_mm"] < 30  # the simulated tape fits the arm model
    assert later["dropped"] == 0


def test_switching_sources_stops_the_old_one(open_client):
    client = open_client(source="simulator")
    assert wait_for(lambda: client.get("/api/source").json()["frames"] > 0)
    old = client.app.state.studio.pipeline.source
    r = client.put("/api/source", json={"kind": "simulator", "seed": 5})
    assert r.status_code == 200 and r.json()["kind"] == "simulator"
    assert not old.status().running
    assert wait_for(lambda: client.get("/api/source").json()["frames"] > 0)


def test_the_network_bridge_feeds_the_pipeline(client):
    import socket

    from studio.capture import simulate
    from studio.capture._network import FrameSender

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    r = client.put("/api/source", json={"kind": "network", "port": port})
    assert r.status_code == 200 and r.json()["kind"] == "network" and r.json()["error"] is None
    frames = simulate(0.5, seed=2).frames
    with FrameSender("127.0.0.1", port) as sender:
        for frame in frames:
            sender.send(frame)
            time.sleep(0.002)
    assert wait_for(lambda: client.get("/api/source").json()["frames"] >= len(frames) * 0.9)
    assert wait_for(lambda: client.get("/api/source").json()["fit_residual_mm"] is not None)
    # a second studio source on the same port cannot bind: the error shows, nothing crashes
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as squatter:
        squatter.bind(("127.0.0.1", 0))
        taken = squatter.getsockname()[1]
        r = client.put("/api/source", json={"kind": "network", "port": taken})
        assert r.status_code == 200 and r.json()["error"]
    assert client.get("/api/config").status_code == 200


def test_capture_events_while_recording(open_client):
    client = open_client(source="simulator")
    client.post("/api/capture/start", json={"name": "evented"})
    with client.stream("GET", "/api/events?max_seconds=0.8") as r:
        text = r.read().decode()
    client.post("/api/capture/stop")
    assert text.count("event: capture") >= 2
    assert '"active":true' in text and '"name":"evented"' in text


def test_malformed_bridge_datagrams_are_counted_not_fatal(client):
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    client.put("/api/source", json={"kind": "network", "port": port})
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sender:
        for _ in range(3):
            sender.sendto(b"garbage", ("127.0.0.1", port))
    assert wait_for(lambda: client.get("/api/source").json()["rejected"] == 3)
    source = client.get("/api/source").json()
    assert source["warning"] and source["running"]


def _play(open_client, tmp_path, frames, config):
    """A studio whose live source plays ``frames`` (looped) from a recording in its data dir."""
    from studio.capture import RecordingWriter

    (tmp_path / "recordings").mkdir(exist_ok=True)
    with RecordingWriter(tmp_path / "recordings" / "take.tape.csv", config=config) as writer:
        writer.write_many(frames)
    client = open_client()
    r = client.put("/api/source", json={"kind": "recording", "recording": "take", "loop": True})
    assert r.status_code == 200, r.text
    assert wait_for(lambda: client.get("/api/source").json()["fit_residual_mm"] is not None)
    # several fits, warm-started: the second pass over the frames has begun
    assert wait_for(lambda: client.get("/api/source").json()["frames"] > len(frames))
    return client


def test_a_tape_the_arm_cannot_follow_is_reported(open_client, tmp_path):
    import numpy as np

    from studio.capture import TapeFrame
    from studio.kinematics import TapeConfig

    config = TapeConfig()
    rng = np.random.default_rng(0)
    frames = [
        TapeFrame(t=i / 110, frame=i, bend=rng.uniform(-1.5, 1.5, 16), twist=rng.uniform(-1, 1, 16))
        for i in range(220)
    ]
    client = _play(open_client, tmp_path, frames, config)
    assert wait_for(lambda: client.get("/api/source").json()["warning"] is not None, 5)
    source = client.get("/api/source").json()
    assert "misses the tape" in source["warning"] and source["error"] is None
    assert source["running"]  # shown, not fatal
