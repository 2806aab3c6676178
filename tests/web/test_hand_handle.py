"""The hand guide's handle in the real scene: shown only for the hand source, placed on the
operator's hand, and dragging it moves the arm and the robot through the same function as the API."""

from __future__ import annotations

import numpy as np
import pytest
import viser
import viser.transforms as vtf
from fastapi.testclient import TestClient

from studio.kinematics import HumanArm, HumanBody
from studio.web import create_app
from studio.web.scene._scene import SceneLayout, StudioScene
from tests.conftest import free_port
from tests.web.conftest import make_settings


@pytest.fixture
def scene_client(tmp_path):
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    scene = StudioScene(server, body=HumanBody("right"), layout=SceneLayout(rate_hz=50.0))
    try:
        with TestClient(create_app(make_settings(tmp_path), scene)) as client:
            yield client, scene
    finally:
        scene.close()
        server.stop()


def test_the_handle_is_on_the_hand_and_dragging_it_moves_the_robot(scene_client) -> None:
    client, scene = scene_client
    handle = scene.hand_handle
    assert not handle.visible
    assert client.put("/api/source", json={"kind": "hand", "side": "left"}).status_code == 200
    assert handle.visible and scene.side == "left"
    worldMbase = scene._operator.worldMbase
    rest = worldMbase @ HumanArm("left").forward(np.zeros(7)).hand
    assert np.allclose(handle._handle.position, rest[:3, 3], atol=1e-6)

    before = client.get("/api/source").json()["q_robot"]
    baseMtarget = np.eye(4)
    baseMtarget[:3, :3] = HumanArm("left").forward(np.zeros(7)).hand[:3, :3]
    baseMtarget[:3, 3] = [0.3, 0.05, -0.3]
    worldMtarget = worldMbase @ baseMtarget
    handle.move(worldMtarget[:3, 3], vtf.SO3.from_matrix(worldMtarget[:3, :3]).wxyz)
    assert handle.moves == 1
    source = client.get("/api/source").json()
    assert source["frames"] == 1 and source["side"] == "left"
    assert np.abs(np.subtract(source["q_robot"], before)).max() > 0.1
    q_human = client.app.state.studio.pipeline._q_human
    reached = HumanArm("left").forward(q_human).hand[:3, 3]
    assert np.linalg.norm(reached - baseMtarget[:3, 3]) < 0.01

    assert client.put("/api/source", json={"kind": "simulator"}).status_code == 200
    assert not handle.visible
    handle.move(worldMtarget[:3, 3], vtf.SO3.from_matrix(worldMtarget[:3, :3]).wxyz)
    assert handle.moves == 1  # a hidden handle hands nothing on


def test_a_drag_released_out_of_reach_puts_the_handle_back_on_the_hand(scene_client) -> None:
    from types import SimpleNamespace

    client, scene = scene_client
    assert client.put("/api/source", json={"kind": "hand"}).status_code == 200
    handle = scene.hand_handle
    worldMbase = scene._operator.worldMbase
    far = worldMbase @ np.array([[1, 0, 0, 2.0], [0, 1, 0, 0.0], [0, 0, 1, 0.0], [0, 0, 0, 1]])
    gizmo = handle._handle
    gizmo.position = far[:3, 3]
    handle._dragged(SimpleNamespace(phase="end", target=gizmo))
    q_human = client.app.state.studio.pipeline._q_human
    hand = worldMbase @ HumanArm("right").forward(q_human).hand
    assert np.allclose(gizmo.position, hand[:3, 3], atol=1e-6)
    assert np.linalg.norm(hand[:3, 3] - far[:3, 3]) > 1.0  # the arm stopped short, as it must


@pytest.mark.parametrize(
    ("position", "wxyz"),
    [
        ((float("nan"), 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)),
        ((0.1, float("inf"), 0.0), (1.0, 0.0, 0.0, 0.0)),
        ((0.1, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0)),
    ],
)
def test_a_pose_that_is_not_one_is_put_back_and_never_passed_on(
    scene_client, monkeypatch, position, wxyz
) -> None:
    """The studio refused a scene client's NaN pose for the handle, but viser still passed
    ``[nan, 0, 0]`` on to the other browsers, and the handle was not put back."""
    import asyncio

    from viser import _messages

    from studio.web.scene._hand_handle import HANDLE_NAME

    client, scene = scene_client
    assert client.put("/api/source", json={"kind": "hand"}).status_code == 200
    gizmo = scene.hand_handle._handle
    before = (np.array(gizmo.position), np.array(gizmo.wxyz))
    api = scene.server.scene
    sent: list = []
    real_queue = api._queue_scene_message
    monkeypatch.setattr(api, "_queue_scene_message", lambda m: sent.append(m) or real_queue(m))
    message = _messages.TransformControlsUpdateMessage(
        name=HANDLE_NAME, wxyz=wxyz, position=position
    )
    # what viser does when a browser drags the handle: apply, call back, pass on to the others
    asyncio.run(api._handle_transform_controls_updates("a-browser", message))
    poses = [
        m
        for m in sent
        if isinstance(m, _messages.SetPositionMessage | _messages.SetOrientationMessage)
    ]
    assert poses, "nothing was sent back"
    for m in poses:
        value = np.array(getattr(m, "position", None) or m.wxyz, dtype=float)
        assert np.isfinite(value).all() and np.linalg.norm(value) > 0, m
    assert np.allclose(gizmo.position, before[0]) and np.allclose(gizmo.wxyz, before[1])
    put_back = [m for m in poses if getattr(m, "excluded_self_client", None) is None]
    assert put_back, "the sender's own handle was not put back"
    assert scene.hand_handle.refused == 1
    assert client.get("/api/source").json()["frames"] == 0  # nothing reached the arm
