"""Linear Dyna-Q speed: the compiled kernel against a plain-Python semi-gradient baseline.

Measures, in one run (``python benchmarks/bench_tiles.py``, about 20-40 s on one free core):

1. Gymnasium's ``MountainCar-v0`` (``max_episode_steps`` raised to 100 000), 500 episodes,
   ``TileCoding(tilings=8, tiles=8)``, zero planning, alpha 0.5 (0.5 / 8 per tiling), gamma 1,
   epsilon 0 (Sutton & Barto, section 10.1): our CPU time (the whole experiment, and the kernel
   alone without the 500 ``env.reset`` calls that draw the starts) against the CPU time of
   ``tiles_reference.py`` (plain Python, Gymnasium's own ``step``, the same features and the same
   random draws). Both runs take exactly the same steps (checked), so the ratio compares equal work.
   Goal: well under one second of kernel time.
2. The same with full planning (5 model updates per real step), 100 episodes.
3. The arm task: real steps per CPU second for six joints with the default per-joint tilings.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import gymnasium
import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from tiles_reference import Tiles  # noqa: E402
from tiles_reference import run_experiment as reference_experiment  # noqa: E402

from studio.learning import ArmReach, DynaQConfig, TileCoding, run_experiments  # noqa: E402
from studio.learning._learner import experiment_seed  # noqa: E402
from studio.learning.linear._env import reset_seed  # noqa: E402

EPISODES = 500
SEED = 0
MOUNTAIN_CAR = dict(alpha=0.5, gamma=1.0, epsilon=0.0)


def mountain_car() -> gymnasium.Env:
    return gymnasium.make("MountainCar-v0", max_episode_steps=100_000)


def reset_cpu(episodes: int) -> float:
    """CPU seconds of the ``env.reset`` calls a run makes to draw its starts."""
    env = mountain_car()
    start = time.thread_time()
    for k in range(episodes):
        env.reset(seed=reset_seed(SEED, 0) if k == 0 else None)
    return time.thread_time() - start


def compare(planning: str, planning_steps: int, episodes: int) -> None:
    config = DynaQConfig(**MOUNTAIN_CAR, planning=planning, planning_steps=planning_steps)
    coding = TileCoding(tilings=8, tiles=8)
    run_experiments(mountain_car, config, 1, 2, SEED, features=coding)  # load the cached kernel
    ours = min(
        (run_experiments(mountain_car, config, 1, episodes, SEED, features=coding, workers=1)
         for _ in range(3)),
        key=lambda r: float(r.cpu_seconds[0]),
    )  # fmt: skip
    resets = min(reset_cpu(episodes) for _ in range(3))
    env = mountain_car()
    space = env.observation_space
    tiles = Tiles(
        [float(x) for x in space.low],
        [float(x) for x in space.high],
        8,
        8,
        [[0, 1]],
        ours.coder.size,
    )
    _, steps, ref_cpu = reference_experiment(
        env, tiles, 3, episodes=episodes, rng=int(experiment_seed(SEED, 0)),
        reset_seed=reset_seed(SEED, 0), alpha=config.alpha, gamma=config.gamma,
        epsilon=config.epsilon, planning=planning, planning_steps=planning_steps,
    )  # fmt: skip
    same = ours.steps[0].tolist() == steps
    cpu = float(ours.cpu_seconds[0])
    kernel = max(cpu - resets, 1e-9)
    real = int(ours.steps.sum())
    print(
        f"MountainCar-v0 {planning} planning ({planning_steps}/step), {episodes} episodes, "
        f"{real:,} real steps, {int(ours.updates.sum()):,} updates; same steps as the reference: {same}"
    )
    print(
        f"  ours: {cpu:.3f} s CPU ({kernel:.3f} s kernel + {resets:.3f} s env.reset)   "
        f"plain Python: {ref_cpu:.2f} s CPU   ratio {ref_cpu / cpu:.0f}x (kernel alone {ref_cpu / kernel:.0f}x)"
    )
    print(f"  first/last 10 episodes: {np.mean(steps[:10]):.0f} / {np.mean(steps[-10:]):.0f} steps")


def arm_speed() -> None:
    task = ArmReach(joints=6)
    rng = np.random.default_rng(1)
    demos = [np.linspace(task.random_start(rng), task.goal, 60) for _ in range(3)]
    config = DynaQConfig(planning="zero", max_steps_per_episode=3000)
    make = lambda: gymnasium.make("TeachStudio/ArmReach-v0", joints=6)  # noqa: E731
    run_experiments(make, config, 1, 4, SEED, demonstrations=demos, features=task.features())
    result = run_experiments(
        make, config, 1, 300, SEED, demonstrations=demos, features=task.features(), workers=1
    )
    real = int(result.steps.sum())
    print(
        f"ArmReach six joints, per-joint tilings ({result.coder.n_active} active of {result.coder.size:,} rows "
        f"x {task.n_actions} actions): {real:,} real steps in {result.cpu_seconds[0]:.2f} s CPU = "
        f"{real / result.cpu_seconds[0] / 1e6:.2f} M steps/s"
    )


def main() -> None:
    compare("zero", 0, EPISODES)
    compare("full", 5, 100)
    arm_speed()


if __name__ == "__main__":
    main()
