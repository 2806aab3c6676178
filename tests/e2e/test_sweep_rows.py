"""A sweep in the page's run list, in Chromium, on a studio app served in this process."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.conftest import free_port
from tests.e2e.conftest import serve_app
from tests.page_hooks import hook
from tests.web.conftest import make_settings
from tests.web.test_sweeps import make_sweep

pytestmark = pytest.mark.e2e


def test_the_page_groups_a_sweep_and_ticking_it_plots_every_trial(
    tmp_path: Path, blank_page: Any
) -> None:
    """In Chromium: one group row; ticking it plots all its runs; unfolding shows the table,
    the figure, the downloads and the trials' own rows."""
    from studio.web import create_app

    keys = make_sweep(tmp_path)
    port = free_port()
    app = create_app(make_settings(tmp_path, port=port, allowed_hosts=()))
    with serve_app(app, port) as base:
        page = blank_page
        page.goto(base + "/")
        row = page.locator('[data-testid="sweep-row"]')
        row.wait_for()
        assert row.count() == 1 and row.get_attribute("data-id") == "tiny"
        assert page.locator('[data-testid="run-row"]').count() == 0  # folded
        run_ids = {f"tiny~tiny-{key}" for key in keys}
        row.locator('[data-testid="sweep-show"]').uncheck()  # the newest runs are shown
        p = hook(page)
        page.wait_for_function("p => p.chart.drawnRuns().length === 0", arg=p)
        page.evaluate("p => p.S.curves.clear()", p)
        row.locator('[data-testid="sweep-show"]').check()
        page.wait_for_function(  # the chart overlays exactly the sweep's runs
            "([p, ids]) => JSON.stringify([...p.chart.drawnRuns()].sort()) === JSON.stringify(ids)",
            arg=[p, sorted(run_ids)],
        )
        row.locator('[data-testid="sweep-open"]').click()
        table = page.locator('[data-testid="sweep-table"] tbody tr')
        table.first.wait_for()
        assert table.count() == len(keys)
        assert page.locator('[data-testid="run-row"]').count() == len(keys)
        figure = page.locator('[data-testid="sweep-figure"]')
        page.wait_for_function(
            "img => img.complete && img.naturalWidth > 0", arg=figure.element_handle()
        )
        with page.expect_download() as download:
            page.locator('[data-testid="sweep-csv"]').click()
        saved = tmp_path / "downloaded.csv"
        download.value.save_as(saved)
        assert saved.read_text() == (tmp_path / "sweeps" / "tiny" / "sweep.csv").read_text()
