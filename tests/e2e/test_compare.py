"""Compare runs as a researcher does in TensorBoard or Weights & Biases: the run table with the
settings that differ highlighted, tags and notes that land in ``<run>/notes.json``, a filter by
name, tag and task, smoothing, other x axes, a legend that names every run, and one CSV.

Controls are found by role and accessible name, as a screen reader finds them.
"""

from __future__ import annotations

import csv
import io
import json
import os
import re
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from studio.learning import curve_statistics, curves_csv
from tests.e2e.conftest import ARTIFACTS, Studio, own_page
from tests.page_hooks import hook
from tests.web.conftest import wait_for

pytestmark = pytest.mark.e2e

T = 20.0  # s: the longest one step of the page may take (the machine may be busy)
SHOTS = Path(os.environ.get("COMPARE_SHOTS", str(ARTIFACTS)))


def ema(values: list[float], weight: float) -> list[float]:
    """TensorBoard's debiased exponential moving average, written independently of the page."""
    out, last = [], 0.0
    for n, v in enumerate(values, start=1):
        last = last * weight + (1 - weight) * v
        out.append(last / (1 - weight**n))
    return out


@pytest.fixture(scope="module")
def two_runs(studio_server: Studio) -> list[dict]:
    """Two finished grid runs that differ in their planner only."""
    runs = []
    for name, planning in (("cmp-zero", "zero"), ("cmp-full", "full")):
        run = studio_server.send(
            "POST",
            "/api/runs",
            {"name": name, "planning": planning, "episodes": 6, "experiments": 2, "seed": 3},
        )
        runs.append(run)
    for run in runs:
        assert wait_for(
            lambda r=run: studio_server.get(f"/api/runs/{r['id']}")["status"] == "done", 180
        )
    return [studio_server.get(f"/api/runs/{r['id']}") for r in runs]


@pytest.fixture
def small_page(browser: Any, studio_server: Studio, two_runs: list[dict]) -> Iterator[Any]:
    """The page at 1280 x 720 with only the two runs plotted."""
    with own_page(browser, studio_server, 1280, 720, accept_downloads=True) as page:
        ids = [r["id"] for r in two_runs]
        for row in page.locator("[data-testid='run-row']").all():
            box = row.get_by_test_id("run-show")
            if box.count() and box.is_checked() != (row.get_attribute("data-id") in ids):
                box.click()
        page.wait_for_function(
            "([p, ids]) => JSON.stringify([...p.chart.drawnRuns()].sort()) === JSON.stringify(ids)",
            arg=[hook(page), sorted(ids)],
            timeout=T * 1000,
        )
        yield page
        assert not page.errors, page.errors


def shoot(page: Any, name: str) -> None:
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / f"{name}.png"))


