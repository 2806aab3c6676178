"""In a browser without a GPU, the page draws the 3D scene at a lower resolution and says so.

Chromium here draws WebGL with SwiftShader, on the CPU that also trains; at half the device-pixel
ratio a frame costs a quarter of the pixels. A browser with a GPU keeps its own ratio.
"""

from __future__ import annotations

from typing import Any
from urllib.parse import parse_qs, urlsplit

import pytest

from tests.e2e.conftest import Studio, live_scene

pytestmark = pytest.mark.e2e

SCENE = "(await import('/static/scene.js'))"
"""The page's scene module (scene.js), as the page runs it."""
GPU_RENDERERS = (
    "ANGLE (NVIDIA, NVIDIA GeForce RTX 3080 (0x00002206) Direct3D11 vs_5_0 ps_5_0, D3D11)",
    "ANGLE (Intel, Mesa Intel(R) UHD Graphics 620 (KBL GT2), OpenGL 4.6)",
    "Apple M2",
)
SOFTWARE_RENDERERS = (
    "ANGLE (Google, Vulkan 1.3.0 (SwiftShader Device (Subzero) (0x0000C0DE)), SwiftShader driver)",
    "llvmpipe (LLVM 15.0.6, 256 bits)",
)


def test_the_scene_is_drawn_at_half_resolution_without_a_gpu(
    page: Any, studio_server: Studio
) -> None:
    page.wait_for_function("() => document.querySelector('#scene').src !== ''")
    assert (
        page.evaluate(f"async () => {SCENE}.softwareWebGL()") is True
    )  # SwiftShader, as launched here
    query = parse_qs(urlsplit(page.locator("#scene").get_attribute("src")).query)
    assert query.get("fixedDpr") == [str(page.evaluate(f"async () => {SCENE}.SOFTWARE_SCENE_DPR"))]
    assert float(query["fixedDpr"][0]) < 1
    assert page.get_by_test_id("scene-note").is_visible()
    # the scene still loads and draws at that ratio (the shared page leaves it out otherwise)
    with live_scene(page) as frame:
        frame.locator("canvas").first.wait_for(state="attached", timeout=60_000)


def test_only_software_renderers_are_taken_for_software(page: Any) -> None:
    for name in SOFTWARE_RENDERERS:
        assert page.evaluate(f"async (n) => {SCENE}.SOFTWARE_RENDERERS.test(n)", name), name
    for name in GPU_RENDERERS:
        assert not page.evaluate(f"async (n) => {SCENE}.SOFTWARE_RENDERERS.test(n)", name), name
