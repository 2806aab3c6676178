"""One rule for a long learning curve: the page's chart averages it as the server's figure does.

The server's rule is :func:`studio.learning.downsample_curve` (the PNG/SVG figures); the page's
chart runs its own copy in the browser (``static/curves.js``, so live curves need no round trip).
Here the browser's copy and the server's run on the same curve, and must give the same points.
"""

from __future__ import annotations

import mimetypes
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

from studio.learning import FIGURE_POINTS, curve_statistics, downsample_curve
from studio.web._app import STATIC_DIR

pytestmark = pytest.mark.e2e

ORIGIN = "http://page.test"

BROWSER_RULE = """async ([curve, points]) => {
    const { curveAxis, bucketCurve } = await import("/static/curves.js");
    const line = { curve, length: curve.episodes.length };
    const { x, bucketOf } = curveAxis([line], "episode", points ?? undefined);
    const s = bucketCurve(line, x.length, bucketOf);
    return { episodes: x, mean: s.mean, std: s.std, min: s.min, max: s.max, count: s.count };
}"""
"""The chart's episode axis on one run, as ``chartData`` computes it, before it draws (points
null: the chart's own number of points)."""


@pytest.fixture
def rule_page(browser: Any) -> Iterator[Any]:
    """A blank page that can import the studio's static modules (served from the package)."""

    def serve(route: Any) -> None:
        path = route.request.url.removeprefix(ORIGIN)
        if path.startswith("/static/"):
            file = STATIC_DIR / path.removeprefix("/static/")
            kind = mimetypes.guess_type(file.name)[0] or "application/octet-stream"
            route.fulfill(status=200, body=file.read_bytes(), content_type=kind)
        else:
            route.fulfill(
                status=200, body="<!doctype html><title>rule</title>", content_type="text/html"
            )

    context = browser.new_context()
    page = context.new_page()
    page.route(ORIGIN + "/**", serve)
    page.goto(ORIGIN + "/")
    try:
        yield page
    finally:
        context.close()


def stopped_run(experiments: int, episodes: int, seed: int) -> dict[str, list]:
    """A run's curve whose experiments stopped at different episodes (so counts fall at the end)."""
    rng = np.random.default_rng(seed)
    steps = rng.integers(5, 400, size=(experiments, episodes))
    ends = rng.integers(episodes // 2, episodes + 1, size=experiments)
    ends[0] = episodes  # one experiment runs to the end, so the run keeps its length
    for row, end in zip(steps, ends, strict=True):
        row[end:] = -1
    return curve_statistics(steps)


@pytest.mark.parametrize(
    ("episodes", "points"),
    [(2500, 600), (1234, 100), (50, 600), (601, 600), (FIGURE_POINTS * 3 + 1, None)],
    ids=["5-episode buckets", "a partial last bucket", "short: as is", "just over", "defaults"],
)
def test_the_chart_averages_a_long_curve_by_the_servers_rule(
    rule_page: Any, episodes: int, points: int | None
) -> None:
    curve = stopped_run(4, episodes, seed=episodes)
    server = downsample_curve(curve) if points is None else downsample_curve(curve, points)
    page = rule_page.evaluate(BROWSER_RULE, [curve, points])
    assert len(page["episodes"]) == len(server["episodes"]) <= (points or FIGURE_POINTS)
    np.testing.assert_allclose(page["episodes"], server["episodes"], rtol=0, atol=1e-9)
    for key in ("mean", "std"):  # the server rounds these to 3 decimals
        np.testing.assert_allclose(page[key], server[key], rtol=0, atol=6e-4, err_msg=key)
    for key in ("min", "max", "count"):
        assert page[key] == pytest.approx(server[key]), key
