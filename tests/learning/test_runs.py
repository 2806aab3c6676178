"""The run folder, the curve statistics, the one curves.csv layout and the curve figure."""

from __future__ import annotations

import csv
import errno
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import studio.learning.runs._record as runs_module
from studio.learning import (
    ArmGrid,
    ConfigError,
    DynaQConfig,
    LearningError,
    LiveProgress,
    RunFolder,
    RunRecord,
    curve_statistics,
    curves_csv,
    downsample_curve,
    find_runs,
    load_policy,
)
from studio.learning.runs._curves import CURVE_COLUMNS, curve_plot
from tests.conftest import interruptible, signal_masks

REPO = Path(__file__).resolve().parents[2]


def tiny_record(**changes: object) -> RunRecord:
    values: dict = {"experiments": 2, "episodes": 5, "seed": 1, "origin": "cli"}
    values.update(changes)
    grid = ArmGrid(joints=2, bins=5, goal=(2, 2))
    return RunRecord.for_arm_grid(
        grid,
        DynaQConfig(planning="zero"),
        values.pop("experiments"),
        values.pop("episodes"),
        **values,
    )


@st.composite
def partial_steps(draw: st.DrawFn) -> np.ndarray:
    """Steps of a run whose experiments each finished a prefix of the episodes (-1 after)."""
    experiments = draw(st.integers(1, 6))
    episodes = draw(st.integers(1, 30))
    steps = np.array(
        draw(
            st.lists(
                st.lists(st.integers(1, 5000), min_size=episodes, max_size=episodes),
                min_size=experiments,
                max_size=experiments,
            )
        ),
        dtype=np.int64,
    )
    for e in range(experiments):
        steps[e, draw(st.integers(0, episodes)) :] = -1
    return steps


