"""Bad input to the exports: one sentence each, never a traceback, nothing already made lost."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from studio.cli import main
from studio.export import ExportError, export_urdf, find_source, portable_urdf
from studio.kinematics import robot_spec
from studio.learning import ArmGrid, DynaQConfig
from studio.learning.tabular._policy import save_policy
from studio.samples import SAMPLES_DIR


def _one_sentence(err: str, verb: str = "export") -> str:
    err = err.strip()
    assert err.startswith(f"studio {verb}: ") and err.endswith(".") and "\n" not in err, err
    assert "Traceback" not in err
    return err


def test_an_unknown_robot_is_one_sentence_and_writes_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["export", "sample-reach-1", "--robot", "nosuch", "--format", "csv"]) == 2
    err = _one_sentence(capsys.readouterr().err)
    assert "Unknown robot 'nosuch'" in err and "puma560" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("learnt", "asked"), [("puma560", "ur5"), ("panda", "puma560")])
def test_a_policy_for_another_robot_is_refused_in_one_sentence(tmp_path, capsys, learnt, asked):
    grid = ArmGrid(robot=learnt)
    policy = tmp_path / "arm.policy.npz"
    save_policy(policy, grid, np.zeros((grid.n_states, grid.n_actions)), DynaQConfig())
    out = tmp_path / "arm.csv"
    assert (
        main(["export", str(policy), "--robot", asked, "--format", "csv", "--out", str(out)]) == 2
    )
    err = _one_sentence(capsys.readouterr().err)
    learnt_title, asked_title = robot_spec(learnt).title, robot_spec(asked).title
    assert (
        f"was learnt on the {learnt_title} and drives only that robot, not the {asked_title}" in err
    )
    assert f"--robot {learnt}" in err
    assert not out.exists()


def test_an_unknown_source_name_is_one_sentence(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["export", "no-such-take", "--format", "mcap"]) == 2
    err = _one_sentence(capsys.readouterr().err)
    assert "'no-such-take'" in err and "sample-reach-1" in err


def test_names_resolve_in_the_data_folder_before_the_samples(tmp_path):
    assert find_source("sample-reach-1") == SAMPLES_DIR / "sample-reach-1.demo.json"
    assert find_source("sample-reach-1.tape.csv") == SAMPLES_DIR / "sample-reach-1.tape.csv"
    mine = tmp_path / "recordings" / "sample-reach-1.demo.json"
    mine.parent.mkdir()
    mine.write_text("{}")
    assert find_source("sample-reach-1", tmp_path) == mine
    run = tmp_path / "runs" / "r1" / "policy.policy.npz"
    run.parent.mkdir(parents=True)
    run.write_bytes(b"")
    assert find_source("r1", tmp_path) == run


def test_a_urdf_without_meshes_is_one_sentence(tmp_path):
    bare = '<robot name="bare"><link name="base"/></robot>'
    with pytest.raises(ExportError, match="names no mesh") as err:
        portable_urdf(bare, tmp_path, tmp_path / "out")
    assert str(err.value).count(".") <= 2 and "\n" not in str(err.value)
    missing = '<robot name="r"><link name="a"><visual><geometry><mesh filename="package://x/robots/gone.stl"/></geometry></visual></link></robot>'
    with pytest.raises(
        ExportError, match=r"names the mesh package://x/robots/gone.stl, which is not installed"
    ):
        portable_urdf(missing, tmp_path, tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_export_urdf_never_replaces_a_folder_with_files(tmp_path, capsys):
    kept = tmp_path / "robot" / "notes.txt"
    kept.parent.mkdir()
    kept.write_text("mine")
    assert main(["export-urdf", "--robot", "so100", "--out", str(kept.parent)]) == 2
    err = _one_sentence(capsys.readouterr().err, "export-urdf")
    assert "not an empty folder" in err
    assert kept.read_text() == "mine" and sorted(kept.parent.iterdir()) == [kept]
    assert main(["export-urdf", "--robot", "nosuch", "--out", str(tmp_path / "x")]) == 2
    assert "Unknown robot 'nosuch'" in _one_sentence(capsys.readouterr().err, "export-urdf")
    assert not (tmp_path / "x").exists()
    with pytest.raises(ExportError):
        export_urdf("so100", kept)  # a file


def test_a_lerobot_export_never_replaces_a_folder_with_files(tmp_path, capsys):
    kept = tmp_path / "data" / "old.parquet"
    kept.parent.mkdir()
    kept.write_bytes(b"old")
    argv = ["export", "sample-reach-2", "--format", "lerobot", "--out", str(kept.parent)]
    assert main(argv) == 2
    assert "not an empty folder" in _one_sentence(capsys.readouterr().err)
    assert kept.read_bytes() == b"old" and sorted(Path(kept.parent).iterdir()) == [kept]
