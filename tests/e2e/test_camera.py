"""The camera teacher in a real browser: Chromium's fake camera plays a clip made at test time.

Each clip (``tests/e2e/camera_clips.py``) carries its frame index in a corner, which the page
reads back for every frame it estimates, so results are matched to what was drawn. Pose
estimation runs in the page (the vendored BlazePose); only landmarks reach the studio.

BlazePose runs on the CPU, at up to the camera's rate, far slower on a busy machine: these tests
wait for events (frames estimated, answers received), never for a time. So that the model loads
once, the tests that estimate share one page in one Chromium, whose fake camera plays the file
``live.y4m``: Chromium opens that file anew at each start of the camera, so a test puts its clip
there before it switches the source to the camera, and afterwards the source goes back to the
simulator (the camera stops). Each clip is stamped from its own first index
(:data:`CLIP_FIRST`), so a frame of another clip is never taken for one of this test's. The 3D
scene is left out of these pages (an empty page in its frame): none of these tests looks at it,
and drawn in software it took a third of the CPU of each estimated frame.
"""

from __future__ import annotations

import math
import os
import shutil
import statistics
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import pytest

from tests.conftest import require
from tests.e2e.camera_clips import (
    CLIPS,
    COLLECT_FRAMES_JS,
    HEIGHT,
    MANNEQUIN_FLEXION_DEG,
    WIDTH,
    Mannequin,
    blank_clip,
    figure_elbow_deg,
    image_elbow_deg,
    mannequin_q,
)
from tests.e2e.conftest import CHROMIUM, CHROMIUM_FLAGS, Studio, leave_out_scene, shot
from tests.page_hooks import hook

pytestmark = pytest.mark.e2e

READY_TIMEOUT_MS = 60_000
ESTIMATE_TIMEOUT_MS = 420_000
"""Loading the model and estimating the first frames: seconds alone, minutes on a shared machine."""
STATUS_TIMEOUT_MS = 240_000
CLIP_FPS = 10
"""The frame rate of the clips (their makers' default), the camera's rate."""
FIGURE_FRAMES = 120
"""Frames of the drawn-figure clip (12 s at 10 frames/s, one raise and lower, looped)."""
FIGURE_SAMPLES = 36
"""Estimated frames of the drawn figure compared with the drawing, at least, and over
FIGURE_LOOPS whole raises and lowers (FIGURE_FRAMES / CLIP_FPS seconds each). Over a third of the
loop, which third the page estimated decided the mean: the studio's elbow MAE read 7.1 to 12.7
degrees from one run to the next (one full suite failed at 10.8); over 36 frames spread on the whole
loop it read 7.0 to 10.1, the image landmarks alone 6.2 to 8.3. A page that estimates at camera rate
gets 36 frames in a third of the loop, so whole loops are waited for."""
FIGURE_LOOPS = 2
"""Loops of the figure clip compared. Over one (55 to 110 frames at camera rate) the studio's MAE
read 7.3 to 10.7 in ten runs: its fit of the nearly straight arm, the loop's first and last tenth,
errs by 20 to 45 degrees in some runs (the image landmarks by 1 to 5 there), and the first frames
after the camera starts are the worst; two loops weigh them by half."""
MANNEQUIN_FRAMES = 40
"""Frames of the rendered-mannequin clip (4 s at 10 frames/s, one raise and lower, looped)."""
MANNEQUIN_SAMPLES = 16
"""Estimated frames of the mannequin compared with the rendering, at least, and over one whole loop:
enough that a few poorly estimated frames do not decide the mean (over 10 frames the studio's elbow
MAE read 5.9 to 14.7 degrees from one run to the next, which frames a busy machine estimates
varying)."""
SETTLE_FRAMES = 2
"""The first frames of a clip, which settle the studio's filter, left out of the comparisons."""
ELBOW_MAE_DEG = 10.0
ARM_PX = 40.0
"""How near (pixels, median) the taped arm's landmarks must be to the rendered arm's joints: the
two shoulders are 92 px apart in the mannequin clip, the elbows 100-150 px."""
LOOPBACK = {"127.0.0.1", "localhost", "::1", "[::1]"}
POSE_FILES = "/static/vendor/pose-landmarker/"
CLIP_SPAN = 128
"""Stamps each clip may use, from its first: no clip is longer."""
CLIP_FIRST = {
    "figure": 0,
    "mannequin": CLIP_SPAN,
    "astronaut": 2 * CLIP_SPAN,
    "blank": 3 * CLIP_SPAN,
}
"""The stamp of each clip's first frame: the clips' stamps do not overlap."""
CLIP_FRAMES = {"figure": FIGURE_FRAMES, "mannequin": MANNEQUIN_FRAMES}
"""Frames of the clips whose length the tests set (the others keep their makers' length)."""


