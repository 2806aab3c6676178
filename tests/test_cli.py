from __future__ import annotations

import json
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


def test_the_cli_page_lists_every_verb_and_every_serve_flag() -> None:
    """``docs/cli.md`` is where the README sends a reader for the verbs: none may be missing."""
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "cli.md").read_text()
    parser, modules = build_parser()
    for verb in modules:
        assert f"| `studio {verb}` |" in page, verb
    serve = next(
        action.choices["serve"] for action in parser._actions if getattr(action, "choices", None)
    )
    for action in serve._actions:
        flag = max(action.option_strings, key=len)
        assert flag == "--help" or f"`{flag}" in page, flag


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


@pytest.mark.parametrize(
    ("argv", "option", "value"),
    [
        (["train", "--goal-deg", "-30,45,-90"], "goal_deg", "-30,45,-90"),
        (["export", "x", "--start-deg", "-90,0,0"], "start_deg", "-90,0,0"),
        (["export", "x", "--start-deg", "-0.5,1e-3,-2"], "start_deg", "-0.5,1e-3,-2"),
    ],
)
def test_a_list_of_numbers_that_starts_negative_is_the_options_value(argv, option, value):
    """``--goal-deg -30,45,-90`` is the goal, as ``--goal-deg=-30,45,-90`` is (argparse alone
    takes it for an unknown option and says 'expected one argument')."""
    parser, _ = build_parser()
    assert getattr(parser.parse_args(argv), option) == value


def test_an_unknown_option_still_is_one(capsys):
    with pytest.raises(SystemExit):
        main(["train", "--goal-deg", "-x"])
    assert "expected one argument" in capsys.readouterr().err


def test_a_recording_gets_a_name_the_other_verbs_take(tmp_path, monkeypatch, capsys):
    """``studio record --out x.csv`` writes ``x.tape.csv``, which ``studio info`` then reads."""
    monkeypatch.chdir(tmp_path)
    assert main(["record", "--seconds", "0.2", "--out", "x.csv"]) == 0
    assert [p.name for p in tmp_path.iterdir()] == ["x.tape.csv"]
    capsys.readouterr()
    assert main(["info", "x.tape.csv", "--json"]) == 0
    assert '"frames": ' in capsys.readouterr().out


def test_a_recording_named_as_another_kind_is_refused(tmp_path, capsys):
    assert main(["record", "--seconds", "0.2", "--out", str(tmp_path / "x.pose.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "give a name ending in .tape.csv" in err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("name", "says"),
    [("sample-reach-1", '"grid_path"'), ("sample-reach-1.tape.csv", '"regions": 16')],
)
def test_info_takes_a_samples_name_as_train_and_export_do(
    name, says, tmp_path, monkeypatch, capsys
):
    monkeypatch.chdir(tmp_path)
    assert main(["info", name, "--json"]) == 0
    assert says in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["train", "--name", "caf\udce9", "--episodes", "2"], "--name 'caf\\xe9'"),
        (["record", "--operator", "Jos\udce9", "--out", "x.tape.csv"], "--operator 'Jos\\xe9'"),
    ],
)
def test_a_name_a_latin1_shell_sent_is_refused_in_one_sentence(
    argv, option, tmp_path, capsys, monkeypatch
):
    """A shell's non-UTF-8 byte reaches Python as a lone surrogate; stored, it once broke the
    page's whole run or recording list. Refused before anything is made."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"studio {argv[0]}: {option} is not UTF-8")
    assert not list(tmp_path.iterdir())


HEAVY = (
    "numpy",
    "gymnasium",
    "scipy",
    "numba",
    "pinocchio",
    "mujoco",
    "toppra",
    "matplotlib",
    "ray",
    "fastapi",
    "viser",
    "studio.learning.tabular._dynaq",
    "studio.learning.linear._linear",
    "studio.kinematics._robot_load",
    "studio.web",
)
"""What `studio --help` once loaded (1.4 s of CPU) and a verb's parser once did (up to 2.5 s);
numpy and Gymnasium alone once made `studio train --help` take 0.4 s."""
ARGUMENT_ERRORS = {
    "serve": ["serve", "--port", "x"],
    "record": ["record", "--seconds", "x", "--out", "x.tape.csv"],
    "bridge": ["bridge", "--no-such-flag"],
    "import-raw": ["import-raw", "raw.txt"],
    "train": ["train", "--episodes", "x"],
    "sweep": ["sweep", "--workers", "x"],
    "reproduce": ["reproduce", "--experiments", "x"],
    "export": ["export"],
    "export-urdf": ["export-urdf", "--no-such-flag"],
    "info": ["info"],
    "robots": ["robots", "--no-such-flag"],
    "evaluate": ["evaluate"],
    "simulate": ["simulate"],
}
"""One usage error per verb: a value that is not a number, a missing file, an unknown flag."""
VALUE_ERRORS = (
    ["train", "--obstacle", "1,2"],
    ["train", "--obstacle", "0,0,1,0.1,0.1,-1", "--task", "arm-grid"],
    ["export", "sample-reach-1", "--format", "pdf"],
)
"""Values argparse refuses by the project's own parsers and choices (``Obstacle.parse``, the
export formats)."""


def _loaded_after(*argvs: list[str]) -> tuple[list[str], list[int]]:
    """The modules of ``HEAVY`` that running ``studio`` on each argv loaded (in one fresh
    interpreter), and each run's exit status."""
    import subprocess

    code = (
        "import sys\nfrom studio.cli import main\ncodes = []\n"
        f"for argv in {list(argvs)!r}:\n"
        "    try:\n        codes.append(main(argv))\n"
        "    except SystemExit as end:\n        codes.append(end.code)\n"
        f"print(json.dumps([[m for m in {HEAVY!r} if m in sys.modules], codes]))"
    )
    done = subprocess.run(
        [sys.executable, "-c", "import json\n" + code],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    loaded, codes = json.loads(done.stdout.strip().splitlines()[-1])
    return loaded, codes


def test_every_verb_has_an_argument_error_checked():
    _, modules = build_parser()
    assert set(ARGUMENT_ERRORS) == set(modules)


@pytest.mark.parametrize("argv", [["--help"], ["no-such-verb"], ["--no-such-flag", "x"]])
def test_help_and_a_mistyped_verb_import_none_of_the_heavy_packages(argv):
    """``studio --help`` lists the verbs from their modules' source: none is imported."""
    loaded, _ = _loaded_after(argv)
    assert loaded == []


@pytest.mark.parametrize("verb", sorted(ARGUMENT_ERRORS))
def test_a_verbs_help_and_its_usage_errors_import_none_of_the_heavy_packages(verb):
    """A verb's parser is built from light modules (its flags' defaults and choices included),
    its heavy imports wait for its run: ``studio VERB --help``, a value that is not a number and
    a missing argument answer in a fraction of a second, not after seconds of Pinocchio, numba
    and SciPy."""
    loaded, codes = _loaded_after([verb, "--help"], ARGUMENT_ERRORS[verb])
    assert codes == [0, 2]
    assert loaded == [], f"studio {verb} --help or a usage error imported {loaded}"


def test_a_flags_value_refused_by_its_own_parser_imports_none_of_the_heavy_packages():
    """``--obstacle``'s box is read by :meth:`Obstacle.parse` before any collision model loads."""
    loaded, codes = _loaded_after(*VALUE_ERRORS)
    assert codes == [2] * len(VALUE_ERRORS)
    assert loaded == []
