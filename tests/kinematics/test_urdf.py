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
from studio.kinematics import LIMIT_MARGIN_RAD, Puma560, load_robot
from tests.conftest import require

ROBOT = Puma560()
TEXT = ROBOT.urdf()
RNG_SEED = 20261122
SAMPLES = 50


def random_q(n: int = SAMPLES) -> np.ndarray:
    """Angles inside the limits, plus the limits themselves."""
    rng = np.random.default_rng(RNG_SEED)
    return np.vstack([rng.uniform(ROBOT.lower, ROBOT.upper, size=(n, 6)), ROBOT.lower, ROBOT.upper])


#: The published speed (rad/s) and torque (N m) limits the URDF carries (see ``_dh``).
SPEEDS = (1.92, 1.51, 2.40, 5.34, 5.09, 5.74)
TORQUES = (97.6, 186.4, 89.4, 24.2, 20.1, 21.3)


def test_urdf_is_well_formed_xml_with_the_joint_limits() -> None:
    root = ET.fromstring(TEXT)
    assert root.tag == "robot"
    joints = [j for j in root.iter("joint") if j.get("type") == "revolute"]
    assert [j.get("name") for j in joints] == [f"joint{i}" for i in range(1, 7)]
    for joint, lower, upper, speed, torque in zip(
        joints, ROBOT.lower, ROBOT.upper, SPEEDS, TORQUES, strict=True
    ):
        limit = joint.find("limit")
        assert limit is not None
        assert float(limit.get("lower")) == lower
        assert float(limit.get("upper")) == upper
        assert float(limit.get("velocity")) == speed and float(limit.get("effort")) == torque
    assert len(list(root.iter("visual"))) == len(ROBOT.visuals())
    assert len(list(root.iter("collision"))) == len(ROBOT.visuals())  # the same solids


def test_the_registry_loads_the_puma560_from_its_urdf_with_standard_dh_kinematics() -> None:
    """``load_robot("puma560")`` is built from the URDF made of the DH table, like every arm:
    Corke's standard-DH tool positions at qz and qn, the DH model's pose everywhere else."""
    arm = load_robot("puma560")
    assert arm.urdf_text.count("<collision") == 7 and "package://rtbdata/" in arm.urdf_text
    np.testing.assert_allclose(arm.forward(ROBOT.qz)[:3, 3], (0.4521, -0.15005, 1.1036), atol=5e-5)
    np.testing.assert_allclose(arm.forward(ROBOT.qn)[:3, 3], (0.5963, -0.1501, 0.6575), atol=5e-5)
    for q in random_q(20):
        np.testing.assert_allclose(arm.forward(q), ROBOT.forward(q), atol=1e-12)
    # Corke's limits are the URDF's hard ones; the usable ones keep the margin inside them.
    np.testing.assert_array_equal(arm.hard_lower, ROBOT.lower)
    np.testing.assert_array_equal(arm.hard_upper, ROBOT.upper)
    np.testing.assert_allclose(arm.lower, ROBOT.lower + LIMIT_MARGIN_RAD)
    np.testing.assert_allclose(arm.upper, ROBOT.upper - LIMIT_MARGIN_RAD)
    np.testing.assert_array_equal(arm.velocity, SPEEDS)
    np.testing.assert_array_equal(arm.model.effortLimit, TORQUES)


def test_the_puma560_checks_self_collision_and_the_floor_on_its_link_meshes() -> None:
    arm = load_robot("puma560")
    assert arm.checks_collisions and arm.collision_model.ngeoms == 7
    for q in (ROBOT.qz, ROBOT.qr, ROBOT.qn, ROBOT.qs):
        assert arm.contacts(q) == [], q
    # the wrist's links 4 and 6 hug its centre 2.5 mm apart at every pose: not a contact, even
    # within the exports' 5 mm margin
    assert arm.self_collisions(ROBOT.qz, 0.005) == []
    # the forearm folded back onto the upper arm (joint 3 near its limit)
    folded = np.radians([-5.0, 86.0, 117.0, -76.0, 14.0, -95.0])
    assert ("link2", "link4") in {(c.link_a, c.link_b) for c in arm.self_collisions(folded)}
    # the arm bent down through the floor it stands on
    down = np.radians([44.0, -51.0, -124.0, -257.0, 63.0, 220.0])
    assert "link6" in {c.link_a for c in arm.table_contacts(down)}


def dimensions(shape: str, sizes: tuple[float, ...]) -> tuple[str, tuple[float, ...]]:
    """A solid as (kind, full sizes): cylinder (r, length), box (x, y, z), sphere (r,)."""
    return shape, tuple(float(v) for v in sizes)


