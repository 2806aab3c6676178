"""``studio reproduce --beyond``: the paper's curse-of-dimensionality discussion, measured.

For J = 3 to 6 joints of the continuous arm task (:class:`ArmReach`) it compares

- the memory of a tabular Q at the paper's resolution (11 bins per joint, 3**J actions) and at
  the continuous task's resolution (one bin per joint step, 2J actions), against the tile-coded
  weight table that learns the task (:meth:`ArmReach.features`);
- learning: linear Dyna-Q (zero planning, the paper's alpha, gamma, epsilon) with
  :data:`BEYOND_DEMONSTRATIONS` demonstrations, trained for each budget in
  :data:`BEYOND_EPISODES`; after each, the greedy policy of every experiment is rolled out from
  :data:`BEYOND_STARTS` random starts. Reported: the CPU time of the smallest budget whose mean
  greedy success reaches :data:`BEYOND_SUCCESS` (or that none did), the final success rate with its
  spread over experiments, and the first episode the agent reached the goal on its own (and its
  length) with and without demonstrations (the paper's supervision claim in continuous space).

Each budget is a fresh run from zero weights (runs are deterministic, so a budget's numbers do not
depend on the others); the CPU time is the mean over experiments of the training threads' time.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TypedDict

import gymnasium
import numpy as np

from .._config import DynaQConfig
from ..linear._linear import LinearResult, greedy_success
from ..tasks._gym import ARM_REACH_ID
from ..tasks._gym_ids import DEFAULT_MAX_EPISODE_STEPS
from ..tasks._reach import ArmReach

BEYOND_JOINTS = (3, 4, 5, 6)
"""Joint counts compared."""
BEYOND_EXPERIMENTS = 2
"""Experiments per budget (the spread is over them)."""
BEYOND_EPISODES = (1_000, 4_000, 16_000)
"""Training budgets, episodes per experiment."""
BEYOND_DEMONSTRATIONS = 3
"""Demonstrations replayed first: straight joint-space paths from random starts to the goal."""
BEYOND_DEMO_SAMPLES = 60
"""Samples per generated demonstration path."""
BEYOND_STARTS = 200
"""Random starts the greedy policy is judged from."""
BEYOND_SUCCESS = 0.95
"""The issue's goal: the greedy policy reaches the goal from this share of random starts."""
PAPER_BINS = 11
"""The paper's bins per joint."""


class Budget(TypedDict):
    """One episode budget's measurement for a joint count."""

    episodes: int
    cpu_seconds: float
    success: list[float]  # per experiment: the greedy policy's share of starts reaching the goal
    first_own_success: list[list[int] | None]


class JointsRow(TypedDict):
    """What :func:`measure` found for one joint count (one row of the report)."""

    joints: int
    memory: dict[str, float]
    budgets: list[Budget]
    time_to_goal: float | None
    first_own_success_without_demos: list[list[int] | None]


def demonstration_paths(task: ArmReach, count: int, rng: np.random.Generator) -> list[np.ndarray]:
    """``count`` straight joint paths from random starts to the goal, ``(samples, joints)``."""
    goal = np.asarray(task.goal[: task.joints])
    return [np.linspace(task.random_start(rng), goal, BEYOND_DEMO_SAMPLES) for _ in range(count)]


def memory_row(task: ArmReach) -> dict[str, float]:
    """Table sizes (entries) and bytes: tabular at the paper's and the task's resolution, tiles."""
    joints = task.joints
    paper = PAPER_BINS**joints * 3**joints
    bins = [
        math.ceil((hi - lo) / task.step) + 1 for lo, hi in zip(task.lower, task.upper, strict=True)
    ]
    fine = math.prod(bins) * task.n_actions
    coder = task.features().bind(task.lower, task.upper)
    tiles = coder.size * task.n_actions
    return {
        "paper_entries": paper,
        "paper_bytes": 8.0 * paper,
        "fine_entries": float(fine),
        "fine_bytes": 8.0 * fine,
        "tile_entries": tiles,
        "tile_bytes": 8.0 * tiles,
        "active": coder.n_active,
    }