@settings(max_examples=60, deadline=None)
@given(partial_steps(), st.integers(0, 35))
def test_curve_statistics_are_numpy_statistics_over_the_experiments_that_finished(steps, start):
    curve = curve_statistics(steps, start)
    done = (steps >= 0).sum(axis=0)
    last = int(np.flatnonzero(done)[-1]) + 1 if done.any() else 0
    first = min(start, last)
    assert curve["episodes"] == list(range(first + 1, last + 1))
    for i, k in enumerate(range(first, last)):
        values = steps[steps[:, k] >= 0, k].astype(float)
        assert curve["count"][i] == values.size
        assert curve["mean"][i] == pytest.approx(values.mean(), abs=1e-3)
        assert curve["std"][i] == pytest.approx(values.std(), abs=1e-3)
        assert curve["min"][i] == values.min() and curve["max"][i] == values.max()
        for key, q in (("p10", 10), ("median", 50), ("p90", 90)):
            assert curve[key][i] == pytest.approx(np.percentile(values, q), abs=1e-3)


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 5000), st.integers(10, 700))
def test_downsampling_bounds_the_points_and_keeps_the_extremes(episodes, points):
    rng = np.random.default_rng(episodes)
    steps = rng.integers(1, 1000, (3, episodes))
    curve = curve_statistics(steps)
    small = downsample_curve(curve, points)
    assert len(small["episodes"]) <= points
    assert min(small["min"]) == min(curve["min"]) and max(small["max"]) == max(curve["max"])
    assert small["episodes"][0] >= 1 and small["episodes"][-1] <= episodes
    assert np.all(np.diff(small["episodes"]) > 0)
    weights = np.diff(np.append(np.arange(0, episodes, -(-episodes // points)), episodes))
    if episodes > points:  # bucket means average back to the overall mean
        assert np.average(small["mean"], weights=weights) == pytest.approx(
            np.mean(curve["mean"]), rel=1e-3
        )
    else:
        assert small == curve


def test_the_figure_of_a_25000_episode_run_draws_at_most_600_points_per_line():
    rng = np.random.default_rng(0)
    steps = rng.integers(1, 3000, (4, 25_000))
    steps[0, 20_000:] = -1  # one experiment stopped early: the tail is drawn dotted
    fig = curve_plot([("long", curve_statistics(steps))])
    lines = fig.axes[0].lines
    assert len(lines) == 2 and lines[1].get_linestyle() == ":"
    for line in lines:
        assert 0 < np.count_nonzero(np.isfinite(line.get_ydata())) <= 600
    solid, dotted = (np.isfinite(line.get_ydata()) for line in lines)
    assert solid.any() and dotted.any() and (solid | dotted).all()


def test_curves_csv_has_the_one_layout_and_round_trips():
    steps = np.array([[3, 5, -1], [4, 7, 2]])
    curve = curve_statistics(steps)
    rows = list(csv.reader(io.StringIO(curves_csv(curve))))
    assert tuple(rows[0]) == CURVE_COLUMNS
    assert [int(r[0]) for r in rows[1:]] == [1, 2, 3]
    assert [float(r[1]) for r in rows[1:]] == curve["mean"]
    assert [int(r[-1]) for r in rows[1:]] == [2, 2, 1]
    named = list(csv.reader(io.StringIO(curves_csv(curve, configuration="SV-ZPL"))))
    assert named[0] == ["configuration", *CURVE_COLUMNS]
    assert [r[1:] for r in named[1:]] == rows[1:] and {r[0] for r in named[1:]} == {"SV-ZPL"}


def test_a_run_folder_trains_checkpoints_and_loads_back(tmp_path):
    record = tiny_record(name="tiny")
    run = RunFolder.create(tmp_path, record, name="tiny-run")
    assert run.path == tmp_path / "tiny-run" and run.status == "queued"
    assert [p.name for p in tmp_path.iterdir()] == ["tiny-run"]  # no temporary left
    result = run.train(workers=1)
    assert result is not None and run.status == "done"
    again = RunFolder.load(run.path)
    assert again.record == record and again.status == "done"
    np.testing.assert_array_equal(again.steps(), result.steps)
    saved = again.curve()
    assert {k: saved[k] for k in curve_statistics(result.steps)} == curve_statistics(result.steps)
    assert again.cpu_seconds == pytest.approx(float(result.cpu_seconds.sum()))
    policy = load_policy(again.policy_path)
    assert policy.grid == record.arm_grid() and policy.experiments == 2
    assert find_runs(tmp_path) == [run.path]


def test_a_stop_before_training_starts_trains_nothing(tmp_path):
    run = RunFolder.create(tmp_path, tiny_record(episodes=500))
    live = LiveProgress(2, 500)
    live.stop()
    assert run.train(live, workers=1) is None
    assert run.status == "stopped" and run.error == "Stopped before it started."
    assert not run.has_policy and int((RunFolder.load(run.path).steps() >= 0).sum()) == 0


def test_a_full_disk_leaves_no_half_made_run_folder(tmp_path, monkeypatch):
    def full(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Path, "write_text", full)
    with pytest.raises(LearningError) as err:
        RunFolder.create(tmp_path / "runs", tiny_record())
    message = str(err.value)
    assert "is full" in message and str(tmp_path / "runs") in message and "\n" not in message
    assert list((tmp_path / "runs").iterdir()) == []


def test_older_run_folders_still_load(tmp_path):
    # studio train before the run record: no status, no format
    old_cli = tmp_path / "old-cli"
    old_cli.mkdir()
    (old_cli / "config.json").write_text(
        json.dumps(
            {
                "grid": {
                    "joints": 3,
                    "bins": 11,
                    "low_deg": -180,
                    "high_deg": 180,
                    "goal": [5, 6, 2],
                },
                "config": DynaQConfig().to_dict(),
                "experiments": 1,
                "episodes": 2,
                "seed": 0,
                "demonstrations": [],
            }
        )
    )
    (old_cli / "steps.csv").write_text("# steps per episode; one row per experiment\n9,4\n")
    run = RunFolder.load(old_cli)
    assert run.record.origin == "cli" and run.status == "done"
    assert run.record.arm_grid() == ArmGrid()
    # the page's layout before the run record: the request held experiments, episodes, name
    old_page = tmp_path / "old-page"
    old_page.mkdir()
    request = {"name": "mine", "experiments": 1, "episodes": 3, "seed": 4, "planning": "zero"}
    (old_page / "config.json").write_text(
        json.dumps(
            {"request": request, "grid": ArmGrid().to_dict(), "config": {"planning": "zero"}}
        )
    )
    (old_page / "status.json").write_text(json.dumps({"status": "running"}))
    run = RunFolder.load(old_page)
    assert (run.record.origin, run.record.name, run.record.seed) == ("page", "mine", 4)
    assert run.status == "stopped" and "stopped while this run was training" in run.error
    assert find_runs(tmp_path) == [old_cli, old_page]


def test_a_newer_or_foreign_config_is_refused_with_one_sentence(tmp_path):
    for data, words in (
        ({"format": "teach-studio-run", "version": 99}, "newer"),
        ({"format": "something-else"}, "not a teach-studio-run"),
        ([1, 2], "no JSON object"),
        ({"format": "teach-studio-run", "version": 1}, "lacks task, config"),
    ):
        (tmp_path / "config.json").write_text(json.dumps(data))
        with pytest.raises(LearningError, match=words):
            RunFolder.load(tmp_path)


def test_every_bad_run_setting_is_reported_at_once():
    with pytest.raises(ConfigError) as err:
        RunRecord.for_arm_grid(ArmGrid(), DynaQConfig(), 0, 0, seed=-1, name=" ", origin="web")
    assert set(err.value.by_field) == {"experiments", "episodes", "seed", "name", "origin"}
    assert len(err.value.problems) == 5


def test_groups_of_runs_are_found_one_level_down(tmp_path):
    RunFolder.create(tmp_path, tiny_record(), name="single")
    RunFolder.create(tmp_path / "paper", tiny_record(group="paper"), name="SV-ZPL")
    (tmp_path / "empty-folder").mkdir()
    (tmp_path / ".hidden-tmp").mkdir()
    found = [p.relative_to(tmp_path).as_posix() for p in find_runs(tmp_path)]
    assert found == ["paper/SV-ZPL", "single"]


def _studio(*args: str, cwd: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.Popen(
        [sys.executable, "-m", "studio", *args],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=interruptible,
    )


def _wait_for_checkpoints(path: Path, proc: subprocess.Popen, count: int) -> list[int]:
    """Episodes done in each new checkpoint of ``steps.csv``, until ``count`` differ."""
    seen: list[int] = []
    deadline = time.monotonic() + 120
    while len(seen) < count and time.monotonic() < deadline and proc.poll() is None:
        try:
            steps = np.loadtxt(path / "steps.csv", delimiter=",", dtype=np.int64, ndmin=2)
        except (OSError, ValueError):
            steps = None
        if steps is not None:
            done = int((steps >= 0).sum())
            if done and (not seen or done != seen[-1]):
                seen.append(done)
        time.sleep(0.05)  # polling the file for the event, not waiting a fixed time
    assert proc.poll() is None, proc.communicate()
    assert len(seen) >= count, f"saw checkpoints {seen}"
    return seen


# Long enough (about a minute even on a quiet machine) that the signal always lands mid-training:
# with 100 planning updates the 100,000 episodes could end in the ~2 s before the kill.
LONG_RUN = [
    "--planning", "full", "--planning-steps", "10000",
    "--experiments", "1", "--episodes", "100000", "--no-progress",
]  # fmt: skip
"""A run the tests stop mid-way: minutes of CPU. (At 2,000 planning steps it ended in 24 s, and on
a busy machine it could end before a test saw its first checkpoint, so no signal stopped it.)"""


def test_kill_9_mid_training_keeps_the_curve_and_the_policy_to_the_last_checkpoint(tmp_path):
    proc = _studio("train", "--out", "runs/killed", *LONG_RUN, cwd=tmp_path)
    folder = tmp_path / "runs" / "killed"
    try:
        seen = _wait_for_checkpoints(folder, proc, 2)  # checkpoints keep coming while it trains
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    run = RunFolder.load(folder)
    assert run.status == "stopped" and run.interrupted
    assert "stopped while this run was training" in run.error
    done = int((run.steps() >= 0).sum())
    assert seen[-1] <= done < 100_000
    assert run.has_policy  # checkpointed with the steps: a crash loses seconds, not the learning
    policy = load_policy(run.policy_path)
    assert len(policy.mean_steps) == 100_000
    assert np.isfinite(policy.mean_steps[: seen[0]]).all()  # learnt up to a checkpoint at least
    assert np.abs(policy.q).max() > 0  # the table the kernel had filled, not a blank one
    run.recover()
    assert RunFolder.load(folder).status == "stopped"
    assert json.loads((folder / "status.json").read_text())["status"] == "stopped"
    with (folder / "curves.csv").open() as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == len(run.curve()["episodes"])
    assert rows[0]["wall_seconds"] and rows[0]["cpu_seconds"]  # the checkpoint's times kept


def test_ctrl_c_mid_training_keeps_the_curve_and_writes_a_policy(tmp_path):
    proc = _studio("train", "--out", "runs/interrupted", *LONG_RUN, cwd=tmp_path)
    folder = tmp_path / "runs" / "interrupted"
    try:
        _wait_for_checkpoints(folder, proc, 1)
        masks = signal_masks(proc.pid)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, f"{err}\nits signals: {masks}; its output: {out[-2000:]}"
    assert "Stopped:" in out and "policy" in out
    run = RunFolder.load(folder)
    assert run.status == "stopped" and not run.interrupted and run.has_policy
    done = int((run.steps() >= 0).sum())
    assert 0 < done < 100_000
    assert len(load_policy(run.policy_path).mean_steps) == 100_000


def test_run_records_stay_json_and_self_describing(tmp_path):
    record = tiny_record(group="sweep-7", origin="sweep", name="trial 3")
    run = RunFolder.create(tmp_path, record)
    data = json.loads((run.path / "config.json").read_text())
    assert data["format"] == "teach-studio-run" and data["version"] == 1
    assert data["task"] == {"kind": "arm-grid", **ArmGrid(joints=2, bins=5, goal=(2, 2)).to_dict()}
    assert data["config"] == DynaQConfig(planning="zero").to_dict()
    assert (data["origin"], data["group"], data["name"]) == ("sweep", "sweep-7", "trial 3")
    assert RunRecord.from_dict(data) == record
    assert data["format"] == runs_module.RUN_FORMAT