@pytest.fixture(scope="module")
def clip_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("camera-clips")


@pytest.fixture(scope="module")
def make_clip(clip_dir: Path) -> Callable[[str], Path]:
    made: dict[str, Path] = {}

    def make(name: str) -> Path:
        if name not in made:
            if name == "astronaut":
                try:
                    import skimage.data  # noqa: F401
                except ImportError:
                    require(False, "scikit-image is not installed (pip install -e .[test])")
            path = clip_dir / f"{name}.y4m"
            sized = {"frames": CLIP_FRAMES[name]} if name in CLIP_FRAMES else {}
            made[name] = CLIPS[name](path, first=CLIP_FIRST[name], **sized)
        return made[name]

    return make


class CameraPage:
    """The studio page in a Chromium whose camera plays a clip, and every request it made."""

    def __init__(self, page: Any, requests: list[str]) -> None:
        self.page = page
        self.requests = requests
        self.clip: str | None = None
        """The clip the camera plays (a name of :data:`CLIP_FIRST`), set by ``show``."""

    def use_camera(self, side: str = "right") -> None:
        self.page.select_option("[data-testid='source-kind']", "camera")
        self.page.select_option("[data-testid='source-side']", side)
        self.page.click("[data-testid='source-apply']")

    def frames(
        self, count: int, where: str = "true", *, settle: int = 0, span_s: float = 0.0
    ) -> list[dict[str, Any]]:
        """Wait for ``count`` answered frames of this test's clip satisfying ``where`` (a JS test
        of ``f``) after the first ``settle`` of them, captured over ``span_s`` seconds at least;
        those frames (``count`` or more) are returned, ``f.tag`` then the frame's index in the clip."""
        if self.clip is not None:
            first = CLIP_FIRST[self.clip]
            where = (
                f"f.tag !== null && f.tag >= {first} && f.tag < {first + CLIP_SPAN} && ({where})"
            )
        test = f"(f) => {where}"
        self.page.wait_for_function(
            f"""() => {{
                const fs = window.__frames.filter({test}).slice({settle});
                return fs.length >= {count} && fs[fs.length - 1].body.t - fs[0].body.t >= {span_s};
            }}""",
            timeout=ESTIMATE_TIMEOUT_MS,
        )
        frames = self.page.evaluate(f"() => window.__frames.filter({test}).slice({settle})")
        if self.clip is not None:
            for f in frames:
                f["tag"] -= CLIP_FIRST[self.clip]
        return frames

    def status(self) -> str:
        return self.page.locator("[data-testid='camera-status']").inner_text().strip()


def camera_browser(browser: Any, clip: Path | None, *, allow: bool = True) -> Any:
    """A Chromium whose fake camera plays ``clip`` (a test pattern without), allowed or refused."""
    args = [*CHROMIUM_FLAGS, "--use-fake-device-for-media-stream"]
    if allow:
        args.append("--use-fake-ui-for-media-stream")
    if clip is not None:
        args.append(f"--use-file-for-fake-video-capture={clip}")
    return browser.browser_type.launch(executable_path=CHROMIUM, args=args, headless=True)


def open_studio(chromium: Any, studio: Studio, init_script: str | None = None) -> CameraPage:
    """The studio, ready, in a new context of ``chromium``, its 3D scene left out, collecting
    every answered frame (``COLLECT_FRAMES_JS``) and every request."""
    context = chromium.new_context(viewport={"width": 1440, "height": 900})
    leave_out_scene(context, studio)
    if init_script:
        context.add_init_script(init_script)
    page = context.new_page()
    requests: list[str] = []
    page.on("request", lambda r: requests.append(r.url))
    page.goto(studio.base + "/")
    page.wait_for_selector("body[data-ready='1']", timeout=READY_TIMEOUT_MS)
    page.evaluate(COLLECT_FRAMES_JS)
    return CameraPage(page, requests)


@pytest.fixture(scope="module")
def live_clip(clip_dir: Path) -> Path:
    """The file the shared Chromium's fake camera plays: a test puts its clip here."""
    return blank_clip(clip_dir / "live.y4m", first=CLIP_FIRST["blank"])


@pytest.fixture(scope="module")
def camera_page(browser: Any, live_clip: Path, studio_server: Studio) -> Iterator[CameraPage]:
    """The studio page the estimating tests share (the pose model loads once), in the module's
    one Chromium whose camera is allowed and plays ``live_clip``."""
    chromium = camera_browser(browser, live_clip)
    try:
        yield open_studio(chromium, studio_server)
    finally:
        chromium.close()