def test_the_run_table_highlights_differences_and_saves_tags_and_notes_beside_the_run(
    small_page: Any, studio_server: Studio, two_runs: list[dict]
) -> None:
    page = small_page
    zero, full = two_runs
    page.get_by_role("button", name="Compare runs").click()
    table = page.get_by_role("dialog", name="Compare runs")
    assert table.is_visible()
    rows = table.get_by_test_id("compare-row")
    assert wait_for(lambda: rows.count() >= 2, T)
    row_zero = table.locator(f"[data-testid='compare-row'][data-id='{zero['id']}']")
    # the planner differs between the plotted runs, the seed does not
    assert "differs" in row_zero.locator("td[data-key='planning']").get_attribute("class")
    assert "differs" not in (row_zero.locator("td[data-key='seed']").get_attribute("class") or "")
    page.get_by_role("checkbox", name="only settings that differ").check()
    assert wait_for(lambda: row_zero.locator("td[data-key='seed']").count() == 0, T)
    assert row_zero.locator("td[data-key='planning']").inner_text() == "zero"
    shoot(page, "compare-table-1280x720")

    tags = page.get_by_role("textbox", name=re.compile(r"^Tags of cmp-zero"))
    tags.fill("baseline, no planning")
    page.get_by_role("textbox", name=re.compile(r"^Notes of cmp-zero")).click()  # leave the field
    notes_file = studio_server.data_dir / "runs" / zero["id"] / "notes.json"
    assert wait_for(notes_file.exists, T)
    # the save redraws nothing under the cursor: the person types on in the notes field
    run_row = page.locator(f"[data-testid='run-row'][data-id='{zero['id']}']")
    assert wait_for(lambda: "baseline" in run_row.get_by_test_id("run-tags").inner_text(), T)
    notes_field = page.get_by_role("textbox", name=re.compile(r"^Notes of cmp-zero"))
    assert notes_field.evaluate("e => e === document.activeElement")
    page.keyboard.type("the paper's Dyna-Q(0)")
    page.get_by_role("textbox", name=re.compile(r"^Tags of cmp-full")).click()
    assert wait_for(lambda: "Dyna-Q(0)" in notes_file.read_text(), T)
    stored = json.loads(notes_file.read_text())
    assert (
        stored["tags"] == ["baseline", "no planning"] and stored["notes"] == "the paper's Dyna-Q(0)"
    )
    # the learner's own files are untouched, and the run list shows the tags
    assert json.loads((notes_file.parent / "config.json").read_text())["name"] == "cmp-zero"
    assert "baseline" in run_row.get_by_test_id("run-tags").inner_text()

    # filter by tag, by task and by name: the table and the run list follow
    search = page.get_by_role("searchbox", name="Filter runs")
    search.fill("tag:baseline")
    assert wait_for(lambda: rows.count() == 1, T)
    assert page.locator(f"[data-testid='run-row'][data-id='{full['id']}']").count() == 0
    assert page.get_by_test_id("runs-filtered").is_visible()
    search.fill("task:continuous")
    assert wait_for(lambda: rows.count() == 0, T)
    search.fill("cmp-full")
    assert wait_for(lambda: rows.count() == 1, T)
    assert rows.first.get_attribute("data-id") == full["id"]
    search.fill("")
    assert wait_for(lambda: rows.count() >= 2, T)

    # a tag too long: one sentence, and nothing changes on disk
    before = notes_file.read_text()
    tags.fill("x" * 40)
    page.get_by_role("textbox", name=re.compile(r"^Notes of cmp-zero")).click()
    alert = table.get_by_role("alert")
    assert wait_for(lambda: alert.is_visible() and "shorten it" in alert.inner_text(), T)
    assert notes_file.read_text() == before
    shoot(page, "compare-error-1280x720")
    page.set_viewport_size({"width": 1920, "height": 1080})
    shoot(page, "compare-error-1920x1080")
    page.set_viewport_size({"width": 1280, "height": 720})
    page.get_by_role("button", name="Close the run table").click()
    assert not table.is_visible()
    page.get_by_role("button", name="Compare runs").click()
    assert wait_for(table.is_visible, T)
    page.keyboard.press("Escape")
    assert wait_for(lambda: not table.is_visible(), T)


