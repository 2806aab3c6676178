"""The exported URDF loads back (Pinocchio, yourdfpy) with the same kinematics and visuals."""

from __future__ import annotations

import io
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from studio.cli import main
from studio.kinematics import Puma560
from tests.conftest import require

ROBOT = Puma560()
TEXT = ROBOT.urdf()
RNG_SEED = 20261122
SAMPLES = 50


def random_q(n: int = SAMPLES) -> np.ndarray:
    """Angles inside the limits, plus the limits themselves."""
    rng = np.random.default_rng(RNG_SEED)
    return np.vstack([rng.uniform(ROBOT.lower, ROBOT.upper, size=(n, 6)), ROBOT.lower, ROBOT.upper])


def test_urdf_is_well_formed_xml_with_the_joint_limits() -> None:
    root = ET.fromstring(TEXT)
    assert root.tag == "robot"
    joints = [j for j in root.iter("joint") if j.get("type") == "revolute"]
    assert [j.get("name") for j in joints] == [f"joint{i}" for i in range(1, 7)]
    for joint, lower, upper in zip(joints, ROBOT.lower, ROBOT.upper, strict=True):
        limit = joint.find("limit")
        assert limit is not None
        assert float(limit.get("lower")) == lower
        assert float(limit.get("upper")) == upper
    assert len(list(root.iter("visual"))) == len(ROBOT.visuals())


def test_pinocchio_loads_it_back_with_the_same_kinematics() -> None:
    model = pin.buildModelFromXML(TEXT)
    data = model.createData()
    tool = model.getFrameId("tool")
    assert model.nq == 6
    np.testing.assert_array_equal(model.lowerPositionLimit, ROBOT.lower)
    np.testing.assert_array_equal(model.upperPositionLimit, ROBOT.upper)
    for q in random_q():
        pin.framesForwardKinematics(model, data, q)
        np.testing.assert_allclose(data.oMf[tool].homogeneous, ROBOT.forward(q), atol=1e-12)


def test_yourdfpy_loads_it_back_with_the_same_kinematics_and_visuals() -> None:
    try:
        import yourdfpy
    except ImportError:
        yourdfpy = None
    require(yourdfpy is not None, "yourdfpy is not installed (pip install -e '.[test]')")
    urdf = yourdfpy.URDF.load(io.StringIO(TEXT))
    assert urdf.validate()
    assert urdf.actuated_joint_names == [f"joint{i}" for i in range(1, 7)]
    for name, lower, upper in zip(urdf.actuated_joint_names, ROBOT.lower, ROBOT.upper, strict=True):
        limit = urdf.joint_map[name].limit
        assert math.isclose(limit.lower, lower) and math.isclose(limit.upper, upper)
    names = [v.name for v in ROBOT.visuals()]
    for q in random_q(10):
        urdf.update_cfg(q)
        np.testing.assert_allclose(
            urdf.get_transform("tool", "base_link"), ROBOT.forward(q), atol=1e-12
        )
        # Each URDF visual sits where visual_poses() puts the scene's solid.
        expected = dict(zip(names, ROBOT.visual_poses(q), strict=True))
        seen = 0
        for link_name, link in urdf.link_map.items():
            oMlink = urdf.get_transform(link_name, "base_link")
            for visual in link.visuals:
                np.testing.assert_allclose(
                    oMlink @ visual.origin, expected[visual.name], atol=1e-12
                )
                seen += 1
        assert seen == len(names)


def test_export_urdf_writes_the_file(tmp_path: Path) -> None:
    out = tmp_path / "puma560.urdf"
    assert main(["export-urdf", "--out", str(out)]) == 0
    assert out.read_text(encoding="utf-8") == TEXT


def test_export_urdf_prints_to_stdout(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["export-urdf"]) == 0
    assert capsys.readouterr().out == TEXT


def test_export_urdf_to_an_unwritable_place_is_one_clear_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for out in (tmp_path / "missing" / "puma.urdf", tmp_path):
        assert main(["export-urdf", "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("studio export-urdf: ") and err.endswith(".")
        assert "\n" not in err
