"""The source's readouts while a slow camera sends landmarks: the pose model without a GPU
estimates 1-3 frames a second, and the top bar and panel read "rate 0 Hz" and "fit residual
0.0 mm" between its frames, as if nothing arrived and the fit were exact."""

from __future__ import annotations

from typing import Any

import pytest

from tests.e2e.conftest import Studio, own_page
from tests.page_hooks import hook

pytestmark = pytest.mark.e2e

FRAMES = 8
INTERVAL_MS = 800
"""A slow camera's pace: 1.25 frames a second, as the full model runs on a busy machine."""
STEADY_FROM = 4
"""Frames sent before the rate is read: three make a pace."""

SEND_JS = f"""p => {{
    window.__sent = 0;
    window.__seen = [];
    p.listen("source", (s) => window.__seen.push([window.__sent, s.rate_hz,
        document.getElementById("top-rate").textContent,
        document.getElementById("src-residual").textContent]));
    // No person in view: frames arrive, and there is nothing to fit.
    const send = () => fetch("/api/source/landmarks", {{
        method: "POST",
        headers: {{ "Content-Type": "application/json" }},
        body: JSON.stringify({{ t: performance.now() / 1000, world: null, image: null,
                                width: 640, height: 480, fps: 1.25, model: "full" }}),
    }}).then((r) => {{ if (r.ok) window.__sent += 1; }});
    const timer = setInterval(() => {{
        if (window.__sent >= {FRAMES}) clearInterval(timer); else send();
    }}, {INTERVAL_MS});
}}"""
"""Send landmark frames at a slow camera's pace from the page, and keep every status drawn."""


def test_a_slow_camera_reads_its_rate_and_no_residual(browser: Any, studio_server: Studio) -> None:
    studio_server.send("PUT", "/api/source", {"kind": "camera", "side": "right"})
    try:
        with own_page(browser, studio_server) as page:
            page.wait_for_function(
                "p => p.S.source && p.S.source.kind === 'camera'", arg=hook(page)
            )
            page.evaluate(SEND_JS, hook(page))
            page.wait_for_function(f"() => window.__sent >= {FRAMES}", timeout=60_000)
            seen = page.evaluate("() => window.__seen")
            steady = [s for s in seen if STEADY_FROM <= s[0] < FRAMES]
            assert len(steady) >= 2, seen
            for sent, rate, top, residual in steady:
                assert rate > 0 and top != "0", (sent, rate, top)
                assert residual == "–", (sent, residual)
            assert not page.errors
    finally:
        studio_server.send("PUT", "/api/source", {"kind": "simulator"})