@pytest.fixture
def show(
    camera_page: CameraPage,
    make_clip: Callable[[str], Path],
    live_clip: Path,
    studio_server: Studio,
) -> Iterator[Callable[[str], CameraPage]]:
    """Put a clip (by name) before the shared page's camera, to be played from its next start;
    afterwards the source goes back to the simulator and the page's camera stops."""
    cam = camera_page
    p = hook(cam.page)
    stopped = "p => !p.S.camera.running && !p.S.camera.starting && !p.S.camera.stream"

    def show_(name: str) -> CameraPage:
        assert cam.page.evaluate(stopped, p), "the camera is on: it would go on with its clip"
        staged = live_clip.with_suffix(".next")
        shutil.copyfile(make_clip(name), staged)
        os.replace(staged, live_clip)  # whole: the camera never opens half a clip
        cam.page.evaluate("() => { window.__frames = []; }")
        cam.clip = name
        return cam

    try:
        yield show_
    finally:
        cam.clip = None
        studio_server.send("PUT", "/api/source", {"kind": "simulator"})
        cam.page.wait_for_function(stopped, arg=p, timeout=STATUS_TIMEOUT_MS)


@pytest.fixture
def open_camera(
    browser: Any, camera_page: CameraPage, studio_server: Studio
) -> Iterator[Callable[..., CameraPage]]:
    """Open the studio in a page of its own, in the shared Chromium (its camera allowed) or in
    one whose camera is refused; the source goes back to the simulator afterwards."""
    opened: list[Any] = []

    def open_(*, allow: bool = True, init_script: str | None = None) -> CameraPage:
        chromium = camera_page.page.context.browser
        if not allow:
            chromium = camera_browser(browser, None, allow=False)
            opened.append(chromium)
        cam = open_studio(chromium, studio_server, init_script)
        opened.append(cam.page.context)
        return cam

    try:
        yield open_
    finally:
        for done in reversed(opened):
            done.close()
        studio_server.send("PUT", "/api/source", {"kind": "simulator"})


def one_sentence(text: str) -> bool:
    return text.endswith(".") and ". " not in text and "\n" not in text


def studio_elbow_deg(q_human: list[float]) -> float:
    """The interior elbow angle from the human arm's elbow flexion (elbow_Z; 0 is straight)."""
    return 180.0 - abs(math.degrees(q_human[3]))


def elbow_maes(frames: list[dict[str, Any]], drawn: list[float]) -> tuple[float, float]:
    """Mean absolute error (deg) against the drawn elbow of the studio's fit and of the image
    landmarks alone."""
    studio = [studio_elbow_deg(f["answer"]["q_human"]) for f in frames]
    image = [image_elbow_deg(f["body"]["image"]) for f in frames]
    return (
        statistics.fmean(abs(a - b) for a, b in zip(studio, drawn, strict=True)),
        statistics.fmean(abs(a - b) for a, b in zip(image, drawn, strict=True)),
    )


def test_a_photograph_is_seen_and_only_landmarks_reach_the_studio(
    show: Callable[[str], CameraPage], studio_server: Studio
) -> None:
    cam = show("astronaut")
    cam.use_camera("right")
    seen = cam.frames(3, "f.answer && f.answer.person_detected")
    assert all(f["body"]["world"] and len(f["body"]["world"]) == 33 for f in seen)
    assert all(f["body"]["width"] == 640 and f["body"]["height"] == 480 for f in seen)
    assert {f["body"]["model"] for f in seen} == {"lite"}

    source = studio_server.get("/api/source")
    assert source["kind"] == "camera" and source["person_detected"] is True
    assert source["frames"] >= 3 and source["model"] == "lite"
    # The page shows the frame rate it achieves and which joints the camera sees.
    cam.page.wait_for_function(
        "() => /^[0-9.]+$/.test(document.querySelector(\"[data-testid='camera-fps']\").textContent)",
        timeout=STATUS_TIMEOUT_MS,
    )
    assert len(cam.page.get_attribute("[data-testid='camera-observable']", "data-observable")) == 7
    privacy = cam.page.locator("[data-testid='camera-privacy']")
    assert privacy.is_visible() and "No camera image is stored" in privacy.inner_text()
    shot(cam.page, "camera-astronaut", "sec-source")

    # Nothing left this machine: the model, the wasm and the page all came from the studio.
    assert any(POSE_FILES + "pose_landmarker_lite.task" in url for url in cam.requests)
    outside = [
        url
        for url in cam.requests
        if urlsplit(url).scheme not in ("blob", "data") and urlsplit(url).hostname not in LOOPBACK
    ]
    assert outside == []


