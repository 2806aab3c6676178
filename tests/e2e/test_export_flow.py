"""In a real browser, at a laptop's 1280 x 720: a person exports a recording whose capture
times break the robot's limits. The Export button writes it at the person's pace, slowed only
where the robot needs it, with the physics report in the file; the page says so in words, with
no command-line flag, beside the button. A motion the robot truly cannot make is refused in
words, with "Export anyway" right under the sentence, in view, writing the findings into the
file."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import Studio, own_page, shot
from tests.web.conftest import wait_for

pytestmark = pytest.mark.e2e

EXPORT_TIMEOUT_S = 240.0
"""Retargeting, timing, the checks and the robot's first MuJoCo model take minutes on a machine
shared by many."""
WIDTH, HEIGHT = 1280, 720
CLI_WORDS = re.compile(r"--[a-z]|studio export|studio simulate|TOPP")
"""What only the command line speaks: a flag, a command, the timing's algorithm."""


def _read(download: Any) -> str:
    return Path(download.path()).read_text()


def _in_view(page: Any, test_id: str) -> bool:
    """Whether the element is shown whole inside the window, as it is scrolled now (to the
    pixel: layout rounds fractions)."""
    box = page.get_by_test_id(test_id).bounding_box()
    return box is not None and box["y"] >= -1 and box["y"] + box["height"] <= HEIGHT + 1


def _export_box_text(page: Any, kind: str) -> str:
    return page.get_by_test_id(f"{kind}-export").inner_text()


def test_a_recording_too_fast_for_the_robot_exports_with_the_primary_button(
    browser: Any, studio_server: Studio
) -> None:
    studio_server.send("PUT", "/api/robot", {"name": "puma560"})
    with own_page(browser, studio_server, WIDTH, HEIGHT, accept_downloads=True) as page:
        page.get_by_role("combobox", name="Recording to export").select_option("sample-reach-1")
        page.get_by_role("combobox", name="Recording export format").select_option("csv")
        button = page.get_by_role("button", name="Export recording", exact=True)
        button.scroll_into_view_if_needed()
        with page.expect_download(timeout=EXPORT_TIMEOUT_S * 1000) as download:
            button.click()
        assert download.value.suggested_filename == "sample-reach-1.puma560.csv"
        text = _read(download.value)
        # its capture times break the Puma560's limits: at the person's pace, slowed only
        # where needed, checked, with the physics report in the file
        assert "# safety checks: passed" in text, text[:2000]
        assert "# note: at the source's pace" in text
        assert "# physics (MuJoCo, puma560" in text
        done = page.get_by_test_id("recording-export-done")
        done.wait_for(state="visible")
        said = done.inner_text()
        assert "faster than the Puma 560 may" in said or "faster than the" in said, said
        assert "person's pace, slowed only where the robot needs it" in said
        assert "physics (MuJoCo, puma560" in said
        assert not CLI_WORDS.search(_export_box_text(page, "recording")), _export_box_text(
            page, "recording"
        )
        assert not page.get_by_test_id("recording-export-error").is_visible()
        assert not page.get_by_role(
            "button", name="Export anyway, findings written in the file"
        ).is_visible()
        shot(page, "export-recording-at-pace-1280x720")
        assert _in_view(page, "recording-export-done"), done.bounding_box()
        assert _in_view(page, "recording-export-go")
        assert page.errors == []


def test_a_motion_the_robot_cannot_make_is_refused_in_words_with_export_anyway_in_view(
    browser: Any, studio_server: Studio
) -> None:
    """The Z1 cannot make the second sample's reach (the checks refuse it at any pace)."""
    studio_server.send("PUT", "/api/robot", {"name": "z1"})
    try:
        assert wait_for(lambda: studio_server.get("/api/robots")["robot"] == "z1")
        with own_page(browser, studio_server, WIDTH, HEIGHT, accept_downloads=True) as page:
            page.get_by_role("combobox", name="Demonstration to export").select_option(
                "sample-reach-2"
            )
            page.get_by_role("combobox", name="Demonstration export format").select_option("csv")
            button = page.get_by_role("button", name="Export demonstration", exact=True)
            button.scroll_into_view_if_needed()
            button.click()
            error = page.get_by_test_id("demonstration-export-error")
            error.wait_for(state="visible", timeout=EXPORT_TIMEOUT_S * 1000)
            sentence = error.inner_text()
            assert sentence.startswith("Refused"), sentence
            assert "cannot make this motion as it is" in sentence
            findings = page.get_by_test_id("demonstration-export-findings")
            assert findings.is_visible() and findings.locator("li").count() >= 1
            box = _export_box_text(page, "demonstration")
            assert not CLI_WORDS.search(box), box
            # the sentence and the button that acts on it, both in view without scrolling
            anyway = page.get_by_role("button", name="Export anyway, findings written in the file")
            assert anyway.is_visible()
            assert _in_view(page, "demonstration-export-error")
            assert _in_view(page, "demonstration-export-anyway")
            shot(page, "export-refused-1280x720")
            with page.expect_download(timeout=EXPORT_TIMEOUT_S * 1000) as download:
                anyway.click()
            text = _read(download.value)
            assert "# safety checks: NOT checked" in text
            first = findings.locator("li").first.inner_text()
            assert first in text
            assert "# physics (MuJoCo, z1" in text
            said = page.get_by_test_id("demonstration-export-done").inner_text()
            assert "Not safe for the" in said and "each stated in the file" in said
            assert page.errors == []
    finally:
        studio_server.send("PUT", "/api/robot", {"name": "puma560"})
