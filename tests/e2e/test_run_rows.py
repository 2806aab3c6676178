"""The runs list shows what the data folder holds even when it is not a healthy run: a damaged
run folder as a "damaged" row that can be deleted, and a stale run that says "running" (from a
studio that crashed on another machine) with a way to mark it stopped.

Each story opens its own tab, so it sees the folders it wrote at load.
"""

from __future__ import annotations

import json
import shutil
import socket
from pathlib import Path
from typing import Any

import pytest

from studio.learning import ArmGrid, DynaQConfig, RunFolder, RunRecord
from tests.e2e.conftest import Studio, shot

pytestmark = pytest.mark.e2e


def _open(browser_page: Any, studio: Studio) -> Any:
    tab = browser_page.context.new_page()
    tab.goto(studio.base + "/")
    tab.wait_for_selector("body[data-ready='1']", timeout=30_000)
    return tab


def test_a_damaged_run_folder_shows_as_damaged_and_can_be_deleted(
    page: Any, studio_server: Studio
) -> None:
    broken = studio_server.data_dir / "runs" / "broken-run"
    broken.mkdir(parents=True)
    (broken / "config.json").write_text('{"format": "teach-studio-run", "version": 1')  # cut short
    tab = _open(page, studio_server)
    try:
        row = tab.locator("[data-testid='run-row'][data-id='broken-run']")
        row.wait_for(timeout=15_000)
        assert row.get_attribute("data-status") == "damaged"
        assert row.locator("[data-testid='run-status']").inner_text() == "damaged"
        assert "config.json" in row.locator("[data-testid='run-damage']").inner_text()
        shot(tab, "runs-damaged-row", "sec-train")
        row.locator("[data-testid='run-delete']").click()
        tab.click("[data-testid='confirm-ok']")
        row.wait_for(state="detached", timeout=15_000)
        assert not broken.exists()
    finally:
        shutil.rmtree(broken, ignore_errors=True)
        tab.close()


def test_a_stale_running_run_can_be_marked_stopped_from_the_page(
    page: Any, studio_server: Studio
) -> None:
    record = RunRecord.for_arm_grid(
        ArmGrid(joints=2, bins=5, goal=(2, 2)), DynaQConfig(planning="zero"), 1, 3, origin="cli"
    )
    run = RunFolder.create(
        studio_server.data_dir / "runs", record, name="stale-run", status="running"
    )
    run.disown()  # written before owner locks, by a studio on a machine that is gone
    (run.path / "owner.lock").unlink()
    status = json.loads((run.path / "status.json").read_text())
    status.update(pid=1, host={"hostname": f"not-{socket.gethostname()}", "node": None})
    (run.path / "status.json").write_text(json.dumps(status))
    tab = _open(page, studio_server)
    try:
        row = tab.locator("[data-testid='run-row'][data-id='stale-run']")
        row.wait_for(timeout=15_000)
        assert row.get_attribute("data-status") == "running"
        assert row.locator("[data-testid='run-stop']").count() == 0  # not this studio's to stop
        row.locator("[data-testid='run-mark-stopped']").click()
        tab.click("[data-testid='confirm-ok']")
        tab.locator("[data-testid='run-row'][data-id='stale-run'][data-status='stopped']").wait_for(
            timeout=15_000
        )
        assert json.loads((run.path / "status.json").read_text())["status"] == "stopped"
        shot(tab, "runs-marked-stopped", "sec-train")
    finally:
        shutil.rmtree(Path(run.path), ignore_errors=True)
        tab.close()
