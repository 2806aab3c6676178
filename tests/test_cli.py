from __future__ import annotations

import sys

import pytest

from studio.cli import build_parser, main


def test_help_lists_every_verb(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    _, modules = build_parser()
    for verb in modules:
        assert verb in out


def test_unknown_verb_is_a_usage_error() -> None:
    with pytest.raises(SystemExit) as exc:
        main(["no-such-verb"])
    assert exc.value.code == 2


def test_output_into_a_closed_pipe_ends_quietly():
    """`studio info FILES | head` is not an error: no traceback when the reader goes away."""
    import subprocess
    import sys

    from studio.samples import SAMPLES_DIR

    sample = SAMPLES_DIR / "sample-reach-1.tape.csv"
    cmd = [sys.executable, "-m", "studio", "info", *[str(sample)] * 400]  # more than a pipe holds
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # the reader is gone before the first line
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 0 and b"Traceback" not in err, err.decode()


def test_train_finds_a_demonstration_by_name_from_a_fresh_data_folder(tmp_path, monkeypatch):
    """README's ``studio train --demos sample-reach-2``: a shipped sample by name, from any folder;
    a demonstration of the data folder's own ``recordings/`` by name comes first."""
    import json

    from studio.capture import load_demonstration
    from studio.cli import main
    from studio.samples import SAMPLES_DIR

    monkeypatch.chdir(tmp_path)
    args = ["--episodes", "2", "--experiments", "1", "--planning", "zero", "--no-progress"]
    assert main(["train", "--demos", "sample-reach-2", "--out", "runs/a", *args]) == 0
    stored = json.loads((tmp_path / "runs/a/config.json").read_text())["demonstrations"]
    assert stored == [load_demonstration(SAMPLES_DIR / "sample-reach-2.demo.json").grid_path]
    (tmp_path / "recordings").mkdir()
    mine = load_demonstration(SAMPLES_DIR / "sample-reach-3.demo.json")
    mine.save(tmp_path / "recordings" / "sample-reach-2.demo.json")
    assert main(["train", "--demos", "sample-reach-2.demo.json", "--out", "runs/b", *args]) == 0
    stored = json.loads((tmp_path / "runs/b/config.json").read_text())["demonstrations"]
    assert (
        stored
        == [mine.grid_path]
        != [load_demonstration(SAMPLES_DIR / "sample-reach-2.demo.json").grid_path]
    )


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["record", "--seconds", "x", "--out", "x.tape.csv"], "studio record: argument --seconds"),
        (["record"], "studio record: the following arguments are required: --out"),
        (["record", "--out", "x.tape.csv", "--bogus"], "studio record: unrecognized arguments"),
        (["no-such-verb"], "studio: argument VERB: invalid choice"),
    ],
)
def test_a_usage_error_is_one_line_pointing_to_help(argv, says, capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(says), err
    verb = "studio" if argv[0] == "no-such-verb" else f"studio {argv[0]}"
    assert err.rstrip().endswith(f"see {verb} --help."), err


def test_a_terminal_is_told_a_recording_is_being_retargeted_a_script_is_not(
    tmp_path, capsys, monkeypatch
):
    argv = ["export", "sample-reach-1.tape.csv", "--robot", "ur5", "--format", "csv"]
    out = ["--out", str(tmp_path / "a.csv"), "--unchecked"]
    assert main([*argv, *out]) == 0
    assert "Retargeting" not in capsys.readouterr().err  # not a terminal: nothing said
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert main([*argv, *out]) == 0
    said = capsys.readouterr().err
    assert said.startswith(
        "Retargeting sample-reach-1.tape.csv onto the Universal Robots UR5, its IK branches "
        "planned over the whole motion"
    )