def _first_own_success(steps: np.ndarray, demos: int, cap: int) -> list[list[int] | None]:
    """Per experiment: ``[own episode (1-based), steps]`` of the agent's first successful
    episode of its own, or None.

    Own episodes are counted from the first one after the demonstrations, so runs with and
    without demonstrations compare on the same scale (counting the replayed episodes too made
    the first own success of a supervised run come "later" by construction)."""
    out: list[list[int] | None] = []
    for row in steps:
        own = np.flatnonzero((row[demos:] >= 0) & (row[demos:] < cap))
        out.append([int(own[0]) + 1, int(row[demos + own[0]])] if own.size else None)
    return out


def measure(
    joints: int,
    seed: int,
    episodes: Sequence[int] = BEYOND_EPISODES,
    experiments: int = BEYOND_EXPERIMENTS,
    workers: int | None = None,
    run: Callable[..., LinearResult] | None = None,
) -> JointsRow:
    """Learn the J-joint task for each budget and judge the greedy policies (see the module)."""
    from .._experiments import run_experiments

    run = run or run_experiments
    task = ArmReach(joints=joints)
    rng = np.random.default_rng([seed, joints])
    demos = demonstration_paths(task, BEYOND_DEMONSTRATIONS, rng)
    starts = np.array([task.random_start(rng) for _ in range(BEYOND_STARTS)])
    config = DynaQConfig(planning="zero")
    cap = DEFAULT_MAX_EPISODE_STEPS
    make = lambda: gymnasium.make(ARM_REACH_ID, joints=joints)  # noqa: E731
    budgets: list[Budget] = []
    for n in episodes:
        result = run(make, config, experiments, n, seed, demos, task.features(), workers=workers)
        success = [
            float(greedy_success(result.task, result.coder, w, starts, cap).mean())
            for w in result.weights
        ]
        budgets.append(
            {
                "episodes": int(n),
                "cpu_seconds": float(np.mean(result.cpu_seconds)),
                "success": success,
                "first_own_success": _first_own_success(result.steps, len(demos), cap),
            }
        )
    bare = run(make, config, experiments, min(episodes), seed, [], task.features(), workers=workers)
    reached = next((b for b in budgets if np.mean(b["success"]) >= BEYOND_SUCCESS), None)
    return {
        "joints": joints,
        "memory": memory_row(task),
        "budgets": budgets,
        "time_to_goal": None if reached is None else reached["cpu_seconds"],
        "first_own_success_without_demos": _first_own_success(bare.steps, 0, cap),
    }


def _size(n: float) -> str:
    for unit, scale in (
        ("EB", 1e18),
        ("PB", 1e15),
        ("TB", 1e12),
        ("GB", 1e9),
        ("MB", 1e6),
        ("kB", 1e3),
    ):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} B"


def _spread(values: Sequence[float]) -> str:
    a = np.asarray(values, dtype=float)
    return f"{100 * a.mean():.0f}% (experiments {', '.join(f'{100 * v:.0f}%' for v in a)})"


def _firsts(values: Sequence[list[int] | None]) -> str:
    return ", ".join("never" if v is None else f"{v[0]}: {v[1]}" for v in values)


