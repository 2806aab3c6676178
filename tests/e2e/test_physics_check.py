"""In a real browser: before exporting a demonstration, the user checks it in physics and reads
the report the file will state (the motion replayed in MuJoCo on the robot chosen)."""

from __future__ import annotations

from typing import Any

import pytest

from tests.e2e.conftest import Studio

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
