"""In a real browser: the user picks the Panda, the page says its meshes are loading, the scene
draws it from its own meshes and the simulated operator drives it; a demonstration plays on the
Panda and exports checked for it, and its recording, whose capture times break the Panda's
limits, exports with the same button at the person's pace, slowed only where the Panda needs it,
and checked; that recording, played as the source, moves the Panda along the path planned over
all of it; the Puma560 comes back and a recording exports for it."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from studio.kinematics import load_robot, robot_names
from tests.e2e.conftest import Studio, shot
from tests.web.conftest import wait_for

pytestmark = pytest.mark.e2e

DRAW_TIMEOUT_S = 120.0
"""Reading a robot's meshes takes seconds alone, far longer on a machine shared by many."""
DEMO = "sample-reach-1"
SIZES = ((1280, 720), (1920, 1080))
"""The screens the page is looked at on: a laptop's and a desktop monitor's."""


def _robot_select(page: Any) -> Any:
    return page.get_by_role("combobox", name="Robot")


def _q_robot(studio_server: Studio) -> np.ndarray:
    return np.array(studio_server.get("/api/source")["q_robot"])


def _download(page: Any, kind: str, name: str, fmt: str) -> tuple[str, str]:
    """Export ``name`` from the ``kind`` list as ``fmt``, passing the checks. Returns the file's
    name and text."""
    noun = kind.capitalize()
    page.get_by_role("combobox", name=f"{noun} to export").select_option(name)
    page.get_by_role("combobox", name=f"{noun} export format").select_option(fmt)
    with page.expect_download(timeout=DRAW_TIMEOUT_S * 1000) as download:
        page.get_by_role("button", name=f"Export {kind}", exact=True).click()
    text = open(download.value.path()).read()  # noqa: PTH123, SIM115
    return download.value.suggested_filename, text


