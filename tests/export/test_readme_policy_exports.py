"""The policy commands of docs/learning.md work as written: a policy trained as it says exports
as MCAP for its robot, checked, without --unchecked (issue 39: the UR5's, from the grid with its
goal at (0, -90, 90), was refused in every format for touching the table it stands on)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from studio.cli import main
from studio.kinematics import load_robot
from studio.learning import ArmGrid

DOCS = Path(__file__).resolve().parents[2] / "docs" / "learning.md"
TRAIN = {
    "panda": ["--task", "arm-reach", "--robot", "panda", "--planning", "zero"],
    "ur5": ["--robot", "ur5", "--goal-deg=0,-90,90"],
}
"""The documented training commands, as written (their budgets are the test's own)."""
BUDGET = ["--episodes", "60", "--experiments", "1", "--no-progress"]


def _documented(line: str) -> bool:
    text = DOCS.read_text()
    return line in text


def _metadata(path: Path) -> dict[str, str]:
    with path.open("rb") as f:
        for record in make_reader(f).iter_metadata():
            if record.name == "teach_studio":
                return dict(record.metadata)
    return {}


@pytest.mark.parametrize("robot", ["panda", "ur5"])
def test_the_documented_policy_exports_pass_the_checks(robot, tmp_path, capsys):
    assert _documented(f"studio train {' '.join(TRAIN[robot])}")
    assert _documented("studio export runs/<run>/policy.policy.npz --robot panda --format mcap")
    run = tmp_path / "run"
    assert main(["train", *TRAIN[robot], *BUDGET, "--out", str(run)]) == 0
    out = tmp_path / f"{robot}.mcap"
    argv = ["export", str(run / "policy.policy.npz"), "--robot", robot, "--format", "mcap"]
    assert main([*argv, "--out", str(out)]) == 0, capsys.readouterr().err
    meta = _metadata(out)
    assert meta["checked"] == "passed" and meta["findings"] == ""
    assert "contacts: none (self or table)" in meta["physics"]


def test_the_ur5_grid_keeps_off_the_table():
    """No state the grid starts from and no move it makes brings the UR5 within a centimetre of
    the table it stands on; its own start (the zero pose lies 7 mm above the table) is the
    nearest state clear of it."""
    free = ArmGrid(robot="ur5")
    grid = ArmGrid(robot="ur5", goal=tuple(free.bins_of_angles(np.radians([0, -90, 90]))))
    ur5 = load_robot("ur5")
    poses = grid.poses()
    mdp = grid.mdp()
    for s in mdp.start_states:
        assert not ur5.table_contacts(poses[s], 0.01), s
    starts = set(mdp.start_states.tolist())
    moved = mdp.next_state != np.arange(grid.n_states)[:, None]
    moves = [(s, a) for s, a in zip(*np.nonzero(moved), strict=True) if s in starts]
    rng = np.random.default_rng(0)
    for k in rng.choice(len(moves), size=min(300, len(moves)), replace=False):
        s, a = moves[k]
        t = mdp.next_state[s, a]
        assert t in starts or t == grid.goal_state  # never into the table
        for f in (0.25, 0.5, 0.75):
            q = poses[s] + f * (poses[t] - poses[s])
            assert not ur5.table_contacts(q, 0.005), (s, a, f)
    zero = grid.state_of_angles(np.zeros(3))
    assert ur5.table_contacts(poses[zero], 0.01)  # why it is no start
    start = grid.nearest_start(np.zeros(3))
    assert start in starts and start != zero
