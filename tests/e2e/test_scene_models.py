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
    # viser's own notices (software WebGL, connection) cover parts of the view: close them.
    for button in page.locator("button.mantine-Notification-closeButton").all():
        button.click()
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
    diff = np.any(np.abs(with_body.astype(int) - without.astype(int)) > 12, axis=2)
    ys, xs = np.nonzero(diff)
    if len(xs) == 0:
        return 0, 0, 0, 0, 0
    return len(xs), int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max())


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
