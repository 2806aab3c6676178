"""The vendored front-end libraries: every file is the one the manifest names, served as is.

``studio/web/static/vendor/SHA256SUMS`` holds the SHA-256 of every file copied from a registry
package (uPlot, ``@mediapipe/tasks-vision``) or built from one (BlazePose's model bundles). A
file edited by hand, half-copied, or added without its hash fails here; so does a vendored file the
studio would serve with the wrong type (Chromium compiles ``.wasm`` streamed from the network only
when it is ``application/wasm``).
"""

from __future__ import annotations

import hashlib
import zipfile
from pathlib import Path

import pytest

from studio.web._app import STATIC_DIR

VENDOR = STATIC_DIR / "vendor"
MANIFEST = VENDOR / "SHA256SUMS"
TASKS = "mediapipe-tasks-vision"
TASKS_FILES = {
    "LICENSE",
    "vision_bundle.mjs",
    "vision_wasm_internal.js",
    "vision_wasm_internal.wasm",
    "vision_wasm_nosimd_internal.js",
    "vision_wasm_nosimd_internal.wasm",
}
"""What the page loads to run BlazePose (SIMD or not), and the licence: nothing else."""
POSE = "pose-landmarker"
POSE_FILES = {"LICENSE", "pose_landmarker_lite.task", "pose_landmarker_full.task"}
"""BlazePose lite and full, and the licence."""


def manifest() -> dict[str, str]:
    """Relative path -> SHA-256, as ``sha256sum`` writes it."""
    entries = {}
    for line in MANIFEST.read_text().splitlines():
        digest, name = line.split(maxsplit=1)
        entries[name.lstrip("*")] = digest
    return entries


def vendored_files() -> set[str]:
    return {
        p.relative_to(VENDOR).as_posix()
        for p in VENDOR.rglob("*")
        if p.is_file() and p.parent != VENDOR
    }


def test_every_vendored_file_is_in_the_manifest_and_matches_it():
    entries = manifest()
    assert set(entries) == vendored_files()
    for name, digest in entries.items():
        assert hashlib.sha256((VENDOR / name).read_bytes()).hexdigest() == digest, (
            f"{name} differs from the copy the manifest names"
        )


@pytest.mark.parametrize(("folder", "files"), [(TASKS, TASKS_FILES), (POSE, POSE_FILES)])
def test_blazepose_is_vendored_with_only_what_the_page_loads(folder, files):
    assert {n.split("/", 1)[1] for n in manifest() if n.startswith(folder + "/")} == files
    assert "Apache License" in (VENDOR / folder / "LICENSE").read_text()


def test_the_pose_bundles_hold_the_two_blazepose_models():
    """A ``.task`` is a zip the PoseLandmarker opens by these two names, stored uncompressed."""
    for model in ("lite", "full"):
        with zipfile.ZipFile(VENDOR / POSE / f"pose_landmarker_{model}.task") as bundle:
            entries = bundle.infolist()
        assert {e.filename for e in entries} == {
            "pose_detector.tflite",
            "pose_landmarks_detector.tflite",
        }
        assert all(e.compress_type == zipfile.ZIP_STORED for e in entries)


@pytest.mark.parametrize(
    ("name", "media_type"),
    [
        (f"{TASKS}/vision_wasm_internal.wasm", "application/wasm"),
        (f"{TASKS}/vision_wasm_nosimd_internal.wasm", "application/wasm"),
        # a module script runs only when served as JavaScript
        (f"{TASKS}/vision_bundle.mjs", "javascript"),
        (f"{TASKS}/vision_wasm_internal.js", "javascript"),
        (f"{POSE}/pose_landmarker_lite.task", None),
    ],
)
def test_the_studio_serves_the_vendored_model_files(client, name, media_type):
    r = client.get(f"/static/vendor/{name}")
    assert r.status_code == 200
    assert r.content == Path(VENDOR / name).read_bytes()
    if media_type:
        assert media_type in r.headers["content-type"]
