"""Browser: train a continuous-joint (tile-coded) run from the page, watch it, download its policy."""

from __future__ import annotations

import io
import time
import urllib.request
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.e2e.conftest import Studio, shot, watch_policy, watched

pytestmark = pytest.mark.e2e

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


def _small_run(page: Any, name: str, episodes: int) -> None:
    """Fill the train form for a small continuous run: 3 joints, no planning, one experiment."""
    page.fill("[data-testid='train-name']", name)
    page.fill("[data-testid='train-joints']", "3")
    page.select_option("[data-testid='train-planning']", "zero")
    page.fill("[data-testid='train-episodes']", str(episodes))
    page.fill("[data-testid='train-experiments']", "1")


@pytest.fixture(scope="module")
def continuous_run(page: Any, studio_server: Studio) -> dict:
    """A tiny continuous-joint run trained from the page's form; the form is left as the stories
    expect it (the paper's grid, its defaults, no demonstration ticked)."""
    defaults = studio_server.get("/api/config")["training"]
    page.click("[data-testid='train-defaults']")
    assert not page.is_visible("[data-testid='train-joints']")  # the paper's grid by default
    page.select_option("[data-testid='train-task']", "arm-reach")
    assert page.is_visible("[data-testid='train-joints']")
    assert not page.is_visible("[data-testid='train-bins']")
    for key, field in (("joints", "joints"), ("step_deg", "step")):
        assert float(page.input_value(f"[data-testid='train-{field}']")) == defaults[key]
    assert defaults["tiles"] is None  # the robot's own default
    assert page.input_value("[data-testid='train-tiles']") == ""
    _small_run(page, RUN_NAME, episodes=40)
    page.select_option("[data-testid='train-actions']", "follow")  # the form starts with "single"
    demos = page.locator("[data-testid='train-demo']")
    if demos.count():
        demos.first.check()
    try:
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
    finally:  # leave the form as the stories expect it, whatever happened
        page.select_option("[data-testid='train-task']", "arm-grid")
        page.click("[data-testid='train-defaults']")
        if demos.count():
            demos.first.uncheck()
    assert not page.is_visible("[data-testid='train-joints']")
    return run


def test_a_continuous_run_trains_from_the_page_is_watched_and_downloaded(
    page: Any, studio_server: Studio, continuous_run: dict, tmp_path: Path
) -> None:
    from studio.learning import TilePolicyFile, load_any_policy

    run = continuous_run
    defaults = studio_server.get("/api/config")["training"]
    watch_policy(page, f"run:{run['id']}", 3, T)
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
    # the action set chosen: one joint per action (2J = 6) and one along the ticked demonstration
    assert policy.task.joints == 3 and policy.task.actions == "follow" and policy.task.paths
    assert policy.weights.shape[1] == policy.task.n_actions == 7
    assert not page.errors  # type: ignore[attr-defined]


def _download(page: Any, testid: str, folder: Path) -> Path:
    with page.expect_download(timeout=T) as download:
        page.click(f"[data-testid='{testid}']")
    target = folder / download.value.suggested_filename
    download.value.save_as(target)
    assert not page.is_visible("[data-testid='export-error']"), page.inner_text(
        "[data-testid='export-error']"
    )
    return target


