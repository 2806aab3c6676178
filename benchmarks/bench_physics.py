"""The shipped samples exported as a new user would, replayed in physics on each robot.

For each robot and each shipped demonstration this runs ``studio export sample-reach-N --robot R
--format csv`` (as the README shows; where the safety checks refuse it, the same with
``--unchecked``, and the table says so), then ``studio simulate FILE --robot R --json``, and
prints whether the motion completed, the largest tool tracking error, the samples where a motor
saturated and the contacts; with ``--recordings`` the samples' recordings too, exported at
their capture times (``--unchecked``: the person's own pace, which no check passes today).
It also prints the replay's speed against real time (the motion's duration over the
``studio simulate`` call's wall time; a robot's first row includes building its MuJoCo model).

Run: ``python benchmarks/bench_physics.py`` (the Panda and the UR5, a minute or two once their
models are kept), ``--robots all`` for every robot (several minutes), ``--recordings`` to add
the recordings. Files and caches go to a temporary folder.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import tempfile
import time
from pathlib import Path

from studio.cli import main
from studio.kinematics import robot_names


def _quiet(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def one(source: str, robot: str, folder: Path, unchecked: bool) -> dict[str, object]:
    """Export ``source`` for ``robot`` and simulate the file; the report and how it went."""
    out = folder / f"{source}.{robot}.csv"
    export = ["export", source, "--robot", robot, "--format", "csv", "--out", str(out)]
    export += ["--data-dir", str(folder)]
    code, _, _ = _quiet([*export, "--unchecked"] if unchecked else export)
    refused = code != 0
    if refused:
        _quiet([*export, "--unchecked"])
    started = time.perf_counter()
    code, printed, err = _quiet(
        ["simulate", str(out), "--robot", robot, "--json", "--data-dir", str(folder)]
    )
    elapsed = time.perf_counter() - started
    if code != 0:
        return {"error": err.strip()}
    rows = [line for line in out.read_text().splitlines() if line and not line.startswith("#")]
    duration = float(rows[-1].split(",")[0])
    return {**json.loads(printed), "refused": refused, "duration": duration, "elapsed": elapsed}


def main_bench() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default="panda,ur5", help="comma-separated, or all")
    parser.add_argument("--recordings", action="store_true", help="the recordings too")
    args = parser.parse_args()
    robots = robot_names() if args.robots == "all" else args.robots.split(",")
    sources = [(f"sample-reach-{n}", False) for n in (1, 2, 3)]
    if args.recordings:
        sources += [(f"sample-reach-{n}.tape.csv", True) for n in (1, 2, 3)]
    print(
        f"{'robot':8} {'source':26} {'completed':>9} {'tool err mm':>11} {'saturated':>9} "
        f"{'contacts':>8} {'speed x real time':>17}"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for robot in robots:
            for source, unchecked in sources:
                r = one(source, robot, Path(tmp), unchecked)
                if "error" in r:
                    print(f"{robot:8} {source:26} {r['error']}")
                    continue
                mark = " (unchecked)" if unchecked else " (refused)" if r["refused"] else ""
                print(
                    f"{robot:8} {source + mark:26} {str(r['completed']):>9} "
                    f"{r['max_tool_error_m'] * 1000:11.2f} {r['saturated_samples']:9d} "
                    f"{len(r['contacts']):8d} {r['duration'] / r['elapsed']:17.1f}"
                )


if __name__ == "__main__":
    main_bench()
