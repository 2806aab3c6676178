"""``studio export`` prints a policy's likeness card: against ``--demo``, else its run's own
demonstrations, rolled out from the demonstration's start, the demonstration's values beside."""

from __future__ import annotations

import json

import pytest

from studio.cli import main
from studio.samples import SAMPLES_DIR

DEMO = SAMPLES_DIR / "sample-reach-1.demo.json"


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """A tiny run of the CLI that replays a recorded demonstration."""
    run = tmp_path_factory.mktemp("run") / "run"
    argv = ["train", "--out", str(run), "--episodes", "6", "--experiments", "1",
            "--planning", "zero", "--demos", str(DEMO), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    return run


def card_columns(said: str) -> None:
    assert "likeness to" in said and "from the demonstration's start" in said
    header = next(
        line for line in said.splitlines() if "policy" in line and "demonstration" in line
    )
    assert header.split() == ["policy", "demonstration"]
    assert "smoothness LDLJ" in said and "duration (s)" in said


def test_a_run_writes_likeness_json_and_export_prints_its_own_card(run, tmp_path, capsys):
    document = json.loads((run / "likeness.json").read_text())
    assert document["cards"][0]["card"]["demonstration"]["duration_s"] > 0
    capsys.readouterr()
    policy = run / "policy.policy.npz"
    assert main(["export", str(policy), "--out", str(tmp_path / "a.csv")]) == 0  # the old form
    card_columns(capsys.readouterr().out)
    argv = [
        "export",
        str(policy),
        "--format",
        "csv",
        "--unchecked",
        "--out",
        str(tmp_path / "b.csv"),
    ]
    assert main(argv) == 0
    card_columns(capsys.readouterr().out)


def test_demo_names_the_demonstration_to_compare_with(run, tmp_path, capsys):
    policy = run / "policy.policy.npz"
    argv = ["export", str(policy), "--out", str(tmp_path / "a.csv"), "--demo", "sample-reach-2"]
    assert main(argv) == 0
    said = capsys.readouterr().out
    card_columns(said)
    assert "likeness to sample-reach-2" in said


def test_demo_that_is_not_a_demonstration_is_one_sentence(run, tmp_path, capsys):
    policy = run / "policy.policy.npz"
    argv = [
        "export",
        str(policy),
        "--out",
        str(tmp_path / "a.csv"),
        "--demo",
        "sample-reach-1.tape.csv",
    ]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "not a demonstration" in err and "Traceback" not in err and len(err.splitlines()) == 1
