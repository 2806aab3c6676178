"""studio export-urdf --robot: a folder that loads elsewhere, with its meshes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from studio.cli import main
from studio.kinematics import Puma560, load_robot


@pytest.mark.parametrize("robot", ["so100", "panda"])
def test_a_robots_folder_loads_elsewhere_with_its_meshes(robot, tmp_path, capsys):
    out = tmp_path / robot
    assert main(["export-urdf", "--robot", robot, "--out", str(out)]) == 0
    urdf = out / f"{robot}.urdf"
    text = urdf.read_text()
    assert "package://" not in text and 'filename="meshes/' in text
    moved = tmp_path / "elsewhere"
    out.rename(moved)  # relative paths: the folder works wherever it goes
    model, collision, visual = pin.buildModelsFromUrdf(str(moved / urdf.name), str(moved))
    assert visual.ngeoms > 0 and collision.ngeoms > 0
    for obj in visual.geometryObjects:
        assert str(obj.meshPath).startswith(str(moved)), obj.meshPath
    arm = load_robot(robot)
    names = [model.names[i] for i in range(1, model.njoints)]
    assert list(arm.joint_names) == names[: arm.nq]  # the exported trajectories' names


def test_the_puma560_folder_carries_its_meshes_where_the_scene_draws_them(tmp_path):
    out = tmp_path / "puma"
    assert main(["export-urdf", "--robot", "puma560", "--out", str(out)]) == 0
    model, collision, visual = pin.buildModelsFromUrdf(str(out / "puma560.urdf"), str(out))
    for geometry in (visual, collision):
        assert [Path(o.meshPath).name for o in geometry.geometryObjects] == [
            f"link{j}.stl" for j in range(7)
        ]
    # real limits: the joints' published speed and torque limits, none left at 0
    assert np.all(model.velocityLimit > 0) and np.all(model.effortLimit > 0)
    data, gdata = model.createData(), pin.GeometryData(visual)
    puma = Puma560()
    q = np.random.default_rng(0).uniform(puma.lower, puma.upper)
    pin.updateGeometryPlacements(model, data, visual, gdata, q)
    frames = puma.joint_frames(q)
    for j in range(7):
        np.testing.assert_allclose(gdata.oMg[j].homogeneous, frames[j], atol=1e-9)


def test_export_urdf_without_robot_still_writes_one_file(tmp_path):
    out = tmp_path / "puma560.urdf"
    assert main(["export-urdf", "--out", str(out)]) == 0
    assert out.read_text() == Puma560().urdf()
