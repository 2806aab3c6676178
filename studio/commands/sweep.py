"""``studio sweep``: run a parameter sweep on Ray Tune, each trial an ordinary run.

``studio sweep SPEC.toml`` reads a sweep spec (``docs/sweeps.md``; an example is
``sweeps/planning.toml``), runs its trials on a local Ray using this machine's cores (or on an
existing cluster with ``--address auto|HOST:PORT``) and writes every trial as a run under
``<data>/runs/<sweep>/`` and the summary (``sweep.csv``, ``sweep.png``/``.svg``) under
``<data>/sweeps/<sweep>/``. Ctrl-C stops cleanly; ``studio sweep --resume [SWEEP]`` runs only the
trials that did not finish. Needs the cluster extra: ``pip install -e '.[cluster]'``.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from studio.learning import SweepProgress, SweepSpec

NAME = "sweep"
HELP = "Run a parameter sweep (a TOML spec) on Ray Tune; each trial is an ordinary run."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "spec",
        nargs="?",
        help="the sweep spec (.toml); with --resume, a spec or a sweep id (default: the latest unfinished)",
    )
    parser.add_argument(
        "--resume", action="store_true", help="continue a sweep: run only unfinished trials"
    )
    parser.add_argument("--name", help="sweep id (default: the spec's name, else its file name)")
    parser.add_argument(
        "--data-dir", type=Path, default=Path("."), help="where runs/ and sweeps/ live"
    )
    parser.add_argument(
        "--address", help="an existing Ray cluster: auto or HOST:PORT (default: a local Ray)"
    )
    parser.add_argument(
        "--workers", type=int, help="local Ray: cores to use (default: all of this machine's)"
    )
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")


def _spec(args: argparse.Namespace) -> SweepSpec:
    from studio.learning import SweepError, load_sweep_spec, resume_target

    if args.spec is None:
        if not args.resume:
            raise SweepError(
                "No sweep spec given; give a spec file (studio sweep sweeps/planning.toml) or --resume."
            )
        return resume_target(args.data_dir, None)
    path = Path(args.spec)
    if args.resume and not path.is_file() and path.suffix != ".toml":
        return resume_target(args.data_dir, args.spec)
    return load_sweep_spec(path, name=args.name)


def run(args: argparse.Namespace) -> int:
    # imported here, not with the flags: `studio sweep --help` and a mistyped flag stay fast
    from studio.learning import run_sweep

    spec = _spec(args)
    bar = None
    if not args.no_progress:
        from tqdm import tqdm

        bar = tqdm(total=len(spec.trials()), unit="trial", desc=f"sweep {spec.name}")

    def show(progress: SweepProgress) -> None:
        if bar is None:
            return
        bar.update(progress.done - bar.n)
        best = f"{progress.best[0]:.4g} ({progress.best[1]})" if progress.best else "-"
        bar.set_postfix_str(
            f"running {progress.running}, failed {progress.failed}, best {spec.metric} {best}"
        )

    try:
        result = run_sweep(
            spec,
            args.data_dir,
            address=args.address,
            workers=args.workers,
            resume=args.resume,
            on_progress=show,
        )
    finally:
        if bar is not None:
            bar.close()
    finished = sum(row["status"] in ("done", "early-stopped") for row in result.rows)
    print(
        f"Sweep {spec.name}: {finished} of {len(result.rows)} trials finished "
        f"({len(result.ran)} now, {len(result.failed)} failed); "
        f"wrote sweep.csv and sweep.png to {result.folder}/ and the runs to "
        f"{Path(args.data_dir) / 'runs' / spec.name}/"
    )
    if result.interrupted:
        print(f"Interrupted: continue with studio sweep --resume {spec.name}")
        return 130
    return 1 if result.failed else 0
