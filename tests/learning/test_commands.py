"""Smoke tests of the learning verbs on tiny budgets, through the real CLI entry point."""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient

from studio.cli import main
from studio.commands import train
from studio.learning import (
    DEFAULT_EPISODES,
    DEFAULT_EXPERIMENTS,
    DEFAULT_GOAL_JOINTS_DEG,
    DEFAULT_SEED,
    ArmGrid,
    DynaQConfig,
    RunFolder,
    load_any_policy,
    load_policy,
)
from studio.learning.paper._reproduce import CONFIGURATIONS, EXTENSIONS, PAPER_MATLAB_SECONDS
from studio.learning.runs._curves import CURVE_COLUMNS, TIME_COLUMNS
from studio.learning.tasks._goal import goal_problems
from studio.web import create_app
from studio.web._schemas import ReachRunCreate
from tests.web.conftest import TINY_RUN, make_settings, wait_run


def test_the_readme_and_the_help_count_the_configurations_reproduce_writes() -> None:
    words = {1: "one", 6: "six", 7: "seven"}
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    line = next(row for row in readme.splitlines() if row.startswith("studio reproduce"))
    paper, beyond = words[len(CONFIGURATIONS)], words[len(EXTENSIONS)]
    assert f"{paper} configurations and {beyond} beyond it" in line, line
    from studio.commands import reproduce as command

    total = words[len(CONFIGURATIONS) + len(EXTENSIONS)]
    assert f"{paper} Dyna-Q configurations" in command.HELP and f"({total})" in command.HELP


def test_reproduce_tiny_budget(tmp_path, capsys) -> None:
    out = tmp_path / "repro"
    code = main(
        ["reproduce", "--out", str(out), "--experiments", "2", "--episodes", "36", "--no-progress"]
    )
    assert code == 0
    with (out / "curves.csv").open() as stream:
        assert next(csv.reader(stream)) == ["configuration", *CURVE_COLUMNS]
    for name in {**CONFIGURATIONS, **EXTENSIONS}:  # each configuration is an ordinary run
        run = RunFolder.load(out / name)
        assert run.status == "done" and run.has_policy
        assert (run.record.origin, run.record.group, run.record.name) == (
            "reproduce",
            "repro",
            name,
        )
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


SAMPLE_DEMO = (
    Path(__file__).resolve().parents[2] / "studio" / "samples" / "sample-reach-2.demo.json"
)


