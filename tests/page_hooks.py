"""The browser tests' hook into the page: its own modules, imported as the page runs them.

The page puts nothing on ``window``. An ES module is one instance per URL in a page, so
``import("/static/state.js")`` from a test's script returns the very ``S`` the page's modules
share, and ``import("/static/chart.js")`` the chart the page draws. :func:`hook` gathers the
modules the tests read into one handle, passed to ``page.evaluate`` or ``page.wait_for_function``
as the argument of a function (``p => p.S.source.kind``), with the test's own argument beside it
when it has one (``([p, id]) => p.chart.drawnPoints(id)``).
"""

from __future__ import annotations

from typing import Any

HOOK_JS = """async () => ({
    S: (await import("/static/state.js")).S,
    listen: (await import("/static/state.js")).listen,
    chart: await import("/static/chart.js"),
    runs: await import("/static/runs.js"),
    scene: await import("/static/scene.js"),
})"""
"""The page's state and the modules the tests call (the chart's drawn runs, loading the runs)."""


def hook(page: Any) -> Any:
    """A handle on the page's state and modules, for a function's argument ``p``.

    Taken again after a reload: a handle belongs to the document it was made in.
    """
    return page.evaluate_handle(HOOK_JS)
