"""Wall and CPU time per episode: stamped where the run's thread polls the learner, saved as two
more ``curves.csv`` columns, served with the curve; older files without them still load."""

from __future__ import annotations

import csv
import io
import shutil
import threading

import numpy as np
import pytest

from studio.learning import (
    ArmGrid,
    DynaQConfig,
    LiveCurve,
    LiveProgress,
    RunFolder,
    RunRecord,
    curve_statistics,
    curves_csv,
)
from studio.learning.runs import _train as _run_train
from studio.learning.runs._curves import (
    CURVE_COLUMNS,
    TIME_COLUMNS,
    downsample_curve,
    episode_seconds,
    read_curve_times,
)
from studio.learning.runs._train import EpisodeClock
from tests.learning.test_runs import tiny_record


def busy(seconds: float) -> None:
    """Spend about this much CPU time in this thread."""
    import time

    end = time.thread_time() + seconds
    while time.thread_time() < end:
        pass


def test_episodes_are_stamped_with_their_experiments_own_clocks():
    live = LiveProgress(2, 4)
    clock = EpisodeClock(live)
    with live.counting_cpu():  # experiment 0, in this thread
        busy(0.02)
        live.steps[0, 0], live.updates[0, 0] = 5, 10
        clock.sample()
        busy(0.02)
        live.steps[0, 1:3], live.updates[0, 1:3] = (7, 9), (10, 30)  # two in one poll
        clock.sample()
        first = live.episode_seconds[:, 0, :3].copy()
    clock.sample()  # nothing new: nothing restamped
    np.testing.assert_array_equal(live.episode_seconds[:, 0, :3], first)
    assert np.isnan(live.episode_seconds[:, 1]).all()  # experiment 1 never started
    wall, cpu = first
    assert np.all(np.diff(wall) > 0) and np.all(np.diff(cpu) > 0)
    assert cpu[0] == pytest.approx(0.02, abs=0.015)
    # the two episodes of one poll share its time in proportion to their updates (10 : 30)
    assert (wall[1] - wall[0]) * 3 == pytest.approx(wall[2] - wall[1], rel=1e-3)
    # the experiment ended: its last episode of the last poll is at its final clocks
    ended = live.experiment_seconds()
    live.steps[0, 3], live.updates[0, 3] = 2, 2
    clock.sample()
    np.testing.assert_allclose(live.episode_seconds[:, 0, 3], ended[:, 0], rtol=1e-6)
    assert ended[1, 0] == pytest.approx(live.cpu_seconds, rel=1e-6)


def test_experiments_take_their_clocks_in_start_order_across_threads():
    live = LiveProgress(2, 1)

    def second() -> None:
        with live.counting_cpu():
            busy(0.05)
            live.steps[1, 0], live.updates[1, 0] = 1, 1

    with live.counting_cpu():  # experiment 0 starts first, and stays short
        thread = threading.Thread(target=second)
        thread.start()
        live.steps[0, 0], live.updates[0, 0] = 1, 1
    thread.join()
    EpisodeClock(live).sample()
    cpu = live.episode_seconds[1, :, 0]
    assert cpu[1] > cpu[0] and cpu[1] == pytest.approx(0.05, abs=0.03)


def test_episode_seconds_average_the_experiments_that_finished_and_were_stamped():
    steps = np.array([[3, 4, -1], [5, -1, -1]])
    seconds = np.full((2, 2, 3), np.nan)
    seconds[:, 0, :2] = [[1.0, 2.0], [0.5, 1.0]]
    seconds[:, 1, 0] = [3.0, 1.5]
    seconds[:, 1, 1] = [9.0, 9.0]  # a stamp on an episode not done is ignored
    times = episode_seconds(steps, seconds)
    np.testing.assert_array_equal(times[:, :2], [[2.0, 2.0], [1.0, 1.0]])
    assert np.isnan(times[:, 2]).all()


def test_curves_csv_carries_the_times_and_reads_them_back():
    steps = np.array([[3, 5, -1], [4, 7, 2]])
    times = np.array([[0.5, 1.25, np.nan], [0.25, 0.75, np.nan]])
    curve = curve_statistics(steps, times=times)
    assert curve["wall_seconds"] == [0.5, 1.25, None] and curve["cpu_seconds"][2] is None
    text = curves_csv(curve)
    rows = list(csv.reader(io.StringIO(text)))
    assert tuple(rows[0]) == CURVE_COLUMNS + TIME_COLUMNS
    assert rows[3][-2:] == ["", ""]
    back = read_curve_times(text, 3)
    np.testing.assert_array_equal(back[:, :2], times[:, :2])
    assert np.isnan(back[:, 2]).all()
    # an older file, without the columns, has no times; garbled cells drop them
    assert read_curve_times(curves_csv(curve_statistics(steps)), 3) is None
    assert read_curve_times(text.replace("1.25", "x"), 3) is None
    # downsampled, a bucket's time is the mean of its episodes'
    long = curve_statistics(np.ones((1, 10), np.int64), times=np.vstack([np.arange(10.0)] * 2))
    small = downsample_curve(long, 5)
    assert small["wall_seconds"] == [0.5, 2.5, 4.5, 6.5, 8.5]