def test_smoothing_other_x_axes_the_legend_and_one_csv_of_the_plotted_runs(
    small_page: Any, studio_server: Studio, two_runs: list[dict], tmp_path: Path
) -> None:
    page = small_page
    zero, full = two_runs
    curve = studio_server.get(f"/api/runs/{zero['id']}/curve")
    # the legend names every run before the cursor comes near the chart, with its last value
    legend = page.locator("#curve-plot .u-legend")
    assert wait_for(
        lambda: "cmp-zero" in legend.inner_text() and "cmp-full" in legend.inner_text(), T
    )
    assert "last" in legend.inner_text()
    assert "–" not in legend.locator(".u-series:not(.band-edge) .u-value").all_inner_texts()[1]

    slider = page.get_by_role("slider", name="Smoothing")
    slider.focus()
    for _ in range(60):  # 0.60, TensorBoard's usual setting, as a keyboard user reaches it
        page.keyboard.press("ArrowRight")
    assert slider.input_value() == "0.6"
    line = "async (id) => (await import('/static/chart.js')).drawnLine(id)"
    want = pytest.approx(ema(curve["mean"], 0.6))
    # the chart redraws at its frame rate: wait for the frame after the last key press
    assert wait_for(lambda: page.evaluate(line, zero["id"])["smooth"] == want, T)
    drawn = page.evaluate(line, zero["id"])
    assert drawn["mean"] == pytest.approx(curve["mean"])  # the raw line stays, behind
    assert "smoothed" in legend.inner_text()
    shoot(page, "compare-smoothing-1280x720")

    page.get_by_test_id("curve-x").select_option("steps")
    steps = [sum(curve["mean"][: k + 1]) for k in range(len(curve["mean"]))]
    assert wait_for(lambda: page.evaluate(line, zero["id"])["x"][-1] != 6, T)
    xs = page.evaluate(line, zero["id"])
    mine = [x for x, m in zip(xs["x"], xs["mean"], strict=True) if m is not None]
    assert mine == pytest.approx(steps)
    # the CPU axis: each episode at the CPU time its experiments had spent by its end, as
    # measured while the run trained (curves.csv's cpu_seconds), and no "≈" on the axis
    assert all(v is not None for v in curve["cpu_seconds"])
    assert curve["cpu_seconds"][-1] * zero["config"]["experiments"] == pytest.approx(
        zero["cpu_seconds"], rel=0.05, abs=0.01
    )
    page.get_by_test_id("curve-x").select_option("cpu")

    def cpu_xs() -> list[float]:
        d = page.evaluate(line, zero["id"])
        return [x for x, m in zip(d["x"], d["mean"], strict=True) if m is not None]

    assert wait_for(lambda: cpu_xs() == pytest.approx(curve["cpu_seconds"]), T)
    assert "CPU time per experiment" in page.locator("#curve-plot").inner_text()
    assert "≈" not in page.locator("#curve-plot").inner_text()
    shoot(page, "compare-cpu-axis-1280x720")
    page.get_by_test_id("curve-x").select_option("episode")

    with page.expect_download() as got:
        page.get_by_role("button", name="Export CSV").click()
    path = tmp_path / "curves.csv"
    got.value.save_as(path)
    rows = list(csv.reader(io.StringIO(path.read_text())))
    assert rows[0][0] == "configuration" and rows[0][1] == "episode"
    assert {r[0] for r in rows[1:]} == {"cmp-zero", "cmp-full"}
    own = studio_server.get(f"/api/runs/{full['id']}/curve")
    assert [float(r[2]) for r in rows[1:] if r[0] == "cmp-full"] == pytest.approx(
        own["mean"], rel=1e-5
    )


def test_a_run_saved_without_times_per_episode_keeps_the_estimated_time_axes(
    small_page: Any, studio_server: Studio, two_runs: list[dict]
) -> None:
    """A run folder from before the times were recorded: its curves.csv in the old layout. Its
    curve loads, and the time axes share its total out by steps, saying so with "≈"."""
    page = small_page
    zero = two_runs[0]
    runs = studio_server.data_dir / "runs"
    old = runs / "cmp-older"
    if not old.exists():
        shutil.copytree(runs / zero["id"], old)
        config = json.loads((old / "config.json").read_text())
        config["name"] = "cmp-older"
        (old / "config.json").write_text(json.dumps(config))
        steps = np.loadtxt(old / "steps.csv", delimiter=",", dtype=np.int64, ndmin=2)
        (old / "curves.csv").write_text(curves_csv(curve_statistics(steps)))
    listed = {r["id"]: r for r in studio_server.get("/api/runs")}  # the studio finds it
    assert "wall_seconds" not in studio_server.get("/api/runs/cmp-older/curve")
    row = page.locator("[data-testid='run-row'][data-id='cmp-older']")
    assert wait_for(lambda: row.count() == 1, T)
    row.get_by_test_id("run-show").check()
    page.wait_for_function(
        "p => p.chart.drawnRuns().includes('cmp-older')", arg=hook(page), timeout=T * 1000
    )
    page.get_by_test_id("curve-x").select_option("cpu")
    plot = page.locator("#curve-plot")
    assert wait_for(lambda: "CPU time ≈ per experiment" in plot.inner_text(), T)
    line = "async (id) => (await import('/static/chart.js')).drawnLine(id)"
    drawn = page.evaluate(line, "cmp-older")
    xs = [x for x, m in zip(drawn["x"], drawn["mean"], strict=True) if m is not None]
    # the estimate ends at the run's CPU time over its experiments
    per_experiment = listed["cmp-older"]["cpu_seconds"] / zero["config"]["experiments"]
    assert xs[-1] == pytest.approx(per_experiment, rel=1e-3, abs=1e-3)
    shoot(page, "compare-estimated-cpu-axis-1280x720")
    row.get_by_test_id("run-show").uncheck()
    assert wait_for(lambda: "≈" not in plot.inner_text(), T)
    page.get_by_test_id("curve-x").select_option("episode")