def report_section(rows: Sequence[JointsRow]) -> str:
    """The REPORT.md section of :func:`beyond_the_paper`'s measurements."""
    lines = [
        "\n## Beyond the paper: continuous joints with tile coding (the curse of dimensionality, measured)\n",
        "Linear Dyna-Q (zero planning, alpha 0.1, gamma 0.95, epsilon 0.1) on `TeachStudio/ArmReach-v0` "
        f"(2-degree joint steps, one joint per action; success: tool within 2 cm and 10 deg), "
        f"{BEYOND_DEMONSTRATIONS} demonstrations, {BEYOND_EXPERIMENTS} experiments per budget, greedy "
        f"success over {BEYOND_STARTS} random starts across the joint limits.\n",
        "| joints | tabular, paper's 11 bins | tabular, 2-degree bins | tile coding (pairs) | "
        "CPU s to 95% greedy success | final greedy success | first own success (own episode: steps), with demos / without |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        m, last = row["memory"], row["budgets"][-1]
        goal = (
            f"{row['time_to_goal']:.1f}"
            if row["time_to_goal"] is not None
            else f"not reached in {last['episodes']:,} episodes ({last['cpu_seconds']:.1f} s)"
        )
        firsts = _firsts(last["first_own_success"])
        bare = _firsts(row["first_own_success_without_demos"])
        lines.append(
            f"| {row['joints']} | {m['paper_entries']:,.0f} entries, {_size(m['paper_bytes'])} | "
            f"{m['fine_entries']:.2g} entries, {_size(m['fine_bytes'])} | "
            f"{m['tile_entries']:,.0f} weights, {_size(m['tile_bytes'])} | {goal} | "
            f"{_spread(last['success'])} after {last['episodes']:,} episodes | {firsts} / {bare} |"
        )
    lines.append(
        "\nPer budget (episodes: mean CPU s per experiment, greedy success per experiment):\n"
    )
    for row in rows:
        parts = [
            f"{b['episodes']:,}: {b['cpu_seconds']:.1f} s, {_spread(b['success'])}"
            for b in row["budgets"]
        ]
        lines.append(f"- {row['joints']} joints: " + "; ".join(parts))
    return "\n".join(lines) + "\n"


def figure(rows: Sequence[JointsRow], out_dir: Path) -> list[Path]:
    """``beyond.png``/``.svg``: greedy success against CPU seconds per joint count, and memory."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 4), dpi=120, layout="constrained")
    ax, mem = fig.subplots(1, 2)
    for row in rows:
        cpu = [b["cpu_seconds"] for b in row["budgets"]]
        success = np.array([b["success"] for b in row["budgets"]])
        (line,) = ax.plot(
            cpu, 100 * success.mean(axis=1), marker="o", label=f"{row['joints']} joints"
        )
        ax.fill_between(
            cpu,
            100 * success.min(axis=1),
            100 * success.max(axis=1),
            alpha=0.2,
            color=line.get_color(),
        )
    ax.axhline(100 * BEYOND_SUCCESS, ls=":", color="grey")
    ax.set_xscale("log")
    ax.set_xlabel("CPU seconds per experiment")
    ax.set_ylabel("greedy success from random starts (%)")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    j = [row["joints"] for row in rows]
    for key, label in (
        ("paper_bytes", "tabular, 11 bins"),
        ("fine_bytes", "tabular, 2-degree bins"),
        ("tile_bytes", "tile coding"),
    ):
        mem.plot(j, [row["memory"][key] for row in rows], marker="o", label=label)
    mem.set_yscale("log")
    mem.set_xlabel("joints")
    mem.set_ylabel("table bytes")
    mem.set_xticks(j)
    mem.legend(fontsize="small")
    mem.grid(alpha=0.3)
    paths = []
    for fmt in ("png", "svg"):
        path = Path(out_dir) / f"beyond.{fmt}"
        fig.savefig(path, format=fmt)
        paths.append(path)
    return paths


def beyond_the_paper(
    out_dir: str | Path,
    seed: int,
    joints: Sequence[int] = BEYOND_JOINTS,
    episodes: Sequence[int] = BEYOND_EPISODES,
    experiments: int = BEYOND_EXPERIMENTS,
    workers: int | None = None,
) -> tuple[str, list[Path], list[JointsRow]]:
    """Measure every joint count; returns the REPORT.md section, the figure files and the rows.

    A one-episode run first loads (or compiles) the kernels, so no budget's CPU time counts it.
    """
    measure(min(joints), seed, (1,), 1, workers)
    rows = [measure(j, seed, episodes, experiments, workers) for j in joints]
    return report_section(rows), figure(rows, Path(out_dir)), rows
