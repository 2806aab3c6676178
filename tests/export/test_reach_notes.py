"""A hand beyond the robot's reach is stated in the export, not only on the page.

Cartesian retargeting draws a hand target beyond the robot's reach back into it (the page says so
live). The operator's reach maps into the robot's workspace, so a human arm's target is never
beyond it; these tests widen the workspace past the reach to see the guard at work. The motion the robot makes there is its own and safe, so the export is not refused, but it
is not the hand's: the export says how many frames, the first one and how far, in the MCAP
metadata, the LeRobot ``info.json`` and the CLI's output. A checked CSV keeps no comment lines.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from mcap.reader import make_reader

from studio.capture import human_angles, read_any_recording
from studio.cli import main
from studio.export import recording_motion
from studio.kinematics import RetargetConfig, load_robot, retarget_path
from studio.kinematics._workspace import Workspace
from studio.samples import SAMPLES_DIR

RECORDING = SAMPLES_DIR / "sample-reach-1.tape.csv"
BEYOND = "the hand went beyond the Universal Robots UR5's reach in"


@pytest.fixture
def wide_workspace(monkeypatch):
    """The operator's reach mapped twice as far as the robot's workspace, beyond its reach."""
    into = Workspace.into

    def wider(self, reach):
        return self.centre + 2.0 * (into(self, reach) - self.centre)

    monkeypatch.setattr(Workspace, "into", wider)


def test_the_retargeted_path_says_where_the_target_was_drawn_in(wide_workspace):
    motion = recording_motion(RECORDING, "ur5")
    assert len(motion.notes) == 1 and motion.notes[0].startswith(BEYOND)
    rec = read_any_recording(RECORDING)
    path = retarget_path(load_robot("ur5"), human_angles(rec, slice(None)))
    beyond = path.pulled_in > RetargetConfig().reach_tolerance
    assert beyond.any() and np.all(path.pulled_in >= 0)
    assert f"in {beyond.sum()} of {len(rec)} frames" in motion.notes[0]
    assert f"first at frame {np.flatnonzero(beyond)[0]}," in motion.notes[0]
    puma = retarget_path(load_robot("puma560"), human_angles(rec, slice(None)))
    assert not puma.pulled_in.any(), "joint mode has no target to draw in"
    assert recording_motion(RECORDING, "puma560").notes == ()


@pytest.mark.parametrize("fmt", ["csv", "mcap", "lerobot"])
def test_a_checked_export_states_the_hand_beyond_reach(fmt, tmp_path, capsys, wide_workspace):
    out = tmp_path / f"demo.{fmt}"
    args = ["export", "sample-reach-1", "--robot", "ur5", "--format", fmt, "--out", str(out)]
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "passed the safety checks" in printed
    assert f"note: {BEYOND}" in printed
    if fmt == "csv":
        # issue 39: every CSV's comment lines say what it is, the notes among them
        comments = [line for line in out.read_text().splitlines() if line.startswith("# ")]
        assert f"# note: {BEYOND}" in "\n".join(comments)
        assert "# safety checks: passed" in "\n".join(comments)
        assert any(line.startswith("# physics (MuJoCo, ur5") for line in comments)
    elif fmt == "mcap":
        with out.open("rb") as f:
            meta = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
        assert meta["teach_studio"]["checked"] == "passed"
        assert meta["teach_studio"]["notes"].startswith(BEYOND)
    else:
        info = json.loads((out / "meta/info.json").read_text())
        assert info["teach_studio"]["checked"] is True
        assert info["teach_studio"]["notes"][0].startswith(BEYOND)


def test_the_puma560s_export_has_no_note(tmp_path, capsys):
    out = tmp_path / "demo.mcap"
    assert main(["export", "sample-reach-1", "--format", "mcap", "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert "reach" not in said and "IK branch" not in said  # joint to joint: no retargeting
    with out.open("rb") as f:
        meta = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    # the one note is the timing's: at the person's pace, where it had to slow down
    assert meta["teach_studio"]["notes"].startswith("at the source's pace: 2.49 s")
    assert "\n" not in meta["teach_studio"]["notes"]


def test_the_frames_the_robot_turns_between_ik_branches_are_stated():
    # The Z1 cannot turn its tool as far as the hand turns in sample 2: its tool is off the
    # hand's target there, and the export says where and how often.
    recording = SAMPLES_DIR / "sample-reach-2.tape.csv"
    motion = recording_motion(recording, "z1")
    rec = read_any_recording(recording)
    path = retarget_path(load_robot("z1"), human_angles(rec, slice(None)))
    off = np.flatnonzero(~path.reached & ~path.out_of_reach)
    assert len(off) > 0
    [note] = [n for n in motion.notes if "off the hand's target" in n]
    assert note.startswith("the Unitree Z1's tool is more than 1 cm or 5 deg off")
    assert f"in {len(off)} of {len(rec)} frames (first at frame {off[0]}," in note
    # the UR5 follows sample 1 throughout: no such note
    assert not [n for n in recording_motion(RECORDING, "ur5").notes if "off the hand's" in n]
