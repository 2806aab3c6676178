"""In a real browser: the user picks the Panda, the scene draws it from its own meshes, the
simulated operator drives it, and the Puma560 comes back."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from studio.kinematics import load_robot, robot_names
from tests.e2e.conftest import Studio, shot
from tests.web.conftest import wait_for

pytestmark = pytest.mark.e2e

DRAW_TIMEOUT_S = 120.0
"""Reading a robot's meshes takes seconds alone, far longer on a machine shared by many."""


def _robot_select(page: Any) -> Any:
    return page.get_by_role("combobox", name="Robot")


def _q_robot(studio_server: Studio) -> np.ndarray:
    return np.array(studio_server.get("/api/source")["q_robot"])


def test_the_user_switches_to_the_panda_sees_it_drawn_and_driven_then_back(
    page: Any, studio_server: Studio
) -> None:
    select = _robot_select(page)
    offered = select.locator("option").evaluate_all("els => els.map(e => e.value)")
    assert offered == list(robot_names())
    assert select.input_value() == "puma560"
    studio_server.send("PUT", "/api/source", {"kind": "simulator"})
    assert wait_for(lambda: studio_server.get("/api/source")["running"])

    select.select_option("panda")
    panda = load_robot("panda")
    drawn = len(panda.visual_model.geometryObjects)
    assert wait_for(
        lambda: (
            studio_server.get("/api/robots")["drawn"] == "panda"
            and studio_server.get("/api/robots")["drawn_meshes"] == drawn
        )
    ), (page.inner_text("#source-error"), studio_server.log_tail())
    assert studio_server.get("/api/robots")["robot"] == "panda"
    # the live chain drives its seven joints, within its limits
    assert wait_for(lambda: _q_robot(studio_server).shape == (7,))
    first = _q_robot(studio_server)
    assert wait_for(lambda: not np.allclose(_q_robot(studio_server), first, atol=1e-3))
    q = _q_robot(studio_server)
    assert np.all(q >= panda.lower - 1e-9) and np.all(q <= panda.upper + 1e-9)
    # the page shows seven angles, and joint mode (the Puma560's) cannot be chosen
    assert wait_for(lambda: len(page.inner_text("#src-q").split()) == 8)  # 7 angles and "°"
    assert page.locator("#retarget-mode option[value='joint']").is_disabled()
    assert page.input_value("#retarget-mode") == "cartesian"
    shot(page, "robot-panda", "sec-source")

    select.select_option("puma560")
    assert wait_for(
        lambda: (
            studio_server.get("/api/robots")["drawn"] == "puma560"
            and studio_server.get("/api/robots")["drawn_meshes"] == 7
        )
    )
    assert wait_for(lambda: _q_robot(studio_server).shape == (6,))
    assert wait_for(lambda: page.input_value("#retarget-mode") == "joint")
    assert not page.locator("#retarget-mode option[value='joint']").is_disabled()

    # the recording chosen in the source form downloads as the robot's trajectory
    page.select_option(
        "[data-testid='source-kind']", "recording"
    )  # shows the list, applies nothing
    page.select_option("#source-recording", "sample-reach-1")
    page.get_by_role("combobox", name="Export format").select_option("csv")
    page.check("#robot-export-unchecked")  # the capture-rate recording fails the checks
    with page.expect_download(timeout=120_000) as download:
        page.click("#robot-export")
    assert download.value.suggested_filename == "sample-reach-1.puma560.csv"
    text = open(download.value.path()).read()  # noqa: PTH123, SIM115
    assert "time," + ",".join(load_robot("puma560").joint_names) in text
    page.select_option("[data-testid='source-kind']", "simulator")  # as the source still is
    assert page.errors == []  # type: ignore[attr-defined]
