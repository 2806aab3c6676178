"""Browser: train a continuous-joint (tile-coded) run from the page, watch it, download its policy."""

from __future__ import annotations

import io
import time
import urllib.request
from pathlib import Path
from typing import Any

import numpy as np

from tests.e2e.conftest import Studio, shot

T = 20_000  # ms: the longest a single UI step may take
RUN_NAME = "e2e-continuous"
TRAIN_TIMEOUT_S = 180.0


def _wait(predicate: Any, timeout: float) -> Any:
    """Poll ``predicate`` until it returns something truthy (the event, not a fixed sleep)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = predicate()
        if value:
            return value
        time.sleep(0.2)
    return predicate()


def test_a_continuous_run_trains_from_the_page_is_watched_and_downloaded(
    page: Any, studio_server: Studio, tmp_path: Path
) -> None:
    from studio.learning import TilePolicyFile, load_any_policy

    defaults = studio_server.get("/api/config")["training"]
    page.click("[data-testid='train-defaults']")
    assert not page.is_visible("[data-testid='train-joints']")  # the paper's grid by default
    page.select_option("[data-testid='train-task']", "arm-reach")
    assert page.is_visible("[data-testid='train-joints']")
    assert not page.is_visible("[data-testid='train-bins']")
    for key, field in (("joints", "joints"), ("step_deg", "step"), ("tiles", "tiles")):
        assert float(page.input_value(f"[data-testid='train-{field}']")) == defaults[key]
    page.fill("[data-testid='train-name']", RUN_NAME)
    page.fill("[data-testid='train-joints']", "3")
    page.select_option("[data-testid='train-planning']", "zero")
    page.fill("[data-testid='train-episodes']", "40")
    page.fill("[data-testid='train-experiments']", "1")
    demos = page.locator("[data-testid='train-demo']")
    if demos.count():
        demos.first.check()
    page.click("[data-testid='train-start']")

    def finished() -> dict | None:
        if page.is_visible("[data-testid='train-error']"):
            raise AssertionError(page.inner_text("[data-testid='train-error']"))
        runs = [r for r in studio_server.get("/api/runs") if r["name"] == RUN_NAME]
        return runs[0] if runs and runs[0]["status"] in ("done", "failed", "stopped") else None

    run = _wait(finished, TRAIN_TIMEOUT_S)
    assert run and run["status"] == "done", run
    assert run["config"]["task"] == "arm-reach" and run["config"]["joints"] == 3
    assert run["has_policy"] and run["episodes_done"] == 40
    row = page.locator(f"[data-testid='run-row'][data-id='{run['id']}']")
    row.wait_for(timeout=T)
    shot(page, "continuous-01-trained", "sec-train")

    page.select_option("[data-testid='watch-policy']", f"run:{run['id']}")
    page.select_option("[data-testid='watch-start']", "random")
    page.fill("[data-testid='watch-seed']", "3")
    page.click("[data-testid='watch-go']")
    page.wait_for_selector("[data-testid='watch-result']:has-text(' s ')", timeout=T)
    assert not page.is_visible("[data-testid='watch-error']")
    shot(page, "continuous-02-watch", "sec-watch")
    with urllib.request.urlopen(studio_server.base + "/api/watch/trajectory.csv") as answer:
        rollout = np.loadtxt(io.StringIO(answer.read().decode()), delimiter=",", skiprows=1)
    assert rollout.shape[1] == 7 and len(rollout) > 2
    # smooth, step by step: no sample moves a joint by more than one 2-degree step, the wrist holds
    assert np.abs(np.diff(rollout[:, 1:], axis=0)).max() <= np.radians(defaults["step_deg"]) + 1e-6
    assert np.ptp(rollout[:, 4:], axis=0).max() == 0.0

    with page.expect_download(timeout=T) as download:
        page.click("[data-testid='download-policy']")
    target = tmp_path / download.value.suggested_filename
    download.value.save_as(target)
    assert not page.is_visible("[data-testid='export-error']")
    policy = load_any_policy(target)
    assert isinstance(policy, TilePolicyFile) and policy.task is not None
    assert policy.task.joints == 3 and policy.weights.shape[1] == 6

    # leave the form as the stories expect it
    page.select_option("[data-testid='train-task']", "arm-grid")
    page.click("[data-testid='train-defaults']")
    if demos.count():
        demos.first.uncheck()
    assert not page.is_visible("[data-testid='train-joints']")
    assert not page.errors  # type: ignore[attr-defined]