def test_the_live_curve_takes_times_stamped_a_poll_after_the_steps():
    live = LiveProgress(2, 3)
    curve = LiveCurve(3)
    live.steps[0, :2] = (4, 6)
    curve.update(live.steps, seconds=live.episode_seconds)
    assert curve.curve()["wall_seconds"] == [None, None]
    seen = curve.version
    live.episode_seconds[:, 0, :2] = [[1.0, 2.0], [0.5, 1.0]]
    curve.update(live.steps, seconds=live.episode_seconds)  # no new episode, new stamps
    assert curve.curve()["wall_seconds"] == [1.0, 2.0]
    assert curve.changed_since(seen) == [(0, 2)]
    expected = curve_statistics(live.steps, times=episode_seconds(live.steps, live.episode_seconds))
    assert curve.curve() == expected


def test_a_trained_run_saves_times_and_an_older_one_loads_without(tmp_path):
    run = RunFolder.create(tmp_path, tiny_record(), name="timed")
    result = run.train(workers=1)
    again = RunFolder.load(run.path)
    curve = again.curve()
    assert all(v is not None and v >= 0 for v in curve["wall_seconds"] + curve["cpu_seconds"])
    assert np.all(np.diff(curve["cpu_seconds"]) >= 0)  # per experiment, time only grows
    # the last episode's CPU time is each experiment's whole CPU time, averaged
    assert curve["cpu_seconds"][-1] == pytest.approx(result.cpu_seconds.mean(), abs=2e-3)
    rows = list(csv.reader(io.StringIO((run.path / "curves.csv").read_text())))
    assert rows[0][-2:] == list(TIME_COLUMNS)
    # a folder written before the times: curves.csv in the old layout
    (run.path / "curves.csv").write_text(curves_csv(curve_statistics(again.steps())))
    old = RunFolder.load(run.path)
    assert old.episode_times() is None and "wall_seconds" not in old.curve()
    assert old.curve() == curve_statistics(result.steps)


def test_a_run_recovered_after_a_crash_keeps_its_episodes_times(tmp_path, monkeypatch):
    """A killed process leaves its folder as of its last checkpoint: ``running``, nobody holding
    its lock. Recovered, its curve keeps the wall and CPU time of each checkpointed episode."""
    monkeypatch.setattr(_run_train, "CHECKPOINT_SECONDS", 0.0)  # a checkpoint at every poll
    grid = ArmGrid(joints=3, bins=11, goal=(5, 5, 5))
    config = DynaQConfig(planning="full", planning_steps=2000)  # slow: stopped long before
    record = RunRecord.for_arm_grid(grid, config, 1, 100_000, seed=3, origin="cli")
    run = RunFolder.create(tmp_path / "runs", record, name="crashing")
    crashed = tmp_path / "crashed"

    def crash_after_a_checkpoint(live: LiveProgress) -> None:
        if not crashed.exists() and (run.path / "steps.csv").exists():
            shutil.copytree(run.path, crashed)  # what kill -9 would leave at this moment
            live.stop()

    run.train(workers=1, on_checkpoint=crash_after_a_checkpoint)
    left = RunFolder.load(crashed)
    assert left.status == "stopped" and left.interrupted
    left.recover()
    again = RunFolder.load(crashed)
    assert not again.interrupted and again.status == "stopped"
    curve = again.curve()
    done = len(curve["episodes"])
    assert 0 < done < 100_000
    wall = [v for v in curve["wall_seconds"] if v is not None]
    cpu = [v for v in curve["cpu_seconds"] if v is not None]
    # an episode that ended between the poll's stamp and the checkpoint may have none
    assert len(wall) == len(cpu) >= done - 2 and len(wall) >= 1
    assert np.all(np.diff(wall) >= 0) and np.all(np.diff(cpu) >= 0)
    assert all(v > 0 for v in wall + cpu)
    rows = list(csv.reader(io.StringIO((crashed / "curves.csv").read_text())))
    assert rows[0][-2:] == list(TIME_COLUMNS) and len(rows) == done + 1