def test_a_continuous_policy_is_listed_watched_uploaded_and_downloaded_in_the_policy_list(
    page: Any, studio_server: Studio, continuous_run: dict, tmp_path: Path
) -> None:
    from studio.learning import TilePolicyFile, load_any_policy

    run = continuous_run
    key = f"run:{run['id']}"
    row = page.locator(f"[data-testid='policy-row'][data-key='{key}']")
    row.wait_for(timeout=T)
    # listed with its task, under the name Watch shows, and no hidden error
    assert page.locator("[data-testid='policy-damaged']").count() == 0
    assert not page.is_visible("[data-testid='policies-error']")
    assert "continuous 3 joints" in row.locator("[data-testid='policy-task']").inner_text()
    option = page.locator(f"[data-testid='watch-policy'] option[value='{key}']").inner_text()
    label = row.locator("td.name").inner_text()
    assert RUN_NAME in label and option == f"run {label}"

    # Watch and the list's ▶ agree, with the rollout's own step count
    by_watch = watch_policy(page, key, 3, T)
    by_row = watched(page, lambda: row.locator("[data-testid='policy-watch']").click(), T)
    assert by_watch == by_row, (by_watch, by_row)
    api = studio_server.send("POST", "/api/watch", {"run": run["id"], "seed": 3})
    assert by_watch.startswith(f"{api['steps']} steps, ") and api["steps"] > 0
    assert ("does not reach" in by_watch) == (not api["reached_goal"])
    shot(page, "continuous-03-policy-list", "sec-watch")

    # its Policy .npz, uploaded back through the page: listed, watched, downloaded again
    npz = _download(page, "download-policy", tmp_path)
    page.set_input_files("[data-testid='policy-upload']", str(npz))
    uploaded = page.locator("[data-testid='policy-row'][data-key^='policy:']")
    uploaded.wait_for(timeout=T)
    assert not page.is_visible("[data-testid='policies-error']"), page.inner_text(
        "[data-testid='policies-error']"
    )
    assert page.locator("[data-testid='policy-damaged']").count() == 0
    assert "continuous 3 joints" in uploaded.locator("[data-testid='policy-task']").inner_text()
    upload_key = uploaded.get_attribute("data-key")
    assert page.input_value("[data-testid='watch-policy']") == upload_key  # selected on upload
    page.fill("[data-testid='watch-seed']", "4")
    of_upload = watched(page, lambda: page.click("[data-testid='watch-go']"), T)
    assert int(of_upload.split(" steps, ")[0]) > 0
    (tmp_path / "again").mkdir()
    again = load_any_policy(_download(page, "download-policy", tmp_path / "again"))
    assert isinstance(again, TilePolicyFile) and again.task is not None and again.task.joints == 3

    # Rollout CSV is the selected policy's (the run's, watched from start 3), not the last watched
    page.select_option("[data-testid='watch-policy']", key)
    csv = _download(page, "download-rollout", tmp_path)
    assert csv.name == f"{run['id']}.rollout.csv"
    rows = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert np.allclose(rows[:, 1:], np.asarray(api["q_robot"]), atol=1e-5)
    page.select_option("[data-testid='watch-policy']", upload_key)
    csv = _download(page, "download-rollout", tmp_path)
    assert csv.name == f"{upload_key.removeprefix('policy:')}.rollout.csv"
    shot(page, "continuous-04-uploaded", "sec-watch")

    # leave the lists as the stories expect them: no uploaded policy, nothing playing
    studio_server.send("POST", "/api/watch/stop")
    studio_server.send("DELETE", f"/api/policies/{upload_key.removeprefix('policy:')}")
    uploaded.wait_for(state="detached", timeout=T)
    page.fill("[data-testid='watch-seed']", "")
    assert not page.errors  # type: ignore[attr-defined]


def test_a_run_that_follows_its_demonstration_is_chosen_and_started_from_the_page(
    page: Any, studio_server: Studio
) -> None:
    """The form starts with one joint per action (its curve shows learning, issue 40); "one
    joint, or follow the demonstrations" is chosen, and with a demonstration ticked the run
    trains with the follow action and keeps the choice."""
    name = "e2e-follow"
    page.click("[data-testid='train-defaults']")
    page.select_option("[data-testid='train-task']", "arm-reach")
    actions = page.locator("[data-testid='train-actions']")
    assert actions.input_value() == "single"  # the form's default, through /api/config
    page.select_option("[data-testid='train-actions']", "follow")
    assert "follow the demonstrations" in actions.locator("option:checked").inner_text()
    _small_run(page, name, episodes=20)
    demo = page.locator("[data-testid='train-demo'][value='sample-reach-1']")
    try:
        demo.check()
        page.click("[data-testid='train-start']")

        def finished() -> dict | None:
            runs = [r for r in studio_server.get("/api/runs") if r["name"] == name]
            return runs[0] if runs and runs[0]["status"] in ("done", "failed", "stopped") else None

        run = _wait(finished, TRAIN_TIMEOUT_S)
        assert run and run["status"] == "done", run
        assert run["config"]["actions"] == "follow" and run["has_policy"]
    finally:  # leave the form as the stories expect it
        if demo.count():
            demo.uncheck()
        page.select_option("[data-testid='train-task']", "arm-grid")
        page.click("[data-testid='train-defaults']")
    assert not page.errors  # type: ignore[attr-defined]