def test_the_studio_tracks_a_drawn_elbow(show: Callable[[str], CameraPage]) -> None:
    """A drawn figure bends its right elbow 170 -> 60 degrees: the studio's elbow follows the drawing."""
    cam = show("figure")
    cam.use_camera("right")
    frames = cam.frames(
        FIGURE_SAMPLES,
        "f.tag !== null && f.answer && f.answer.person_detected && f.answer.q_human",
        settle=SETTLE_FRAMES,
        span_s=FIGURE_LOOPS * FIGURE_FRAMES / CLIP_FPS,
    )
    drawn = [figure_elbow_deg(f["tag"], FIGURE_FRAMES) for f in frames]
    mae, mae_image = elbow_maes(frames, drawn)
    print(
        f"elbow MAE over {len(frames)} frames: studio {mae:.1f} deg, "
        f"image landmarks alone {mae_image:.1f} deg (drawn {min(drawn):.0f}-{max(drawn):.0f} deg)"
    )
    assert max(drawn) - min(drawn) > 30, "the samples do not span the motion"
    assert mae <= ELBOW_MAE_DEG


def test_the_studios_mannequin_is_seen_with_its_sides_put_back(
    show: Callable[[str], CameraPage],
) -> None:
    """The studio's own human model, rendered, raising its right arm: BlazePose sees a person in
    every frame but takes it for one seen from behind and swaps left and right. The page swaps
    them back (the person faces the camera), so the taped right arm's landmarks are the rendered
    right arm's, and the studio's elbow follows the rendered one."""
    model = Mannequin()
    cam = show("mannequin")
    cam.use_camera("right")
    frames = cam.frames(
        MANNEQUIN_SAMPLES,
        "f.tag !== null",
        settle=SETTLE_FRAMES,
        span_s=MANNEQUIN_FRAMES / CLIP_FPS,
    )
    assert all(f["body"]["world"] is not None for f in frames), "a frame without a person"
    assert all(f["answer"] and f["answer"]["person_detected"] for f in frames)
    swapped = sum(bool(f["swapped"]) for f in frames)
    near, far = [], []  # per frame: mean distance of the right-arm landmarks to each rendered arm
    for f in frames:
        q = mannequin_q(f["tag"], MANNEQUIN_FRAMES)
        seen = [
            [p[0] * WIDTH, p[1] * HEIGHT] for p in (f["body"]["image"][i] for i in (12, 14, 16))
        ]
        for side, out in (("right", near), ("left", far)):
            truth = model.arm_pixels(q, side).tolist()
            out.append(statistics.fmean(math.dist(a, b) for a, b in zip(seen, truth, strict=True)))
    drawn = [180.0 - math.degrees(mannequin_q(f["tag"], MANNEQUIN_FRAMES)[3]) for f in frames]
    mae, mae_image = elbow_maes(frames, drawn)
    print(
        f"mannequin: {swapped}/{len(frames)} frames swapped back; right-arm landmarks "
        f"{statistics.median(near):.0f} px from the rendered right arm (median), "
        f"{statistics.median(far):.0f} px from the left; elbow MAE studio {mae:.1f} deg, "
        f"image landmarks {mae_image:.1f} deg (rendered {min(drawn):.0f}-{max(drawn):.0f} deg)"
    )
    assert swapped > 0, "BlazePose no longer swaps this mannequin: the test lost its subject"
    assert all(n < f for n, f in zip(near, far, strict=True)), "the taped arm is the other arm"
    assert statistics.median(near) < ARM_PX
    assert max(drawn) - min(drawn) > (MANNEQUIN_FLEXION_DEG[1] - MANNEQUIN_FLEXION_DEG[0]) / 4
    # Within the goal, or (on a busy machine the page estimates other frames, and BlazePose's
    # own reading of this mannequin can miss the goal: 17.9 deg once) no worse than the image
    # landmarks the studio is given. A fit that reads the wrong landmarks misses both.
    assert mae <= max(ELBOW_MAE_DEG, mae_image), (mae, mae_image)


def test_no_person_in_view_says_so(
    show: Callable[[str], CameraPage], studio_server: Studio
) -> None:
    cam = show("blank")
    cam.use_camera()
    cam.frames(2, "f.body.world === null")
    cam.page.wait_for_function(
        "() => /No person/.test(document.querySelector(\"[data-testid='camera-status']\").textContent)",
        timeout=STATUS_TIMEOUT_MS,
    )
    assert one_sentence(cam.status())
    assert studio_server.get("/api/source")["person_detected"] is False


