"""What a first run waits for: compiling the learner, and what compiling it at start saves.

Each measurement runs in a child process with an empty numba cache (``NUMBA_CACHE_DIR`` in a
temporary folder), as on a fresh install:

1. per task, compiling its kernels (``prepare_learner``): wall and CPU seconds, then loading
   them from the cache in a second process: the figures behind ``PREPARE_SECONDS``;
2. ``studio serve`` (API, scene, simulator) with and without compiling in the background at
   start: seconds until the API answers, then seconds from submitting a first arm-grid run
   until its first episode, with the page's default run submitted a few seconds after start.

Run: ``python benchmarks/bench_prepare.py`` (several minutes: every condition compiles from
scratch; ``--skip-serve`` for part 1 only). On a shared machine the wall times vary with the
other load; the CPU seconds much less.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from bench_api_load import Studio  # noqa: E402

COMPILE = """
import json, sys, time
from studio.learning._prepare import prepare_learner
kind = sys.argv[1]
wall, cpu = time.perf_counter(), time.process_time()
prepare_learner(kind)
print(json.dumps({"wall": time.perf_counter() - wall, "cpu": time.process_time() - cpu}))
"""
FIRST_RUN = {"planning": "full", "experiments": 2, "episodes": 50, "seed": 0}
SETTLE_S = 10.0
"""The user opens the page and presses Start this long after the studio is up (``--settle``)."""


def child(kind: str, cache: str) -> dict[str, float]:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    out = subprocess.run(
        [sys.executable, "-c", COMPILE, kind], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def compile_times() -> None:
    from studio.learning import TASK_KINDS

    for kind in TASK_KINDS:
        with tempfile.TemporaryDirectory(prefix="bench-prepare-") as cache:
            cold = child(kind, cache)
            warm = child(kind, cache)
        print(
            f"{kind:<10} compile {cold['wall']:6.1f} s wall {cold['cpu']:6.1f} s CPU;   "
            f"load from the cache {warm['wall']:5.2f} s wall"
        )


def first_run(background: bool, settle: float = SETTLE_S) -> tuple[float, float]:
    """Seconds until the API answers, and from submitting a first run to its first episode."""
    with (
        tempfile.TemporaryDirectory(prefix="bench-prepare-") as cache,
        tempfile.TemporaryDirectory(prefix="bench-prepare-data-") as data,
    ):
        os.environ["NUMBA_CACHE_DIR"] = cache
        try:
            t0 = time.perf_counter()
            studio = Studio(10, Path(data), background_prepare=background)
            up = time.perf_counter() - t0
            try:
                time.sleep(settle)
                t1 = time.perf_counter()
                run = studio.call("POST", "/api/runs", FIRST_RUN)
                while studio.call("GET", f"/api/runs/{run['id']}")["episodes_done"] == 0:
                    time.sleep(0.1)
                return up, time.perf_counter() - t1
            finally:
                studio.stop()
        finally:
            del os.environ["NUMBA_CACHE_DIR"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip-serve", action="store_true", help="only the compile times")
    parser.add_argument("--serve-only", action="store_true", help="only studio serve's part")
    parser.add_argument(
        "--settle", type=float, default=SETTLE_S, help="seconds from start to the first run"
    )
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    if not args.serve_only:
        compile_times()
    if args.skip_serve:
        return
    for background in (True, False):  # the machine's other load changes: report each pair
        up, first = first_run(background, args.settle)
        label = "compiled at start" if background else "compiled by the run"
        print(
            f"studio serve, {label:<19}: API up in {up:5.1f} s; a first run submitted "
            f"{args.settle:g} s later starts its first episode after {first:6.1f} s "
            f"(load average {os.getloadavg()[0]:.1f})",
            flush=True,
        )


if __name__ == "__main__":
    main()
