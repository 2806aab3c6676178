"""Browser: the train form's "Add obstacle" puts a box in the scene, sized in the form, listed
where its handle stands, and sent with the run the form starts (issue 40)."""

from __future__ import annotations

import json
from typing import Any

import pytest

from tests.e2e.conftest import Studio
from tests.web.conftest import wait_for

pytestmark = pytest.mark.e2e

T = 60_000  # ms: the longest a single UI step may take on a busy machine


def _boxes(studio: Studio) -> list[dict]:
    return studio.get("/api/scene/obstacles")["obstacles"]


def _stored_with_obstacles(studio: Studio) -> list[dict]:
    found = []
    for config in (studio.data_dir / "runs").glob("*/config.json"):
        task = json.loads(config.read_text()).get("task", {})
        if task.get("obstacles"):
            found.append(task)
    return found


def test_add_an_obstacle_size_it_and_train_around_it(page: Any, studio_server: Studio) -> None:
    row = "[data-testid='obstacle-row']"
    try:
        page.click("[data-testid='train-add-obstacle']")
        page.wait_for_selector(row, timeout=T)
        assert page.locator(row).count() == 1
        assert wait_for(lambda: _boxes(studio_server), 60)
        assert len(_boxes(studio_server)) == 1  # drawn in the scene, with its handle

        # sized in the form: the scene's box follows
        page.fill("[data-testid='obstacle-0-size-0']", "0.2")
        page.press("[data-testid='obstacle-0-size-0']", "Tab")
        assert wait_for(lambda: _boxes(studio_server)[0]["size"][0] == 0.2, 60)

        # a size that is no size: one sentence under the list, and the box keeps its size
        page.fill("[data-testid='obstacle-0-size-1']", "0")
        page.press("[data-testid='obstacle-0-size-1']", "Tab")
        error = page.wait_for_selector("[data-testid='obstacle-error']:visible", timeout=T)
        assert "above zero" in error.inner_text() and error.inner_text().count(".") == 1
        assert _boxes(studio_server)[0]["size"] == [0.2, 0.15, 0.15]
        page.wait_for_function(
            "() => document.querySelector(\"[data-testid='obstacle-0-size-1']\").value === '0.15'",
            timeout=T,
        )

        # moved in the scene (what dragging its handle does to the scene's boxes): the form
        # lists it where it stands now
        moved = {**_boxes(studio_server)[0], "centre": [0.55, 0.45, 0.85]}
        studio_server.send("PUT", "/api/scene/obstacles", {"obstacles": [moved]})
        page.wait_for_function(
            "() => document.querySelector(\"[data-testid='obstacle-0-centre']\")"
            ".textContent.includes('0.55, 0.45, 0.85')",
            timeout=T,
        )

        # a small grid run: the box goes with it into its config.json
        page.fill("[data-testid='train-bins']", "5")
        page.fill("[data-testid='train-episodes']", "3")
        page.fill("[data-testid='train-experiments']", "1")
        before = len(_stored_with_obstacles(studio_server))
        page.click("[data-testid='train-start']")
        ran = wait_for(lambda: _stored_with_obstacles(studio_server)[before:], 180)
        assert ran, page.inner_text("[data-testid='train-error']")
        stored = _stored_with_obstacles(studio_server)[before:]
        assert stored[0]["obstacles"] == [{"centre": [0.55, 0.45, 0.85], "size": [0.2, 0.15, 0.15]}]

        # removed: the form and the scene hold none
        page.click("[data-testid='obstacle-0-remove']")
        assert wait_for(lambda: not _boxes(studio_server), 60)
        page.wait_for_selector(row, state="detached", timeout=T)
    finally:
        studio_server.send("PUT", "/api/scene/obstacles", {"obstacles": []})
        page.click("[data-testid='train-defaults']")
