"""benchmarks/bench_peers.py runs without Stable-Baselines3, and its peers are judged as the studio is."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import gymnasium
import numpy as np
import pytest

from studio.learning import ArmReach

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"


@pytest.fixture(scope="module")
def bench():
    with pytest.MonkeyPatch.context() as patch:
        patch.syspath_prepend(str(BENCHMARKS))
        yield importlib.import_module("bench_peers")


class Rule:
    """A stand-in for an SB3 model: ``predict`` maps scaled observations to actions by a rule."""

    def __init__(self, task: ArmReach, rule) -> None:
        self.task, self.rule = task, rule

    def predict(self, obs, deterministic=True):
        assert deterministic
        q = self.task.lower + (np.asarray(obs, np.float64) + 1.0) / 2.0 * (
            self.task.upper - self.task.lower
        )
        return np.array([self.rule(row) for row in q]), None


def plain_success(task: ArmReach, model: Rule, starts: np.ndarray, cap: int) -> float:
    """Each start rolled out in the registered environment, one step at a time, to the cap."""
    env = gymnasium.make("TeachStudio/ArmReach-v0", joints=task.joints)
    wins = 0
    for start in starts:
        obs, _ = env.reset(options={"q": start})
        for _ in range(cap):
            scaled = 2.0 * (obs - task.lower) / (task.upper - task.lower) - 1.0
            obs, _, terminated, _, _ = env.step(int(model.predict(scaled[None])[0][0]))
            if terminated:
                wins += 1
                break
    return wins / len(starts)


def test_peer_success_is_the_plain_rollouts(bench):
    """Batched, with loops cut short, it scores a policy as stepping the environment does."""
    task = ArmReach(joints=3)
    goal = np.asarray(task.goal)[:3]
    half = task.step / 2

    def toward(q):  # the first joint off its goal angle steps toward it: reaches the goal
        for j in range(3):
            if abs(q[j] - goal[j]) > half:
                return 2 * j if q[j] < goal[j] else 2 * j + 1
        return 0

    def swing(q):  # joint 1 swings about its goal angle for ever
        return 0 if q[0] < goal[0] else 1

    def push(q):  # joint 1 up into its limit, then stuck there
        return 0

    starts = bench.held_out_starts(3)[:12]
    starts[0] = goal + np.array([0.0, task.step, 0.0])  # one step from the goal
    for rule in (toward, swing, push):
        model = Rule(task, rule)
        expected = plain_success(task, model, starts, bench.CAP)
        assert bench.peer_success(model, task, starts, None) == expected
    assert plain_success(task, Rule(task, toward), starts, bench.CAP) == 1.0
    assert plain_success(task, Rule(task, swing), starts[1:], bench.CAP) == 0.0


def test_studio_side_runs_without_sb3(bench, monkeypatch, capsys):
    """With SB3 missing it says how to install the extra and measures the studio alone; the
    studio's learner is evaluated on the rhythm and checked against the compiled kernel."""
    monkeypatch.setitem(sys.modules, "stable_baselines3", None)  # as if not installed
    rows = bench.main(
        ["--joints", "3", "--seeds", "1", "--budget", "3000", "--learners", "8 tiles, 30", "DQN"]
    )
    out = capsys.readouterr().out
    assert 'pip install -e ".[peers]"' in out
    name = "studio, 32 tilings x 8 tiles, 30 planning steps"
    assert [r.name for r in rows] == [name]
    (trace,) = rows[0].traces
    assert trace.steps == [1000, 2000, 3000]
    assert all(0.0 <= s <= 1.0 for s in trace.success)
    assert f"| {name} |" in out