def test_the_user_teaches_the_panda_plays_and_exports_a_demonstration_then_back(
    page: Any, studio_server: Studio
) -> None:
    select = _robot_select(page)
    offered = select.locator("option").evaluate_all("els => els.map(e => e.value)")
    assert offered == list(robot_names())
    assert select.input_value() == "puma560"
    studio_server.send("PUT", "/api/source", {"kind": "simulator"})
    assert wait_for(lambda: studio_server.get("/api/source")["running"])

    # every line the robot's notes show, as they come and go
    page.evaluate(
        """() => {
        window.robotNotes = [];
        const box = document.getElementById("robot-notes");
        new MutationObserver(() => window.robotNotes.push(box.innerText))
          .observe(box, { childList: true, subtree: true, characterData: true });
      }"""
    )
    select.select_option("panda")
    panda = load_robot("panda")
    drawn = len(panda.visual_model.geometryObjects)
    assert wait_for(
        lambda: (
            studio_server.get("/api/robots")["drawn"] == "panda"
            and studio_server.get("/api/robots")["drawn_meshes"] == drawn
        ),
        timeout=DRAW_TIMEOUT_S,
    ), (page.inner_text("#source-error"), studio_server.log_tail())
    # meanwhile the page said what it was doing, rather than appear stuck
    notes = page.evaluate("window.robotNotes")
    assert any("Loading the Franka Emika Panda" in n for n in notes), notes
    assert studio_server.get("/api/robots")["robot"] == "panda"
    # the live chain drives its seven joints, within its limits
    assert wait_for(lambda: _q_robot(studio_server).shape == (7,))
    first = _q_robot(studio_server)
    assert wait_for(lambda: not np.allclose(_q_robot(studio_server), first, atol=1e-3))
    q = _q_robot(studio_server)
    assert np.all(q >= panda.lower - 1e-9) and np.all(q <= panda.upper + 1e-9)
    assert wait_for(lambda: len(page.inner_text("#src-q").split()) == 8)  # 7 angles and "°"
    assert page.locator("#retarget-mode option[value='joint']").is_disabled()
    assert page.input_value("#retarget-mode") == "cartesian"
    shot(page, "robot-panda", "sec-source")

    # a demonstration plays on the Panda: retargeted, its seven joints moving
    row = page.locator(f"[data-testid='demo-row'][data-name='{DEMO}']")
    row.get_by_role("button", name=f"Preview {DEMO} on the robot").click()
    seen: list[np.ndarray] = []

    def panda_plays() -> bool:
        p = studio_server.get("/api/scene/playback")
        if p["active"] and p["robot"] == "panda" and p["drawn"] == "panda" and not p["finished"]:
            seen.append(np.radians(p["q_robot_deg"]))
        return len(seen) >= 2 and not np.allclose(seen[0], seen[-1], atol=1e-4)

    assert wait_for(panda_plays, timeout=DRAW_TIMEOUT_S, step=0.02), (
        studio_server.get("/api/source")["robot_notes"],
        studio_server.log_tail(),
    )
    for q in seen:
        assert q.shape == (7,)
        assert np.all(q >= panda.lower - 1e-6) and np.all(q <= panda.upper + 1e-6)
    # its end is the Panda's goal, and its hand stays within the Panda's reach
    assert "out of the Franka Emika Panda's reach" not in page.inner_text("#robot-notes")
    for width, height in SIZES:
        page.set_viewport_size({"width": width, "height": height})
        shot(page, f"robot-panda-demonstration-{width}x{height}", "sec-demos")
        shot(page, f"robot-panda-notes-{width}x{height}", "sec-source")
    page.set_viewport_size({"width": 1440, "height": 900})

    # the demonstration exports for the Panda, timed and checked
    name, text = _download(page, "demonstration", DEMO, "csv")
    assert name == f"{DEMO}.panda.csv"
    assert "NOT checked" not in text and "time," + ",".join(panda.joint_names) in text
    # its recording, at the capture rate, breaks the Panda's acceleration limits: the Export
    # button writes it at the person's pace, slowed only where the Panda needs it, and checked
    name, text = _download(page, "recording", DEMO, "csv")
    assert name == f"{DEMO}.panda.csv"
    assert "NOT checked" not in text and "\ntime," + ",".join(panda.joint_names) in text
    assert "# note: at the source's pace" in text
    assert not page.get_by_test_id("recording-export-error").is_visible()
    assert "person's pace" in page.get_by_test_id("recording-export-done").inner_text()

    # the recording played as the source: the Panda follows the path planned over all of it,
    # the path the export wrote, and the page says so
    page.select_option("[data-testid='source-kind']", "recording")
    page.select_option("[data-testid='source-recording']", DEMO)
    page.click("[data-testid='source-apply']")
    planned = "Franka Emika Panda follows the path planned over the whole recording"
    assert wait_for(lambda: planned in page.inner_text("#robot-notes"), timeout=DRAW_TIMEOUT_S), (
        page.inner_text("#robot-notes"),
        studio_server.log_tail(),
    )
    q = _q_robot(studio_server)
    assert np.all(q >= panda.lower - 1e-9) and np.all(q <= panda.upper + 1e-9)
    shot(page, "robot-panda-recording-planned", "sec-source")

    select.select_option("puma560")
    assert wait_for(
        lambda: (
            studio_server.get("/api/robots")["drawn"] == "puma560"
            and studio_server.get("/api/robots")["drawn_meshes"] == 7
        )
    )
    assert wait_for(lambda: _q_robot(studio_server).shape == (6,))
    assert wait_for(lambda: page.input_value("#retarget-mode") == "joint")
    assert not page.locator("#retarget-mode option[value='joint']").is_disabled()

    # a recording exports for the Puma560 from the recordings list (its capture-rate fitting
    # noise breaks the acceleration limits: written at the person's pace)
    name, text = _download(page, "recording", DEMO, "csv")
    assert name == f"{DEMO}.puma560.csv"
    assert "time," + ",".join(load_robot("puma560").joint_names) in text
    assert page.errors == []  # type: ignore[attr-defined]
