"""In a real browser: the user picks the UR5, the train form says the run trains it, and a run
started from the form trains the UR5 with its own default tiles; the Puma560 comes back."""

from __future__ import annotations

from typing import Any

import pytest

from studio.kinematics import robot_spec
from tests.e2e.conftest import Studio
from tests.web.conftest import wait_for

pytestmark = pytest.mark.e2e

RUN_NAME = "ur5 from the form"


def test_a_run_from_the_form_trains_the_robot_chosen(page: Any, studio_server: Studio) -> None:
    trains = page.locator("[data-testid='train-robot']")
    assert trains.inner_text() == robot_spec("puma560").title
    page.get_by_role("combobox", name="Robot").select_option("ur5")
    assert wait_for(lambda: trains.inner_text() == robot_spec("ur5").title)
    try:
        page.click("[data-testid='train-defaults']")
        page.select_option("[data-testid='train-task']", "arm-reach")
        assert page.input_value("[data-testid='train-tiles']") == ""  # the robot's default
        page.fill("[data-testid='train-name']", RUN_NAME)
        page.fill("[data-testid='train-joints']", "3")
        page.fill("[data-testid='train-goal-1']", "-90")
        page.fill("[data-testid='train-goal-2']", "90")
        page.select_option("[data-testid='train-planning']", "zero")
        page.fill("[data-testid='train-episodes']", "3")
        page.fill("[data-testid='train-experiments']", "1")
        page.click("[data-testid='train-start']")

        def finished() -> dict | None:
            if page.is_visible("[data-testid='train-error']"):
                raise AssertionError(page.inner_text("[data-testid='train-error']"))
            runs = [r for r in studio_server.get("/api/runs") if r["name"] == RUN_NAME]
            return runs[0] if runs and runs[0]["status"] in ("done", "failed") else None

        assert wait_for(finished, timeout=120.0)
        run = finished()
        assert run is not None and run["status"] == "done", run
        assert run["config"]["robot"] == "ur5"
        assert run["config"]["tiles"] == 72  # joints 1-3 turn +-360 degrees: 10 per tile
    finally:
        page.click("[data-testid='train-defaults']")  # the form as the other stories expect it
        page.get_by_role("combobox", name="Robot").select_option("puma560")
        assert wait_for(lambda: trains.inner_text() == robot_spec("puma560").title)
        assert wait_for(lambda: studio_server.get("/api/robots")["robot"] == "puma560")
    assert page.errors == []  # type: ignore[attr-defined]
