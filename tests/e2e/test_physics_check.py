"""In a real browser: before exporting a demonstration, the user checks it in physics and reads
the report the file will state (the motion replayed in MuJoCo on the robot chosen), then plays
the motion the robot made in physics on the robot in the scene."""

from __future__ import annotations

from typing import Any

import pytest

from tests.e2e.conftest import Studio
from tests.web.conftest import wait_for

pytestmark = pytest.mark.e2e

REPORT_TIMEOUT_S = 180.0
"""Retargeting, timing and the robot's first MuJoCo model take a minute on a shared machine."""


def test_a_demonstration_is_checked_in_physics_before_export(
    page: Any, studio_server: Studio
) -> None:
    robot = studio_server.get("/api/robots")["robot"]
    page.get_by_role("combobox", name="Demonstration to export").select_option("sample-reach-2")
    page.get_by_test_id("demonstration-physics-go").click()
    report = page.get_by_test_id("demonstration-physics")
    report.wait_for(state="visible", timeout=REPORT_TIMEOUT_S * 1000)
    text = report.inner_text()
    assert text.startswith(f"physics (MuJoCo, {robot}"), text
    assert "completed" in text and "saturation: none" in text
    assert "contacts: none (self or table)" in text
    assert not page.get_by_test_id("demonstration-export-error").is_visible()
    # and plays, on the robot in the scene, the motion the robot made in physics
    simulated = studio_server.get("/api/robot/simulate/demonstration/sample-reach-2?fit=true")[
        "q_simulated"
    ]
    page.get_by_test_id("demonstration-physics-play").click()

    def plays_simulated() -> bool:
        p = studio_server.get("/api/scene/playback")
        return bool(p["active"] and p["robot"] == robot and p["samples"] == len(simulated))

    assert wait_for(plays_simulated, timeout=REPORT_TIMEOUT_S), studio_server.get("/api/source")[
        "robot_notes"
    ]
    assert "plays the motion it makes in physics" in report.inner_text()
    assert not page.get_by_test_id("demonstration-export-error").is_visible()
    assert page.errors == []  # type: ignore[attr-defined]
