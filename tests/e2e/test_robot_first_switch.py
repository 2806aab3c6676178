"""The first switch to a robot whose meshes are not yet kept: the live source goes on while they
load, the robot drawn keeps following the operator, and "q robot" is always the drawn robot's
(the Panda's seven values showed on the six-joint UR5 that was still drawn, which stood still)."""

from __future__ import annotations

import re
from typing import Any

import pytest

from studio.kinematics import load_robot
from tests.e2e.conftest import Studio, own_page
from tests.page_hooks import hook
from tests.web.conftest import wait_for

pytestmark = pytest.mark.e2e

ROBOT = "xarm7"
"""A robot no other browser test loads, so its first switch reads and simplifies its meshes."""
LOAD_TIMEOUT_S = 600.0
"""Building a robot's geometry the first time takes a minute or more on a busy machine."""

RECORD_JS = """p => {
    window.__statuses = [];
    p.listen("source", (s) => window.__statuses.push(
        [s.robot, s.robot_drawn, s.frames, document.getElementById("src-q").textContent,
         s.q_robot]));
}"""
"""Keep every status the page draws, with the "q robot" it drew for it."""


def test_q_robot_is_the_drawn_robots_and_the_source_goes_on_while_meshes_load(
    browser: Any, studio_server: Studio
) -> None:
    studio_server.send("PUT", "/api/source", {"kind": "simulator"})
    joints = load_robot(ROBOT, geometry=False).nq
    puma = load_robot("puma560", geometry=False).nq
    with own_page(browser, studio_server, scene=True) as page:
        try:
            page.evaluate(RECORD_JS, hook(page))
            page.get_by_role("combobox", name="Robot").select_option(ROBOT)
            assert wait_for(
                lambda: studio_server.get("/api/robots")["drawn"] == ROBOT, LOAD_TIMEOUT_S
            ), studio_server.log_tail()
            # drawn, and driven by the live chain (the scene draws it a moment before)
            page.wait_for_function(
                f"() => window.__statuses.some((s) => s[1] === '{ROBOT}' && s[4].length === {joints})",
                timeout=60_000,
            )
            statuses = page.evaluate("() => window.__statuses")
        finally:
            studio_server.send("PUT", "/api/robot", {"name": "puma560"})
        loading = [s for s in statuses if s[0] == ROBOT and s[1] != ROBOT]
        drawn = [s for s in statuses if s[0] == ROBOT and s[1] == ROBOT]
        # while its meshes loaded the live stream went on: statuses with frames counting up
        assert len(loading) >= 2, statuses
        assert loading[-1][2] > loading[0][2]
        # the Puma560 drawn meanwhile kept following, and "q robot" showed its six angles
        for robot, shown, _, text, q in loading:
            assert shown == "puma560" and len(q) == puma, (robot, shown, q)
            assert len(re.findall(r"-?\d+", text)) == puma, text
        assert len({tuple(s[4]) for s in loading}) >= 2, "the robot drawn stood still"
        # once drawn, its own joints; the scene flips the robot drawn just before the live chain
        # takes it over, so one status (on a busy machine) may fall between the two, never more
        assert len(drawn[-1][4]) == joints and len(drawn[-1][3].split()) == joints + 1
        assert sum(len(s[4]) != joints for s in drawn) <= 1, drawn
        assert not page.errors
