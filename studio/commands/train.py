"""``studio train``: train Dyna-Q on the arm grid from the terminal into a run directory.

The run directory holds ``config.json`` (everything needed to repeat the run), ``curves.csv``
(mean and spread of steps per episode), ``steps.csv`` (every experiment's steps per episode) and
``policy.policy.npz`` (the best experiment's Q table, see :mod:`studio.learning._policy`).

Settings come from ``--config FILE.json`` and/or flags (flags win). The file looks like::

    {"grid": {"joints": 3, "bins": 11, "low_deg": -180, "high_deg": 180, "goal": [5, 6, 2]},
     "config": {"planning": "full", "planning_steps": 100, "alpha": 0.1},
     "experiments": 20, "episodes": 100, "seed": 0,
     "demonstrations": [[12, 133, ...], ...]}

Demonstrations may also come from ``--demos FILE.json``: a JSON list of state lists, an object with
a ``"demonstrations"`` list, or a ``*.demo.json`` with a ``"grid_path"``; or be generated with
``--generated-demos N`` (noisy shortest-ish paths, as ``studio reproduce`` uses).
"""

from __future__ import annotations

import argparse
import csv
import json
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from studio.learning import (
    PLANNERS,
    ArmGrid,
    DynaQConfig,
    LearningError,
    LiveProgress,
    check_budget,
    generate_demonstrations,
    run_experiments,
    save_policy,
)
from studio.learning._reproduce import _percentiles, _run_with_progress

NAME = "train"
HELP = "Train Dyna-Q on the arm grid: a config in, a run directory with curves and a policy out."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--config", type=Path, help="JSON file with grid, config and run settings")
    parser.add_argument("--out", type=Path, help="run directory (default: runs/<time>-<planning>)")
    parser.add_argument("--planning", choices=PLANNERS, help="planner (default: full)")
    parser.add_argument("--planning-steps", type=int, help="planning updates per real step")
    parser.add_argument("--alpha", type=float, help="learning rate")
    parser.add_argument("--gamma", type=float, help="discount factor")
    parser.add_argument("--epsilon", type=float, help="exploration probability")
    parser.add_argument("--experiments", type=int, help="independent experiments (default: 20)")
    parser.add_argument("--episodes", type=int, help="episodes per experiment (default: 100)")
    parser.add_argument("--seed", type=int, help="random seed (default: 0)")
    parser.add_argument("--joints", type=int, help="grid joints (default: 3)")
    parser.add_argument("--bins", type=int, help="bins per joint (default: 11)")
    parser.add_argument("--goal", help="goal bins, comma-separated, e.g. 5,6,2")
    parser.add_argument("--demos", type=Path, help="JSON file of demonstrations (grid state lists)")
    parser.add_argument("--generated-demos", type=int, help="replay N generated demonstrations")
    parser.add_argument("--workers", type=int, default=None, help="threads (default: all cores)")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")


def _read_json(path: Path, what: str) -> Any:
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise LearningError(f"The {what} file {path} does not exist; check the path.") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise LearningError(
            f"The {what} file {path} is not valid JSON ({err}); fix or replace it."
        ) from None


def _demos_from(data: Any, source: str) -> list[list[int]]:
    if isinstance(data, dict):
        if "grid_path" in data:
            data = [data["grid_path"]]
        elif "demonstrations" in data:
            data = data["demonstrations"]
    if not isinstance(data, list) or not all(isinstance(d, list) for d in data):
        raise LearningError(
            f"{source} holds no demonstrations; give a list of grid state lists, or an object with 'demonstrations' or 'grid_path'."
        )
    return data


def _goal(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(v) for v in text.split(","))
    except ValueError:
        raise LearningError(
            f"--goal is {text!r}; give bin indices separated by commas, e.g. 5,6,2."
        ) from None


