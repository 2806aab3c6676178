"""The vendored front-end libraries: every file is the one the manifest names, served as is.

``studio/web/static/vendor/SHA256SUMS`` holds the SHA-256 of every file copied from a registry
package (uPlot, BlazePose's ``@mediapipe/pose``). A file edited by hand, half-copied, or added
without its hash fails here; so does a vendored file the studio would serve with the wrong type
(Chromium compiles ``.wasm`` streamed from the network only when it is ``application/wasm``).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from studio.web._app import STATIC_DIR

VENDOR = STATIC_DIR / "vendor"
MANIFEST = VENDOR / "SHA256SUMS"
POSE = "mediapipe-pose"
POSE_FILES = {
    "LICENSE",
    "pose.js",
    "pose_solution_packed_assets_loader.js",
    "pose_solution_packed_assets.data",
    "pose_web.binarypb",
    "pose_solution_simd_wasm_bin.js",
    "pose_solution_simd_wasm_bin.wasm",
    "pose_solution_wasm_bin.js",
    "pose_solution_wasm_bin.wasm",
    "pose_landmark_lite.tflite",
    "pose_landmark_full.tflite",
}
"""What the page loads for BlazePose lite and full (SIMD or not), and the licence: nothing else."""


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


def test_blazepose_is_vendored_with_only_what_the_page_loads():
    assert {n.split("/", 1)[1] for n in manifest() if n.startswith(POSE + "/")} == POSE_FILES
    assert "Apache License" in (VENDOR / POSE / "LICENSE").read_text()


@pytest.mark.parametrize(
    ("name", "media_type"),
    [
        ("pose_solution_simd_wasm_bin.wasm", "application/wasm"),
        ("pose_solution_wasm_bin.wasm", "application/wasm"),
        ("pose.js", "javascript"),
        ("pose_landmark_lite.tflite", None),
    ],
)
def test_the_studio_serves_the_vendored_model_files(client, name, media_type):
    r = client.get(f"/static/vendor/{POSE}/{name}")
    assert r.status_code == 200
    assert r.content == Path(VENDOR / POSE / name).read_bytes()
    if media_type:
        assert media_type in r.headers["content-type"]
