"""The scene in a real browser: both bodies are drawn from meshes and framed by the default camera.

The studio's guarded scene runs in this process (so the test can hide one body at a time); the
browser opens it at the page's scene-pane size. Where each body lies on screen is the difference
between a screenshot with it and one without it; both must lie inside the viewport, the raised
hand included. Screenshots go to ``test-artifacts/e2e/``.
"""

from __future__ import annotations

import io
import time
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
import viser

from studio.kinematics import HumanArm, Puma560
from studio.web import Settings
from studio.web._serve import start_scene
from tests.e2e.conftest import ARTIFACTS, free_port

pytestmark = pytest.mark.e2e

VIEWPORT = {"width": 1000, "height": 560}
"""The page's scene pane at a 1440 x 900 window."""
SETTLE_TIMEOUT_S = 30.0
MIN_BODY_PIXELS = 2000
"""A body drawn at the default camera covers far more pixels than this."""
DIFF_LEVEL = 48
"""A pixel belongs to a body when hiding it changes a channel by more than this (of 255). viser
lowers its resolution when software rendering is slow, which shifts the floor's lines by less."""
STRAY_PERCENTILES = (0.2, 99.8)
"""A body's extent on screen, ignoring the odd stray pixel of a resolution change."""


@pytest.fixture(scope="module")
def scene() -> Iterator[Any]:
    settings = Settings(port=free_port(), viser_port=free_port(), source=None)
    server, sc, _ = start_scene(settings)
    try:
        yield sc
    finally:
        sc.close()
        server.stop()


@pytest.fixture(scope="module")
def scene_page(browser: Any, scene: Any) -> Iterator[Any]:
    context = browser.new_context(viewport=VIEWPORT)
    page = context.new_page()
    page.goto(f"http://127.0.0.1:{scene.server.get_port()}/")
    page.locator("canvas").first.wait_for(state="attached", timeout=60_000)
    deadline = time.monotonic() + SETTLE_TIMEOUT_S
    while not scene.server.get_clients() and time.monotonic() < deadline:
        time.sleep(0.05)
    # viser's software-WebGL notice is closed by the studio once the browser connects.
    page.wait_for_function(
        "() => !document.getElementById('webgl-software-rendering')", timeout=60_000
    )
    try:
        yield page
    finally:
        context.close()


def _pixels(page: Any) -> np.ndarray:
    from PIL import Image

    return np.asarray(
        Image.open(io.BytesIO(page.locator("canvas").first.screenshot())).convert("RGB")
    )


def _settled(page: Any, previous: np.ndarray | None = None) -> np.ndarray:
    """A screenshot once the view stops changing (and differs from ``previous``, if given)."""
    deadline = time.monotonic() + SETTLE_TIMEOUT_S
    last = _pixels(page)
    while time.monotonic() < deadline:
        now = _pixels(page)
        changed = previous is None or np.any(now != previous)
        if changed and np.array_equal(now, last):
            return now
        last = now
    raise AssertionError("the scene did not settle")


def _footprint(with_body: np.ndarray, without: np.ndarray) -> tuple[int, int, int, int, int]:
    """(pixels, x0, y0, x1, y1) of where two screenshots differ."""
    diff = np.any(np.abs(with_body.astype(int) - without.astype(int)) > DIFF_LEVEL, axis=2)
    ys, xs = np.nonzero(diff)
    if len(xs) == 0:
        return 0, 0, 0, 0, 0
    lo, hi = STRAY_PERCENTILES
    x0, x1 = np.percentile(xs, [lo, hi])
    y0, y1 = np.percentile(ys, [lo, hi])
    return len(xs), int(x0), int(y0), int(x1), int(y1)


def _shown(handles: list[Any], visible: bool) -> None:
    for h in handles:
        h.visible = visible


def test_both_models_are_meshes_and_framed(scene: Any, scene_page: Any) -> None:
    from PIL import Image

    # Drawn from meshes: every robot link and operator segment is a mesh node.
    robot_nodes = [h.name for h in scene._robot_handles]
    assert robot_nodes == [f"/robot/link{j}" for j in range(7)]
    assert all(isinstance(h, viser.MeshHandle) for h in scene._robot_handles)
    operator_nodes = [h.name for h in scene._operator_handles]
    assert len(operator_nodes) >= 20 and "/operator/right_hand/hand_mesh" in operator_nodes
    assert "/operator/middle_head/head_mesh" in operator_nodes
    assert all(isinstance(h, viser.MeshHandle) for h in scene._operator_handles)

    robot, arm = Puma560(), HumanArm("right")
    raised = arm.neutral.copy()
    raised[0] = arm.upper[0]  # the taped arm raised as high as it goes
    scene.update_live(raised, robot.qr, None)  # the robot up too: both at their tallest
    full = _settled(scene_page)
    Image.fromarray(full).save(ARTIFACTS / "scene-models.png")
    height, width = full.shape[:2]
    ghosts = scene._ghost_handles
    _shown(ghosts, False)
    for name, handles in (("robot", scene._robot_handles), ("operator", scene._operator_handles)):
        _shown(handles, False)
        without = _settled(scene_page, full)
        _shown(handles, True)
        again = _settled(scene_page, without)
        pixels, x0, y0, x1, y1 = _footprint(again, without)
        assert pixels > MIN_BODY_PIXELS, f"the {name} is not drawn"
        # framed: inside the viewport with room to spare on every side
        assert x0 > 0 and x1 < width - 1 and y0 > 0 and y1 < height - 1, (name, x0, y0, x1, y1)
        full = again
    Image.fromarray(full).save(ARTIFACTS / "scene-models-raised.png")


def test_reset_view_returns_to_the_default_camera(scene: Any, scene_page: Any) -> None:
    (client,) = scene.server.get_clients().values()
    client.camera.position = (4.0, 4.0, 4.0)  # the user wandered off
    client.camera.look_at = (3.0, 3.0, 0.0)
    deadline = time.monotonic() + SETTLE_TIMEOUT_S
    while np.allclose(client.camera.position, scene.layout.camera_position, atol=1e-3):
        assert time.monotonic() < deadline, "the camera did not move"
        time.sleep(0.05)
    # viser's panel is folded into a rail beside the scene: unfold it to reach the button.
    reset = scene_page.get_by_role("button", name="Reset view")
    if not reset.is_visible():
        scene_page.get_by_role("button", name="Expand column").click()
    reset.click()

    def back() -> bool:  # the page reports position and look-at as its camera moves: wait for both
        return np.allclose(
            client.camera.position, scene.layout.camera_position, atol=1e-3
        ) and np.allclose(client.camera.look_at, scene.layout.camera_look_at, atol=1e-3)

    while not back():
        assert time.monotonic() < deadline, (
            "Reset view did not bring the camera back: "
            f"at {client.camera.position}, looking at {client.camera.look_at}"
        )
        time.sleep(0.05)
