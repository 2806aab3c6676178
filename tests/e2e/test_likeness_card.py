"""Browser: the likeness card beside Watch, and the training form checking a demonstration's goal
as it is filled in (before Start)."""

from __future__ import annotations

from typing import Any

import pytest

from tests.e2e.conftest import Studio, shot
from tests.e2e.test_continuous import _wait

pytestmark = pytest.mark.e2e

T = 20_000  # ms: the longest a single UI step may take
TRAIN_TIMEOUT_S = 180.0
DEMO = "sample-reach-1"


def test_watching_a_policy_shows_its_likeness_card_with_both_columns(
    page: Any, studio_server: Studio
) -> None:
    run = studio_server.send(
        "POST",
        "/api/runs",
        {"planning": "zero", "experiments": 1, "episodes": 5, "seed": 1, "demonstrations": [DEMO]},
    )

    def done() -> dict | None:
        now = studio_server.get(f"/api/runs/{run['id']}")
        return now if now["status"] in ("done", "failed", "stopped") else None

    assert _wait(done, TRAIN_TIMEOUT_S)["status"] == "done"
    option = f"[data-testid='watch-policy'] option[value='run:{run['id']}']"
    page.wait_for_selector(option, state="attached", timeout=T)
    page.select_option("[data-testid='watch-policy']", f"run:{run['id']}")
    page.click("[data-testid='watch-go']")
    card = page.locator("[data-testid='likeness-card']")
    card.locator("[data-testid='likeness-row']").first.wait_for(timeout=T)
    assert DEMO in card.inner_text()
    rows = card.locator("[data-testid='likeness-row']")
    assert rows.count() == 8
    for i in range(rows.count()):  # every figure has the policy's value and the demonstration's
        assert rows.nth(i).locator("[data-testid='likeness-policy']").inner_text().strip()
        assert rows.nth(i).locator("[data-testid='likeness-demo']").inner_text().strip()
    for measure in ("LDLJ", "SPARC"):
        smooth = rows.filter(has_text=measure)
        assert smooth.locator("[data-testid='likeness-demo']").inner_text() != "–"
    shot(page, "likeness-01-card", "sec-watch")
    assert not page.errors  # type: ignore[attr-defined]


def test_a_demonstration_for_another_goal_is_named_before_start(
    page: Any, studio_server: Studio
) -> None:
    runs_before = len(studio_server.get("/api/runs"))
    page.click("[data-testid='train-defaults']")
    demo = page.locator(f"[data-testid='train-demo'][value='{DEMO}']")
    try:
        page.fill("[data-testid='train-goal-0']", "-120")
        demo.check()  # the user picks a demonstration: the form checks it against the goal now
        problem = page.locator("[data-testid='train-problem']")
        problem.first.wait_for(timeout=T)
        assert DEMO in problem.first.inner_text() and "goal" in problem.first.inner_text()
        shot(page, "likeness-02-goal-check", "sec-train")
        # back to the demonstration's own goal: the sentence goes
        page.fill(
            "[data-testid='train-goal-0']",
            str(studio_server.get("/api/config")["training"]["goal_deg"][0]),
        )
        page.locator("[data-testid='train-goal-0']").dispatch_event("change")
        page.wait_for_selector("[data-testid='train-error']", state="hidden", timeout=T)
    finally:  # leave the form as the stories expect it
        demo.uncheck()
        page.click("[data-testid='train-defaults']")
    assert len(studio_server.get("/api/runs")) == runs_before  # nothing was started
    assert not page.errors  # type: ignore[attr-defined]
