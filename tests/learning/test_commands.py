"""Smoke tests of the learning verbs on tiny budgets, through the real CLI entry point."""

from __future__ import annotations

import csv
import json

import numpy as np

from studio.cli import main
from studio.learning import load_policy
from studio.learning._reproduce import CONFIGURATIONS, PAPER_MATLAB_SECONDS


def test_reproduce_tiny_budget(tmp_path, capsys) -> None:
    out = tmp_path / "repro"
    code = main(
        ["reproduce", "--out", str(out), "--experiments", "2", "--episodes", "36", "--no-progress"]
    )
    assert code == 0
    for name in (
        "curves.csv",
        "timing.csv",
        "REPORT.md",
        "fig5.png",
        "fig5.svg",
        "fig8.png",
        "fig8.svg",
    ):
        assert (out / name).stat().st_size > 0, name
    with (out / "curves.csv").open() as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 6 * 36 and {r["configuration"] for r in rows} == set(CONFIGURATIONS)
    sv_first = [float(r["mean"]) for r in rows if r["configuration"] == "SV-FPL"][:20]
    assert max(sv_first) < 40  # demonstrations are short paths, not thousands of steps
    with (out / "timing.csv").open() as stream:
        timing = {r["configuration"]: r for r in csv.DictReader(stream)}
    assert float(timing["US-FPL"]["paper_matlab_seconds"]) == PAPER_MATLAB_SECONDS["US-FPL"]
    assert int(timing["US-FPL"]["updates"]) > int(timing["US-ZPL"]["updates"])
    report = (out / "REPORT.md").read_text()
    assert "thousands of steps" in report and "| 7 |" in report and "| US-PSW |" in report
    assert "± " in report  # means come with their standard errors
    printed = capsys.readouterr().out
    assert "paper Matlab" in printed and "1435.4" in printed
    # the table's total is over the six configurations of the paper, not the extension
    total = next(line for line in printed.splitlines() if line.startswith("total")).split()
    six = sum(float(row["wall_seconds"]) for row in timing.values())
    assert abs(float(total[2]) - six) < 0.002 + 1e-9
    assert abs(float(total[1]) - sum(float(r["cpu_seconds"]) for r in timing.values())) < 0.002


def test_train_then_export(tmp_path, capsys) -> None:
    config = tmp_path / "run.json"
    config.write_text(
        json.dumps(
            {
                "grid": {"joints": 2, "bins": 5, "goal": [2, 2]},
                "config": {"planning": "soft", "planning_steps": 20},
                "experiments": 2,
                "episodes": 15,
            }
        )
    )
    run_dir = tmp_path / "run"
    assert (
        main(
            [
                "train",
                "--config",
                str(config),
                "--out",
                str(run_dir),
                "--seed",
                "3",
                "--no-progress",
            ]
        )
        == 0
    )
    policy = load_policy(run_dir / "policy.policy.npz")
    assert policy.grid.goal == (2, 2) and policy.config.planning == "soft"
    assert len(policy.mean_steps) == 15
    steps = np.loadtxt(run_dir / "steps.csv", delimiter=",")
    assert steps.shape == (2, 15)
    assert json.loads((run_dir / "config.json").read_text())["seed"] == 3

    csv_path = tmp_path / "rollout.csv"
    assert (
        main(
            [
                "export",
                str(run_dir / "policy.policy.npz"),
                "--start-deg=-150,150",
                "--out",
                str(csv_path),
            ]
        )
        == 0
    )
    data = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    assert data.shape[1] == 7 and np.all(np.diff(data[:, 0]) > 0)


def test_user_errors_are_one_line_not_tracebacks(tmp_path, capsys) -> None:
    assert main(["train", "--episodes", "1000000000", "--no-progress"]) == 2
    assert "episodes is 1000000000" in capsys.readouterr().err
    bad = tmp_path / "bad.policy.npz"
    bad.write_text("nope")
    assert main(["export", str(bad)]) == 2
    assert "bad.policy.npz is corrupt" in capsys.readouterr().err