@pytest.mark.parametrize(
    ("old", "new", "says"),
    [
        ('"t":[1.0,', '"t":["one",', "trajectory is missing or is not a list of times"),
        ('"t":[1.0,', '"t":[NaN,', "holds NaN or infinite samples (sample 1 of"),
        ('"goal":[5,6,2],"grid_path"', '"goal":[Infinity,6,2],"grid_path"', "goal is missing"),
        ('"grid_path":[898,', '"grid_path":[1e999,', "grid_path is missing or is not"),
        ('"reached_at":2.24', '"reached_at":1e999,"x":2.24', "reached_at holds NaN or infinite"),
        ('"segment":[1.0,', '"segment":[-Infinity,', "segment holds NaN or infinite values"),
    ],
)
def test_train_on_a_damaged_demonstration_is_one_sentence(
    old: str, new: str, says: str, tmp_path, capsys
) -> None:
    """Strings, NaN, Infinity or 1e999 (JSON's way to write infinity) where a demonstration has
    numbers: one sentence naming the field, never a traceback nor a run trained on NaN."""
    text = SAMPLE_DEMO.read_text()
    assert old in text
    bad = tmp_path / "bad.demo.json"
    bad.write_text(text.replace(old, new, 1))
    argv = ["train", "--demos", str(bad), "--episodes", "2", "--experiments", "1", "--no-progress"]
    assert main([*argv, "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("studio train: ") and says in err, err
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ('[["a", "b"]]', "Demonstration 0 holds 'a', not a grid state"),
        ("[[0, 1], [NaN, 1]]", "Demonstration 1 holds nan, not a grid state"),
        ("[[Infinity]]", "Demonstration 0 holds inf, not a grid state"),
        ('{"demonstrations": [[1e999, 2]]}', "Demonstration 0 holds inf, not a grid state"),
        ("[[1.5, 2]]", "Demonstration 0 holds 1.5, not a grid state"),
        ("[[true, 2]]", "Demonstration 0 holds True, not a grid state"),
    ],
)
def test_train_on_a_file_of_bad_grid_paths_is_one_sentence(text: str, says: str, tmp_path, capsys):
    """Grid paths holding strings, NaN, Infinity or 1e999 once gave ``ValueError: invalid
    literal for int()`` (or an ``OverflowError``) from the run request."""
    bad = tmp_path / "paths.json"
    bad.write_text(text)
    argv = ["train", "--demos", str(bad), "--episodes", "2", "--experiments", "1", "--no-progress"]
    assert main([*argv, "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("studio train: ") and says in err, err
    assert "from 0 to 1330" in err and not (tmp_path / "run").exists()


@pytest.mark.parametrize(
    ("old", "new", "says"),
    [
        ('"experiments": 1', '"experiments": Infinity', "experiments is inf"),
        ('"experiments": 1', '"experiments": 1e999', "experiments is inf"),
        ('"mean_steps": [', '"mean_steps": [Infinity, ', "its curve holds an infinite value"),
        ('"alpha": 0.1', '"alpha": Infinity', "alpha is inf"),
    ],
)
def test_export_of_a_policy_with_infinity_in_its_header_is_one_sentence(
    old: str, new: str, says: str, tmp_path, capsys
) -> None:
    args = ["--episodes", "2", "--experiments", "1", "--planning", "zero", "--no-progress"]
    assert main(["train", "--out", str(tmp_path / "run"), *args]) == 0
    with np.load(tmp_path / "run" / "policy.policy.npz") as archive:
        arrays = {key: archive[key] for key in archive.files}
    header = str(arrays["header"])
    assert old in header
    arrays["header"] = np.array(header.replace(old, new, 1))
    bad = tmp_path / "bad.policy.npz"
    np.savez_compressed(bad, **arrays)
    capsys.readouterr()
    assert main(["export", str(bad), "--out", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "damaged header" in err and says in err, err


def _parse_train(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    train.add_arguments(parser)
    return parser.parse_args(argv)


def test_the_train_commands_defaults_are_the_learning_packages() -> None:
    settings = train.resolve(_parse_train([]))
    assert settings.config == DynaQConfig() and settings.task == ArmGrid()
    assert (settings.experiments, settings.episodes, settings.seed) == (
        DEFAULT_EXPERIMENTS,
        DEFAULT_EPISODES,
        DEFAULT_SEED,
    )
    assert settings.demonstrations == []
    flags = train.resolve(_parse_train(["--planning", "soft", "--bins", "7", "--seed", "4"]))
    assert flags.config == DynaQConfig(planning="soft") and flags.task == ArmGrid(bins=7)
    assert flags.seed == 4


def test_the_page_and_the_command_share_every_default(tmp_path) -> None:
    with TestClient(create_app(make_settings(tmp_path))) as client:
        served = client.get("/api/config").json()
    form = served["training"]
    config, grid = DynaQConfig(), ArmGrid()
    for key in ("planning", "planning_steps", "alpha", "gamma", "epsilon"):
        assert form[key] == getattr(config, key), key
    assert form["bins"] == grid.bins and form["goal_deg"] == list(DEFAULT_GOAL_JOINTS_DEG)
    assert (form["experiments"], form["episodes"], form["seed"]) == (
        DEFAULT_EXPERIMENTS,
        DEFAULT_EPISODES,
        DEFAULT_SEED,
    )
    assert served["planners"] == ["zero", "full", "soft", "prioritized"]
    assert config.planning == "full"  # the paper's Dyna-Q: 100 planning updates per real step
    # the default goal's bins are the grid's default goal
    assert (
        train.resolve(_parse_train(["--goal-deg", ",".join(map(str, form["goal_deg"]))])).task
        == grid
    )


def test_one_goal_check_for_the_page_and_the_command(tmp_path, capsys) -> None:
    bad = [170.0, 0.0, -150.0]
    sentences = goal_problems(bad)
    assert len(sentences) == 2
    assert main(["train", f"--goal-deg={','.join(map(str, bad))}", "--no-progress"]) == 2
    printed = capsys.readouterr().err
    assert all(sentence in printed for sentence in sentences)
    with TestClient(create_app(make_settings(tmp_path))) as client:
        r = client.post("/api/runs", json={**TINY_RUN, "goal_deg": bad})
    assert r.status_code == 422 and r.json()["problems"] == sentences


def test_every_bad_field_is_reported_at_once_by_the_page_and_the_command(tmp_path, capsys) -> None:
    with TestClient(create_app(make_settings(tmp_path))) as client:
        r = client.post("/api/runs", json={**TINY_RUN, "alpha": 5, "episodes": 0, "seed": -1})
        assert client.get("/api/runs").json() == []
    assert r.status_code == 422
    body = r.json()
    assert set(body["by_field"]) == {"alpha", "episodes", "seed"}
    assert len(body["problems"]) == 3 and body["detail"] == " ".join(body["problems"])
    assert main(["train", "--alpha", "5", "--episodes", "0", "--seed", "-1", "--no-progress"]) == 2
    printed = capsys.readouterr().err
    assert all(problem in printed for problem in body["problems"])


def test_a_run_trained_on_the_command_line_is_listed_plotted_watched_and_exported(
    tmp_path, monkeypatch
) -> None:
    monkeypatch.chdir(tmp_path)  # a data folder: studio train writes runs/<name>
    args = ["--experiments", "2", "--episodes", "6", "--planning", "zero", "--no-progress"]
    assert main(["train", "--out", "runs/cli-run", "--name", "from the terminal", *args]) == 0
    assert main(["reproduce", "--out", "runs/paper", "--experiments", "1", "--episodes", "3",
                 "--no-progress"]) == 0  # fmt: skip
    with TestClient(create_app(make_settings(tmp_path))) as client:
        listed = {r["id"]: r for r in client.get("/api/runs").json()}
        cli = listed["cli-run"]
        assert cli["origin"] == "cli" and cli["status"] == "done" and cli["has_policy"]
        assert cli["name"] == "from the terminal" and cli["episodes_done"] == 12
        assert cli["config"]["planning"] == "zero" and cli["config"]["episodes"] == 6
        assert {f"paper~{name}" for name in CONFIGURATIONS} <= set(listed)
        assert listed["paper~SV-FPL"]["origin"] == "reproduce"
        assert listed["paper~SV-FPL"]["group"] == "paper"

        curve = client.get("/api/runs/cli-run/curve").json()
        steps = np.loadtxt(tmp_path / "runs/cli-run/steps.csv", delimiter=",")
        assert curve["episodes"] == list(range(1, 7))
        assert curve["mean"] == pytest.approx(steps.mean(axis=0), abs=1e-3)
        watched = client.post("/api/watch", json={"run": "cli-run", "seed": 1})
        assert watched.status_code == 200 and len(watched.json()["states"]) >= 1
        policy = client.get("/api/runs/cli-run/policy")
        assert policy.content == (tmp_path / "runs/cli-run/policy.policy.npz").read_bytes()
        png = client.get("/api/runs/paper~SV-FPL/plot.png")
        assert png.status_code == 200 and png.content[:4] == b"\x89PNG"

        # one curves.csv layout: the command's file, the page's download, the page's own runs
        page_csv = client.get("/api/runs/cli-run/curve.csv").text
        assert page_csv == (tmp_path / "runs/cli-run/curves.csv").read_text()
        page_run = client.post("/api/runs", json=TINY_RUN).json()
        wait_run(client, page_run["id"])
        page_file = (tmp_path / "runs" / page_run["id"] / "curves.csv").read_text()
    header = ",".join(CURVE_COLUMNS)
    timed = ",".join(CURVE_COLUMNS + TIME_COLUMNS)  # a run's own file has its episodes' times
    assert page_csv.splitlines()[0] == page_file.splitlines()[0] == timed
    assert (tmp_path / "runs/paper/curves.csv").read_text().splitlines()[
        0
    ] == f"configuration,{header}"


def test_train_learns_the_continuous_task_the_page_trains_and_export_reads_it(
    tmp_path, capsys
) -> None:
    run_dir = tmp_path / "reach"
    argv = ["train", "--task", "arm-reach", "--joints", "4", "--step-deg", "2", "--tiles", "16",
            "--tilings", "4", "--experiments", "1", "--episodes", "2", "--planning-steps", "5",
            "--out", str(run_dir), "--no-progress"]  # fmt: skip
    assert main(argv) == 0, capsys.readouterr().err
    record = json.loads((run_dir / "config.json").read_text())
    assert record["task"]["kind"] == "arm-reach" and record["task"]["joints"] == 4
    assert record["task"]["tile_coding"]["tiles"] == 16
    assert record["task"]["tile_coding"]["tilings"] == 4
    policy = load_any_policy(run_dir / "policy.policy.npz")
    assert policy.task.joints == 4
    csv_path = tmp_path / "reach.csv"
    assert main(["export", str(run_dir / "policy.policy.npz"), "--out", str(csv_path)]) == 0
    data = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    assert data.ndim == 2 and data.shape[1] == 7


def test_train_takes_the_continuous_defaults_and_checks_from_the_page(tmp_path) -> None:
    settings = train.resolve(_parse_train(["--task", "arm-reach"]))
    with TestClient(create_app(make_settings(tmp_path))) as client:
        form = client.get("/api/config").json()["training"]
    task, coding = settings.arm_reach(), settings.tile_coding()
    assert task.joints == form["joints"] and task.step_deg == form["step_deg"]
    assert form["tiles"] is None and coding.tiles == task.default_tiles == 32  # the robot's own
    assert coding.tilings == form["tilings"]
    page = ReachRunCreate(task="arm-reach")
    keys = ("planning", "planning_steps", "alpha", "gamma", "epsilon")
    assert settings.config == DynaQConfig(**{key: getattr(page, key) for key in keys})
    assert (settings.experiments, settings.episodes) == (page.experiments, page.episodes)


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["--task", "arm-reach", "--joints", "9"], "joints is 9"),
        (["--task", "arm-reach", "--step-deg", "5"], "step_deg"),
        (["--task", "arm-reach", "--tiles", "0"], "tiles"),
        (["--task", "arm-reach", "--bins", "5"], "--bins sets the arm grid"),
        (["--task", "arm-reach", "--generated-demos", "2"], "--generated-demos"),
        (["--task", "arm-reach", "--goal-deg=170,0,0"], "goal_deg joint 1"),
        (["--tiles", "8"], "--tiles sets the continuous task; add --task arm-reach"),
    ],
)
def test_bad_continuous_settings_give_one_sentence(argv, words, capsys) -> None:
    assert main(["train", *argv, "--episodes", "2", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err and err.count("\n") == 1