def run(args: argparse.Namespace) -> int:
    spec: dict[str, Any] = {}
    if args.config is not None:
        spec = _read_json(args.config, "config")
        if not isinstance(spec, dict):
            raise LearningError(
                f"The config file {args.config} holds no JSON object; give an object with 'grid' and 'config'."
            )
    grid_spec = dict(spec.get("grid", {}))
    for key in ("joints", "bins"):
        if getattr(args, key) is not None:
            grid_spec[key] = getattr(args, key)
    if args.goal is not None:
        grid_spec["goal"] = _goal(args.goal)
    if grid_spec.get("goal") is not None:
        grid_spec["goal"] = tuple(grid_spec["goal"])
    try:
        grid = ArmGrid(**grid_spec)
    except TypeError as err:
        raise LearningError(
            f"The grid settings are wrong ({err}); use joints, bins, low_deg, high_deg and goal."
        ) from None
    config_spec = {"planning": "full", **spec.get("config", {})}
    for key in ("planning", "planning_steps", "alpha", "gamma", "epsilon"):
        if getattr(args, key) is not None:
            config_spec[key] = getattr(args, key)
    config = DynaQConfig.from_dict(config_spec)
    experiments = args.experiments if args.experiments is not None else spec.get("experiments", 20)
    episodes = args.episodes if args.episodes is not None else spec.get("episodes", 100)
    seed = args.seed if args.seed is not None else spec.get("seed", 0)
    demos = (
        _demos_from(spec["demonstrations"], str(args.config)) if "demonstrations" in spec else []
    )
    if args.demos is not None:
        demos = _demos_from(_read_json(args.demos, "demonstrations"), str(args.demos))
    if args.generated_demos:
        demos = generate_demonstrations(
            grid, args.generated_demos, np.random.default_rng([seed, 1])
        )

    check_budget(experiments, episodes, grid.n_states, grid.n_actions)
    out = args.out or Path("runs") / f"{datetime.now(UTC):%Y%m%d-%H%M%S}-{config.planning}"
    live = LiveProgress(experiments, episodes)
    bar = None
    if not args.no_progress:
        from tqdm import tqdm

        bar = tqdm(total=live.total, unit="episode", desc="train")
    start = time.perf_counter()
    try:
        result = _run_with_progress(
            lambda live: run_experiments(
                grid.mdp(),
                config,
                experiments,
                episodes,
                seed,
                demos,
                workers=args.workers,
                live=live,
            ),
            live,
            bar,
        )
    finally:
        if bar is not None:
            bar.close()
    wall = time.perf_counter() - start

    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise LearningError(
            f"Cannot create the run directory {out} ({err.strerror}); choose another --out."
        ) from None
    record = {
        "grid": grid.to_dict(),
        "config": config.to_dict(),
        "experiments": experiments,
        "episodes": episodes,
        "seed": seed,
        "demonstrations": demos,
    }
    (out / "config.json").write_text(json.dumps(record, indent=1))
    stats = _percentiles(result.steps)
    with (out / "curves.csv").open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["episode", "mean", "std", "median", "p10", "p90"])
        for k in range(episodes):
            writer.writerow(
                [
                    k + 1,
                    *(f"{stats[key][k]:.6g}" for key in ("mean", "std", "median", "p10", "p90")),
                ]
            )
    np.savetxt(
        out / "steps.csv",
        result.steps,
        fmt="%d",
        delimiter=",",
        header="steps per episode; one row per experiment",
    )
    best = result.best_experiment()
    save_policy(
        out / "policy.policy.npz",
        grid,
        result.q[best],
        config,
        result.mean_steps(),
        experiments=experiments,
        notes=f"experiment {best} of {experiments}, seed {seed}, {len(demos)} demonstrations",
    )
    mean = result.mean_steps()
    print(
        f"Trained {experiments} x {episodes} episodes ({config.planning} planning) in {wall:.2f} s "
        f"({result.cpu_seconds.sum():.2f} CPU s): mean steps {mean[0]:.0f} in episode 1, "
        f"{mean[-1]:.1f} in episode {episodes}."
    )
    print(f"Wrote config.json, curves.csv, steps.csv and policy.policy.npz to {out}/")
    return 0
