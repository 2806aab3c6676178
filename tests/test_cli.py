from __future__ import annotations

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
    from pathlib import Path

    sample = Path(__file__).resolve().parents[1] / "recordings" / "sample-reach-1.tape.csv"
    cmd = [sys.executable, "-m", "studio", "info", *[str(sample)] * 400]  # more than a pipe holds
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # the reader is gone before the first line
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 0 and b"Traceback" not in err, err.decode()
