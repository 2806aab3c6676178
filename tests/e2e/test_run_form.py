"""The run form and the run list in Chromium, on a studio app served in this process (so a test
can write run folders beside it, or hold the learner's preparation inside it)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.conftest import free_port, hold_preparation
from tests.e2e.conftest import serve_app
from tests.page_hooks import hook
from tests.web.conftest import TINY_RUN, make_settings, wait_for

pytestmark = pytest.mark.e2e


@pytest.fixture
def page_server(tmp_path: Path) -> Iterator[tuple[str, Any]]:
    """The studio app on a random loopback port in this process (no scene): its URL and the app."""
    from studio.web import create_app

    port = free_port()
    app = create_app(make_settings(tmp_path, port=port, viser_url="about:blank"))
    with serve_app(app, port) as base:
        yield base, app


def test_the_page_form_reports_every_bad_field_and_plots_short_beside_long_runs(
    page_server, blank_page
):
    base, app = page_server
    page = blank_page
    runs = app.state.studio.runs
    from fastapi.testclient import TestClient

    api = TestClient(app, base_url=base)
    short = api.post("/api/runs", json={**TINY_RUN, "episodes": 100}).json()
    long = api.post("/api/runs", json={**TINY_RUN, "experiments": 2, "episodes": 30_000}).json()
    page.goto(base + "/")
    page.wait_for_selector("body[data-ready='1']", timeout=60_000)

    # the form holds the learning package's defaults, served by /api/config
    training = api.get("/api/config").json()["training"]
    for key in ("alpha", "gamma", "epsilon", "planning_steps", "episodes", "experiments", "bins"):
        field = "n" if key == "planning_steps" else key
        assert float(page.input_value(f"[data-testid='train-{field}']")) == training[key], key
    assert page.input_value("[data-testid='train-planning']") == training["planning"]
    assert float(page.input_value("[data-testid='train-goal-1']")) == training["goal_deg"][1]

    # every bad field at once, each marked; Paper defaults clears them
    page.fill("[data-testid='train-alpha']", "5")
    page.fill("[data-testid='train-episodes']", "0")
    page.fill("[data-testid='train-goal-0']", "170")
    page.click("[data-testid='train-start']")
    page.wait_for_selector("[data-testid='train-problem']", timeout=60_000)
    problems = page.locator("[data-testid='train-problem']").all_inner_texts()
    assert len(problems) == 3, problems
    assert any("alpha" in p for p in problems) and any("episodes" in p for p in problems)
    assert any("goal_deg joint 1" in p for p in problems)
    bad = page.locator("#train-form .bad").evaluate_all("xs => xs.map(x => x.name)")
    assert set(bad) == {"alpha", "episodes", "goal0", "goal1", "goal2"}
    page.click("[data-testid='train-defaults']")
    assert page.locator("[data-testid='train-error']").is_hidden()
    assert page.locator("#train-form .bad").count() == 0
    assert float(page.input_value("[data-testid='train-alpha']")) == training["alpha"]

    # a 100-episode run beside a 30,000-episode one: a log or fraction axis keeps its shape
    assert runs.wait_idle(300)
    p = hook(page)
    page.evaluate("p => p.runs.loadRuns()", p)

    def points(run_id: str) -> int:
        return page.evaluate("([p, id]) => p.chart.drawnPoints(id)", [p, run_id])

    assert wait_for(lambda: points(long["id"]) > 0, 60)
    linear = points(short["id"])
    page.select_option("[data-testid='curve-x']", "log")
    assert wait_for(lambda: points(short["id"]) > 2 * linear, 60)
    page.select_option("[data-testid='curve-x']", "fraction")
    assert wait_for(lambda: points(short["id"]) == 100, 60)
    assert points(long["id"]) <= 600
    assert not page.errors


def test_the_page_marks_where_a_run_averages_fewer_experiments(page_server, blank_page, tmp_path):
    from studio.learning import ArmGrid, DynaQConfig, RunFolder, RunRecord

    base, _ = page_server
    page = blank_page
    # experiments of different lengths (a stopped run): 1000, 500 and 200 episodes finished
    record = RunRecord.for_arm_grid(ArmGrid(), DynaQConfig(), 3, 1000, origin="cli")
    folder = RunFolder.create(tmp_path / "runs", record, name="uneven")
    steps = np.random.default_rng(0).integers(1, 500, (3, 1000))
    steps[1, 500:] = -1
    steps[2, 200:] = -1
    folder.save_steps(steps)
    folder.status = "stopped"
    folder.save_status()
    page.goto(base + "/")
    page.wait_for_selector("body[data-ready='1']", timeout=60_000)
    p = hook(page)
    fewer = "([p, id]) => p.chart.drawnFewerFrom(id)"
    assert wait_for(lambda: page.evaluate(fewer, [p, "uneven"]) is not None, 60)
    assert 201 <= page.evaluate(fewer, [p, "uneven"]) <= 202  # the bucket holding episode 201
    assert not page.errors


def test_the_run_list_says_a_first_run_prepares_the_learner(page_server, blank_page, monkeypatch):
    from fastapi.testclient import TestClient

    compiling, compiled = hold_preparation(monkeypatch)
    base, app = page_server
    page = blank_page
    api = TestClient(app, base_url=base)
    page.goto(base + "/")
    page.wait_for_selector("body[data-ready='1']", timeout=60_000)
    try:
        run = api.post("/api/runs", json=TINY_RUN).json()
        assert compiling.wait(30)
        row = f"[data-testid='run-row'][data-id='{run['id']}']"
        page.wait_for_selector(f"{row} [data-testid='run-note']", timeout=30_000)
        assert page.inner_text(f"{row} [data-testid='run-status']") == "preparing"
        note = page.inner_text(f"{row} [data-testid='run-note']")
        assert note.startswith("preparing the learner (first run on this machine, about ")
    finally:
        compiled.set()
    assert app.state.studio.runs.wait_idle(120)
    page.wait_for_selector(
        f"{row}[data-status='done'] [data-testid='run-progress']", timeout=30_000
    )
    assert page.locator(f"{row} [data-testid='run-note']").count() == 0
    assert not page.errors
