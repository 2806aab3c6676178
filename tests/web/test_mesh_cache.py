"""A damaged mesh cache entry is built again, never drawn from.

A ``cache/meshes/*.npz`` entry whose part pointed at a frame the model does not have left the UR5
undrawn ("loading" forever) and the scene loop failing on every frame, across restarts; a
malformed part list raised an uncaught ``TypeError``; NaN vertices were accepted; and the key did
not cover the model whose frame indices the parts use.
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pytest

from studio.kinematics import MeshConfig, load_robot
from studio.web.scene import _robot_view
from studio.web.scene._mesh_cache import cached_parts


def _damage(path: Path, how: str) -> None:
    """Rewrite the cache file ``path`` (a stored npz) damaged in one way, still a valid npz."""
    with np.load(path, allow_pickle=False) as npz:
        arrays = {k: npz[k] for k in npz.files}
    meta = json.loads(str(arrays["meta"]))
    if how == "frame":
        meta[0]["frame"] = 999
    elif how == "parts":
        meta = {"not": "a list"}
    elif how == "part":
        meta[0] = ["name", 0]
    elif how == "colour":
        meta[0]["rgb"] = "red"
    elif how == "nan":
        arrays["v0"] = arrays["v0"].copy()
        arrays["v0"][0, 0] = np.nan
    arrays["meta"] = np.array(json.dumps(meta))
    stream = io.BytesIO()
    np.savez(stream, **arrays)
    path.write_bytes(stream.getvalue())


@pytest.mark.parametrize("how", ["frame", "parts", "part", "colour", "nan"])
def test_a_damaged_entry_is_built_again_and_the_robot_drawn(tmp_path: Path, how: str, caplog):
    arm = load_robot("so100")
    first = _robot_view.arm_view(arm, MeshConfig(), cache=tmp_path)
    (entry,) = tmp_path.glob("so100-*.npz")
    _damage(entry, how)
    again = _robot_view.arm_view(arm, MeshConfig(), cache=tmp_path)
    assert "is ignored" in caplog.text and "written again" in caplog.text
    assert [p.frame for p in again.parts] == [p.frame for p in first.parts]
    assert all(np.isfinite(p.vertices).all() for p in again.parts)
    poses = again.poses(np.array(arm.home, dtype=float))  # what the scene loop does each frame
    assert poses.shape == (len(again.parts), 4, 4) and np.isfinite(poses).all()
    caplog.clear()
    _robot_view.arm_view(arm, MeshConfig(), cache=tmp_path)
    assert "is ignored" not in caplog.text  # written anew, read as is


def test_the_key_covers_the_model_the_parts_are_attached_to(monkeypatch):
    keys: list[tuple] = []
    real = _robot_view.mesh_key
    monkeypatch.setattr(_robot_view, "mesh_key", lambda *a: keys.append(a) or real(*a))
    arm = load_robot("so100")
    _robot_view.arm_view(arm, MeshConfig())
    stamp = json.dumps(keys[0], default=str)
    for geometry in arm.visual_model.geometryObjects:  # each object's place in the model
        assert json.dumps(geometry.name) in stamp


def test_cached_parts_refuses_frames_the_caller_does_not_have(tmp_path: Path):
    arm = load_robot("so100")
    built: list[int] = []

    def build():
        built.append(1)
        return _robot_view.arm_view(arm, MeshConfig()).parts

    cached_parts(tmp_path, "so100", "k", build)
    assert len(cached_parts(tmp_path, "so100", "k", build, frames=range(100))) and len(built) == 1
    cached_parts(tmp_path, "so100", "k", build, frames=range(0))
    assert len(built) == 2