def test_pinocchio_loads_it_back_with_the_same_kinematics() -> None:
    model = pin.buildModelFromXML(TEXT)
    data = model.createData()
    tool = model.getFrameId("tool")
    assert model.nq == 6
    assert list(model.names)[1:] == [f"joint{i}" for i in range(1, 7)]
    np.testing.assert_array_equal(model.lowerPositionLimit, ROBOT.lower)
    np.testing.assert_array_equal(model.upperPositionLimit, ROBOT.upper)
    for q in random_q():
        pin.framesForwardKinematics(model, data, q)
        np.testing.assert_allclose(data.oMf[tool].homogeneous, ROBOT.forward(q), atol=1e-12)
        # Every joint, not only the tool: joint i turns about z of DH frame i-1.
        pin.forwardKinematics(ROBOT.model, ROBOT.data, q)
        for i in range(1, 7):
            np.testing.assert_allclose(
                data.oMi[i].homogeneous, ROBOT.data.oMi[i].homogeneous, atol=1e-12
            )


def test_pinocchio_loads_back_the_same_visuals() -> None:
    # Pinocchio renames visuals after their link, so they are matched in file order (grouped
    # by joint, as visuals() lists them) by kind, size, colour and pose.
    model = pin.buildModelFromXML(TEXT)
    geometry = pin.buildGeomFromUrdfString(model, TEXT, pin.GeometryType.VISUAL)
    visuals = ROBOT.visuals()
    assert [v.joint for v in visuals] == sorted(v.joint for v in visuals)
    assert geometry.ngeoms == len(visuals)
    for obj, visual in zip(geometry.geometryObjects, visuals, strict=True):
        solid = obj.geometry
        kind = type(solid).__name__.lower()
        if kind == "cylinder":
            loaded = dimensions(kind, (solid.radius, 2 * solid.halfLength))
        elif kind == "box":
            loaded = dimensions(kind, tuple(2 * solid.halfSide))
        else:
            loaded = dimensions(kind, (solid.radius,))
        expected = dimensions(visual.shape, visual.dimensions)
        assert loaded[0] == expected[0], visual.name
        np.testing.assert_allclose(loaded[1], expected[1], rtol=1e-12, err_msg=visual.name)
        assert obj.parentJoint == visual.joint  # DH frame i moves with joint i (0: the base)
        np.testing.assert_allclose(obj.meshColor, (*visual.rgb, 1.0), atol=1e-7)  # float32
    data, geometry_data = model.createData(), geometry.createData()
    for q in random_q(10):
        pin.forwardKinematics(model, data, q)
        pin.updateGeometryPlacements(model, data, geometry, geometry_data)
        placed = np.stack([oMg.homogeneous for oMg in geometry_data.oMg])
        np.testing.assert_allclose(placed, ROBOT.visual_poses(q), atol=1e-12)


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
    # ... and is the same solid, in the same colour.
    for visual in ROBOT.visuals():
        (loaded,) = [
            v for link in urdf.link_map.values() for v in link.visuals if v.name == visual.name
        ]
        geometry = loaded.geometry
        if visual.shape == "cylinder":
            sizes = (geometry.cylinder.radius, geometry.cylinder.length)
        elif visual.shape == "box":
            sizes = tuple(geometry.box.size)
        else:
            sizes = (geometry.sphere.radius,)
        assert getattr(geometry, visual.shape) is not None, visual.name
        assert sizes == visual.dimensions, visual.name
        assert tuple(loaded.material.color.rgba) == (*visual.rgb, 1.0), visual.name


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


def _kinematics_imports() -> dict[str, set[str]]:
    """Module -> the package modules it imports anywhere (functions and TYPE_CHECKING included)."""
    import ast

    import studio.kinematics

    folder = Path(studio.kinematics.__file__).parent
    graph: dict[str, set[str]] = {}
    for path in folder.glob("_*.py"):
        names = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module:
                names.add(node.module)
        graph[path.stem] = names
    return graph


def test_the_kinematics_modules_import_one_way() -> None:
    """Issue 9: ``_puma`` imported the URDF writer inside a function while the writer imported
    ``_puma``; the description and its URDF (``_dh``) import neither the model nor the registry."""
    graph = _kinematics_imports()
    assert not {"_puma", "_robots"} & graph["_dh"] and "_dh" in graph["_puma"]
    done: set[str] = set()

    def visit(module: str, stack: tuple[str, ...]) -> None:
        assert module not in stack, f"import cycle: {' -> '.join((*stack, module))}"
        if module in done:
            return
        for imported in graph.get(module, ()):
            visit(imported, (*stack, module))
        done.add(module)

    for module in graph:
        visit(module, ())