def test_a_refused_camera_says_so(open_camera: Callable[..., CameraPage]) -> None:
    cam = open_camera(allow=False)
    cam.use_camera()
    cam.page.wait_for_function(
        "() => /refused the camera/.test(document.querySelector(\"[data-testid='camera-status']\").textContent)",
        timeout=STATUS_TIMEOUT_MS,
    )
    assert one_sentence(cam.status())


BUSY_CAMERA = """
navigator.mediaDevices.getUserMedia = () =>
    Promise.reject(new DOMException("Could not start video source", "NotReadableError"));
"""
"""What Chromium answers when another program holds the camera."""


def test_a_busy_camera_says_so(open_camera: Callable[..., CameraPage]) -> None:
    cam = open_camera(init_script=BUSY_CAMERA)
    cam.use_camera()
    cam.page.wait_for_function(
        "() => /camera is busy/.test(document.querySelector(\"[data-testid='camera-status']\").textContent)",
        timeout=STATUS_TIMEOUT_MS,
    )
    assert one_sentence(cam.status())
    assert cam.page.evaluate("p => p.S.camera.running", hook(cam.page)) is False


NO_CAMERA = """
navigator.mediaDevices.getUserMedia = () =>
    Promise.reject(new DOMException("Requested device not found", "NotFoundError"));
"""
"""What Chromium answers on a machine with no camera."""


def test_a_camera_error_goes_with_the_camera(open_camera: Callable[..., CameraPage]) -> None:
    """The red "No camera was found" stays while the camera is the source, and goes when the
    user switches to the hand guide or the simulator (it stayed until a reload)."""
    cam = open_camera(init_script=NO_CAMERA)
    page = cam.page
    status = page.get_by_test_id("camera-status")
    for other in ("hand", "simulator"):
        cam.use_camera()
        page.wait_for_function(
            "() => /No camera was found/.test("
            "document.querySelector(\"[data-testid='camera-status']\").textContent)",
            timeout=STATUS_TIMEOUT_MS,
        )
        assert status.is_visible()
        page.select_option("[data-testid='source-kind']", other)
        page.click("[data-testid='source-apply']")
        page.wait_for_function(
            "([p, kind]) => p.S.source && p.S.source.kind === kind", arg=[hook(page), other]
        )
        status.wait_for(state="hidden", timeout=STATUS_TIMEOUT_MS)
        assert status.inner_text() == ""


def test_hand_guide_countdown_and_named_controls(
    open_camera: Callable[..., CameraPage], studio_server: Studio
) -> None:
    """The hand guide says what to do; Record counts down first (pressing it again cancels), and
    the recording is listed as the hand guide's."""
    cam = open_camera()
    page = cam.page
    for name in ("Teaching arm", "Pose model", "Mirror picture", "Countdown"):
        assert page.get_by_label(name, exact=True).count() == 1, name
    page.select_option("[data-testid='source-kind']", "hand")
    page.click("[data-testid='source-apply']")
    page.wait_for_function("p => p.S.source && p.S.source.kind === 'hand'", arg=hook(page))
    note = page.locator("[data-testid='hand-guide-note']")
    assert note.is_visible() and "Drag the handle" in note.inner_text()
    assert not page.locator("[data-testid='camera-panel']").is_visible()

    page.get_by_label("Countdown", exact=True).fill("5")
    page.click("[data-testid='capture-toggle']")
    left = page.locator("[data-testid='capture-countdown-left']")
    left.wait_for(state="visible")
    assert "Recording in 5 s" in left.inner_text()
    page.click("[data-testid='capture-toggle']")  # cancel
    left.wait_for(state="hidden")
    assert studio_server.get("/api/capture")["active"] is False
    assert page.get_attribute("[data-testid='capture-toggle']", "data-active") == "0"

    # Counted down to the end, the recording starts; the list says what it holds.
    page.get_by_label("Countdown", exact=True).fill("1")
    page.fill("[data-testid='capture-name']", "hand-countdown")
    page.click("[data-testid='capture-toggle']")
    page.wait_for_selector("[data-testid='capture-toggle'][data-active='1']")
    studio_server.send("POST", "/api/source/hand", {"position": [0.25, -0.1, -0.3], "wxyz": None})
    page.click("[data-testid='capture-toggle']")
    page.wait_for_selector("[data-testid='capture-toggle'][data-active='0']")
    row = page.locator("[data-testid='recording-row'][data-name='hand-countdown']")
    row.wait_for()
    assert row.locator("[data-testid='recording-kind']").inner_text() == "hand guide"
    studio_server.send("DELETE", "/api/recordings/hand-countdown")  # the stories start clean
