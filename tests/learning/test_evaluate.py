"""``studio evaluate RUN|POLICY [--starts N] [--seed S] [--json]`` (issue 40): the policy from
held-out random starts, and for a run taught by following demonstrations the teacher (the
demonstrations followed, no learning) from the very same starts."""

from __future__ import annotations

import json

import pytest

from studio.cli import main

KEYS = {"success", "collisions", "mean_steps", "mean_seconds"}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("evaluate")
    common = ["--episodes", "5", "--experiments", "1", "--no-progress"]
    taught = ["train", "--task", "arm-reach", "--demos", "sample-reach-1", *common]
    assert main([*taught, "--out", str(root / "runs/taught")]) == 0
    assert main(["train", "--planning", "zero", *common, "--out", str(root / "runs/grid")]) == 0
    return root


def _evaluate(capsys, *argv: str) -> dict:
    capsys.readouterr()
    assert main(["evaluate", *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_a_taught_run_stands_beside_its_teacher_on_the_same_starts(runs, capsys):
    out = _evaluate(capsys, str(runs / "runs/taught"), "--starts", "8", "--seed", "3")
    assert set(out) == {"policy", "teacher"}
    assert set(out["policy"]) == set(out["teacher"]) == KEYS
    # pressing 'follow the demonstrations' at every step reaches the goal from anywhere: the
    # controller the audit found behind the headline (issue 40)
    assert out["teacher"]["success"] == 1.0 and out["teacher"]["mean_steps"] > 0
    assert 0.0 <= out["policy"]["collisions"] <= 1.0
    # the same seed draws the same starts: the same figures again
    assert _evaluate(capsys, str(runs / "runs/taught"), "--starts", "8", "--seed", "3") == out


def test_a_run_by_name_in_the_data_folder_and_a_grid_run_has_no_teacher(runs, capsys):
    out = _evaluate(capsys, "grid", "--data-dir", str(runs), "--starts", "4")
    assert set(out) == {"policy"} and set(out["policy"]) == KEYS


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["sample-reach-1"], "not a policy"),
        (["no-such-run"], "There is no file no-such-run"),
        (["sample-reach-1", "--starts", "0"], "--starts is 0"),
    ],
)
def test_a_wrong_argument_is_one_sentence(argv, says, capsys, tmp_path):
    assert main(["evaluate", *argv, "--data-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert says in err and err.count("\n") == 1
