"""Loading a robot once per process, and in a child process after ``isolate_robot_loading``:
the same robot either way, and every way the child can fail is one sentence or a fallback."""

from __future__ import annotations

import subprocess
import sys
import threading

import numpy as np
import pytest

from studio.kinematics import KinematicsError, load_robot
from studio.kinematics import _robot_load as robot_load
from studio.kinematics._robots import RobotArm, robot_spec

SPEC = robot_spec("so100")  # meshes for both geometries, and quick to build
TEXT = robot_load._urdf_text(SPEC)


def _arm(parts: tuple) -> RobotArm:
    return RobotArm(SPEC, *parts, TEXT)


def test_a_robot_built_in_a_child_process_is_the_robot_built_here():
    here = _arm(robot_load._built(SPEC, TEXT, True))
    child = _arm(robot_load._built_in_child(SPEC, TEXT))
    assert child.joint_names == here.joint_names
    for name in ("lower", "upper", "velocity", "home"):
        np.testing.assert_array_equal(getattr(child, name), getattr(here, name))
    drawn = [(g.name, g.meshPath, g.parentJoint) for g in here.visual_model.geometryObjects]
    assert [
        (g.name, g.meshPath, g.parentJoint) for g in child.visual_model.geometryObjects
    ] == drawn
    for a, b in zip(
        here.visual_model.geometryObjects, child.visual_model.geometryObjects, strict=True
    ):
        np.testing.assert_array_equal(a.placement.homogeneous, b.placement.homogeneous)
        np.testing.assert_array_equal(a.meshScale, b.meshScale)
    rng = np.random.default_rng(4)
    for q in rng.uniform(here.lower, here.upper, size=(8, here.nq)):
        np.testing.assert_allclose(child.forward(q), here.forward(q))
        near = [(c.link_a, c.link_b, c.distance) for c in here.self_collisions(q, 0.05)]
        found = [(c.link_a, c.link_b, c.distance) for c in child.self_collisions(q, 0.05)]
        assert [(a, b) for a, b, _ in found] == [(a, b) for a, b, _ in near]
        np.testing.assert_allclose([d for *_, d in found], [d for *_, d in near], atol=1e-9)


def test_the_visual_meshes_are_kept_as_files_not_triangles():
    _, visual, _ = robot_load._built(SPEC, TEXT, True)
    assert visual.ngeoms > 0
    for obj in visual.geometryObjects:
        assert obj.meshPath.endswith((".stl", ".STL", ".dae"))  # drawn from its file
        assert type(obj.geometry).__name__ == "Sphere" and obj.geometry.radius == 0.0


def test_without_a_child_process_the_robot_loads_here(monkeypatch):
    monkeypatch.setattr(robot_load.sys, "executable", "/nonexistent/python")
    arm = _arm(robot_load._built_in_child(SPEC, TEXT))
    assert arm.checks_collisions and len(arm.visual_model.geometryObjects) > 0


def test_a_child_that_dies_is_one_sentence(monkeypatch):
    monkeypatch.setattr(robot_load, "_CHILD", "import sys; print('assimp crashed', file=sys.stderr); sys.exit(3)")  # fmt: skip
    with pytest.raises(KinematicsError) as err:
        robot_load._built_in_child(SPEC, TEXT)
    message = str(err.value)
    assert "\n" not in message and message.endswith("reinstall example-robot-data.")
    assert "ended with code 3 (assimp crashed)" in message


def test_a_robot_the_child_refuses_is_refused_in_its_sentence(monkeypatch):
    code = "import pathlib, sys; (pathlib.Path(sys.argv[2]) / 'refused.txt').write_text('The SO-100 URDF is gone; reinstall example-robot-data.')"  # fmt: skip
    monkeypatch.setattr(robot_load, "_CHILD", code)
    with pytest.raises(KinematicsError, match=r"^The SO-100 URDF is gone; reinstall"):
        robot_load._built_in_child(SPEC, TEXT)


def test_a_child_that_hangs_is_given_up_in_one_sentence(monkeypatch):
    monkeypatch.setattr(robot_load, "_CHILD", "import time; time.sleep(60)")
    monkeypatch.setattr(robot_load, "LOAD_TIMEOUT_S", 0.5)
    with pytest.raises(KinematicsError, match=r"took over 0 s and was given up; try again"):
        robot_load._built_in_child(SPEC, TEXT)


def test_threads_asking_for_one_robot_together_get_one_arm():
    arms: list[RobotArm] = []
    threads = [
        threading.Thread(target=lambda: arms.append(load_robot("ur3", geometry=False)))
        for _ in range(4)
    ]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len(arms) == 4 and all(arm is arms[0] for arm in arms)


def test_a_server_process_loads_robots_in_a_child_process():
    """``isolate_robot_loading`` then ``load_robot``, in a fresh process: the geometry comes
    from a child process (seen as one), and the arm works."""
    code = (
        "import subprocess, sys\n"
        "from studio.kinematics import isolate_robot_loading, load_robot\n"
        "from studio.kinematics import _robot_load\n"
        "children = []\n"
        "run = subprocess.run\n"
        "def counted(*a, **k):\n"
        "    children.append(a[0][3])\n"
        "    return run(*a, **k)\n"
        "_robot_load.subprocess.run = counted\n"
        "isolate_robot_loading()\n"
        "arm = load_robot('so100')\n"
        "assert load_robot('so100') is arm\n"
        "print(children, arm.checks_collisions, len(arm.self_collisions(arm.home, 1.0)) > 0)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["['so100']", "True", "True"]


FAILING_CHILD = "import sys; sys.exit(3)"


def _same_robot(a: tuple, b: tuple) -> None:
    arm_a, arm_b = _arm(a), _arm(b)
    assert arm_b.joint_names == arm_a.joint_names
    assert [g.meshPath for g in arm_b.visual_model.geometryObjects] == [
        g.meshPath for g in arm_a.visual_model.geometryObjects
    ]
    for q in np.random.default_rng(5).uniform(arm_a.lower, arm_a.upper, size=(4, arm_a.nq)):
        np.testing.assert_allclose(arm_b.forward(q), arm_a.forward(q))
        assert [(c.link_a, c.link_b) for c in arm_b.self_collisions(q, 0.05)] == [
            (c.link_a, c.link_b) for c in arm_a.self_collisions(q, 0.05)
        ]


def test_a_built_robot_is_kept_in_the_cache_and_read_back_without_a_child(tmp_path, monkeypatch):
    monkeypatch.setattr(robot_load, "_cache", [tmp_path])
    built = robot_load._built_in_child(SPEC, TEXT)
    (kept,) = tmp_path.iterdir()
    assert kept.name.startswith("so100-")
    assert sorted(p.name for p in kept.iterdir()) == sorted(
        [*(f"{part}.bin" for part in robot_load._PARTS), robot_load._MANIFEST]
    )
    monkeypatch.setattr(robot_load, "_CHILD", FAILING_CHILD)  # a child would fail: none runs
    _same_robot(built, robot_load._built_in_child(SPEC, TEXT))


def test_a_robot_built_in_this_process_is_kept_and_read_back(tmp_path, monkeypatch):
    """``keep_robot_geometry`` (a studio's planning child): built here, without a child, kept in
    the cache folder as a child's build is, and read back from it the next time."""
    monkeypatch.setattr(robot_load, "_cache", [])
    robot_load.keep_robot_geometry(tmp_path)
    assert robot_load.robot_cache_folder() == tmp_path
    monkeypatch.setattr(robot_load, "_CHILD", FAILING_CHILD)  # a child would fail: none runs
    built = robot_load._load(SPEC, True)
    (kept,) = tmp_path.iterdir()
    assert kept.name.startswith("so100-") and (kept / robot_load._MANIFEST).is_file()
    monkeypatch.setattr(robot_load, "_built", None)  # built again here, it would raise
    again = robot_load._load(SPEC, True)
    assert again.joint_names == built.joint_names
    for q in np.random.default_rng(6).uniform(built.lower, built.upper, size=(4, built.nq)):
        np.testing.assert_allclose(again.forward(q), built.forward(q))
        assert [(c.link_a, c.link_b) for c in again.self_collisions(q, 0.05)] == [
            (c.link_a, c.link_b) for c in built.self_collisions(q, 0.05)
        ]


def test_a_damaged_kept_robot_is_built_again_and_kept_anew(tmp_path, monkeypatch, caplog):
    monkeypatch.setattr(robot_load, "_cache", [tmp_path])
    built = robot_load._built_in_child(SPEC, TEXT)
    (kept,) = tmp_path.iterdir()
    archive = kept / "collision.bin"
    data = bytearray(archive.read_bytes())
    data[len(data) // 2] ^= 0xFF
    archive.write_bytes(bytes(data))
    again = robot_load._built_in_child(SPEC, TEXT)
    assert "ignored and built again" in caplog.text
    _same_robot(built, again)
    monkeypatch.setattr(robot_load, "_CHILD", FAILING_CHILD)
    _same_robot(built, robot_load._built_in_child(SPEC, TEXT))  # the new copy is read


def test_a_cache_that_cannot_be_written_still_gives_the_robot(tmp_path, monkeypatch, caplog):
    blocked = tmp_path / "not-a-folder"
    blocked.write_text("a file where the cache folder should be")
    monkeypatch.setattr(robot_load, "_cache", [blocked])
    arm = _arm(robot_load._built_in_child(SPEC, TEXT))
    assert arm.checks_collisions
    assert "is not kept" in caplog.text


def test_another_pinocchio_or_urdf_is_another_cache_entry(tmp_path, monkeypatch):
    monkeypatch.setattr(robot_load, "_cache", [tmp_path])
    entry = robot_load._cache_entry(SPEC, TEXT)
    assert entry is not None and entry.parent == tmp_path
    monkeypatch.setattr(robot_load.pin, "__version__", "0.0.0")
    assert robot_load._cache_entry(SPEC, TEXT) != entry
    monkeypatch.undo()
    monkeypatch.setattr(robot_load, "_cache", [tmp_path])
    assert robot_load._cache_entry(SPEC, "<robot name='other'/>") != entry
    monkeypatch.setattr(robot_load, "_cache", [])
    assert robot_load._cache_entry(SPEC, TEXT) is None


def test_a_kept_robot_damaged_with_its_hashes_is_built_again(tmp_path, monkeypatch, caplog):
    """An archive damaged before its hashes were written (they match it) raised an uncaught
    ``MemoryError`` in ``loadFromBinary``: ``PUT /api/robot`` answered 500 until ``cache/`` was
    deleted by hand."""
    import hashlib
    import json

    monkeypatch.setattr(robot_load, "_cache", [tmp_path])
    built = robot_load._built_in_child(SPEC, TEXT)
    (kept,) = tmp_path.iterdir()
    archive = kept / "model.bin"
    data = bytearray(archive.read_bytes())
    data[0:8] = b"\xff" * 7 + b"\x0f"  # a length no memory holds
    archive.write_bytes(bytes(data))
    hashes = json.loads((kept / robot_load._MANIFEST).read_text())
    hashes["model.bin"] = hashlib.sha256(bytes(data)).hexdigest()
    (kept / robot_load._MANIFEST).write_text(json.dumps(hashes))
    again = robot_load._built_in_child(SPEC, TEXT)
    assert "ignored and built again: MemoryError" in caplog.text
    _same_robot(built, again)
    monkeypatch.setattr(robot_load, "_CHILD", FAILING_CHILD)
    _same_robot(built, robot_load._built_in_child(SPEC, TEXT))  # the rebuilt copy is kept
