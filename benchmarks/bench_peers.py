"""Real steps and CPU to 95% greedy success: the studio's learner against Stable-Baselines3.

``python benchmarks/bench_peers.py [--joints 3 6] [--seeds 3] [--budget STEPS] [--quick]
[--stop-at-target] [--learners NAME ...] [--first-seed K]``

Every learner trains on ``TeachStudio/ArmReach-v0`` with the environment's defaults (one joint per
action, the default shaping, the episode cap of 3,000 steps) and is judged the same way: every
``RHYTHM[joints]`` real steps (1,000 at 3 joints, 5,000 at 6) its greedy policy is rolled out from
the same 200 held-out random starts (``default_rng([7, joints])``, as ``bench_actions.py``), at most
3,000 steps each. A row gives, per learner and over the seeds (mean and the seeds' values):

- **steps to 95%**: the real environment steps when greedy success first reaches >= 95% (a seed
  that never does counts as missing, shown as ``-``);
- **CPU to 95%**: the process CPU seconds (``time.process_time``) spent learning until then,
  the evaluations left out;
- **final**: greedy success at the end of the budget (with ``--stop-at-target``, which ends each
  run at its first evaluation at >= 95% to save CPU, at that evaluation).

The learners:

- **studio** through the public API: ``run_experiments(env, DynaQConfig(), ...)`` with
  ``ArmReach(joints).features()``, the defaults the studio trains the arm task with (no
  demonstrations: a run has none unless a person gives them), plus ``planning="zero"`` and
  ``planning_steps=10`` for reference, and the default learner on a wider tile coding (32 tilings
  of 8 tiles per joint instead of 8 of 32: tiles four times wider, the same resolution), the
  setting that wins at 3 joints. To evaluate it mid-run the environment is wrapped, so the
  learner steps it from Python; that loop learns exactly as the compiled kernel does (asserted
  here: the per-episode steps match), and the CPU figure is the compiled kernel's, re-run to the
  episode where 95% was reached and prorated to the step.
- **studio taught by 3 demonstrations** (``STUDIO_DEMOS``): the same learner given
  ``bench_demos.py``'s 3 straight demonstrations of the seed first, its default actions following
  them, judged on compiled runs cut at each checkpoint (:func:`studio_demos_trace`); the
  demonstrations' steps count as real steps. With the defaults, and with 30 or 10 planning steps
  (with demonstrations, fewer planning steps take fewer real steps at 3 joints).
- **SB3 DQN and PPO** (``pip install -e .[peers]``), one torch thread, observations rescaled to
  [-1, 1] (the same box the studio's tile coder is given). Settings from the RL Zoo's tuned
  hyperparameters for discrete-action classic-control tasks (``rl-baselines3-zoo/hyperparams``,
  ``dqn.yml`` and ``ppo.yml``): DQN as tuned for MountainCar-v0 (a reach-the-goal task with -1 a
  step; the best peer here) and for Acrobot-v1; PPO as tuned for CartPole-v1 and as given for
  Acrobot-v1 (with ``VecNormalize``). ``exploration_fraction`` is a share of the budget, as in
  the Zoo's ``n_timesteps``.

Seeds are paired: seed ``s`` is the studio's ``run_experiments`` seed and SB3's ``seed``. The
closing lines compare the studio's defaults with the best peer (fewest mean steps to 95%) per
joint count: the steps ratio (goal < 1) and the CPU ratio (goal >= 10).

Without SB3 installed it measures the studio side only and says how to install the extra.
``--quick`` runs 6,000 steps at 3 joints, one seed, the studio's defaults and the wider tilings.
``--learners`` keeps the rows whose names contain any of the words given (``--learners "studio
defaults" "DQN (zoo MountainCar)"``); ``--first-seed`` lets seeds run in separate processes.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import gymnasium
import numpy as np
from numba import njit

from studio.learning import (
    MAX_EPISODES,
    ArmReach,
    DynaQConfig,
    LiveProgress,
    greedy_rollout,
    run_experiments,
)
from studio.learning.linear._linear import greedy_success
from studio.learning.tasks._gym import ARM_REACH_ID
from studio.learning.tasks._reach import reach_step

STARTS = 200
CAP = 3_000
SUCCESS = 0.95
RHYTHM = {3: 1_000, 6: 5_000}
"""Real steps between two evaluations of the greedy policy."""
BUDGET = {3: 150_000, 6: 300_000}
"""Real steps each learner trains for (default)."""
QUICK_BUDGET = 6_000
INSTALL = 'pip install -e ".[peers]"'

WIDE_TILES = {"tilings": 32, "tiles": 8}
"""Wider tiles, more of them: the tile coding that won at 3 joints (see the docstring)."""
STUDIO: dict[str, tuple[DynaQConfig, dict | None]] = {
    "studio defaults": (DynaQConfig(), None),
    "studio, 10 planning steps": (DynaQConfig(planning_steps=10), None),
    "studio, no planning": (DynaQConfig(planning="zero"), None),
    "studio, 32 tilings x 8 tiles": (DynaQConfig(), WIDE_TILES),
    "studio, 32 tilings x 8 tiles, 30 planning steps": (DynaQConfig(planning_steps=30), WIDE_TILES),
}
STUDIO_DEMOS: dict[str, DynaQConfig] = {
    "studio defaults, 3 demonstrations": DynaQConfig(),
    "studio, 10 planning steps, 3 demonstrations": DynaQConfig(planning_steps=10),
    "studio, 30 planning steps, 3 demonstrations": DynaQConfig(planning_steps=30),
}
"""Taught by demonstrations first (:func:`studio_demos_trace`); the peers get none."""


@dataclass(frozen=True)
class Peer:
    """One Stable-Baselines3 setting."""

    algo: str  # "DQN" or "PPO"
    source: str
    kwargs: dict
    n_envs: int = 1
    normalize: bool = False


# fmt: off
PEERS = {
    "SB3 DQN (zoo MountainCar)": Peer("DQN", "rl-zoo dqn.yml MountainCar-v0 (tuned)", dict(
        learning_rate=4e-3, batch_size=128, buffer_size=10_000, learning_starts=1_000, gamma=0.98,
        target_update_interval=600, train_freq=16, gradient_steps=8, exploration_fraction=0.2,
        exploration_final_eps=0.07, policy_kwargs=dict(net_arch=[256, 256]))),
    "SB3 DQN (zoo Acrobot)": Peer("DQN", "rl-zoo dqn.yml Acrobot-v1 (tuned)", dict(
        learning_rate=6.3e-4, batch_size=128, buffer_size=50_000, learning_starts=0, gamma=0.99,
        target_update_interval=250, train_freq=4, gradient_steps=-1, exploration_fraction=0.12,
        exploration_final_eps=0.1, policy_kwargs=dict(net_arch=[256, 256]))),
    "SB3 PPO (zoo CartPole)": Peer("PPO", "rl-zoo ppo.yml CartPole-v1 (tuned)", dict(
        n_steps=32, batch_size=256, gae_lambda=0.8, gamma=0.98, n_epochs=20, ent_coef=0.0,
        learning_rate="lin_0.001", clip_range="lin_0.2"), n_envs=8),
    "SB3 PPO (zoo Acrobot)": Peer("PPO", "rl-zoo ppo.yml Acrobot-v1", dict(
        n_steps=256, gae_lambda=0.94, gamma=0.99, n_epochs=4, ent_coef=0.0), n_envs=16,
        normalize=True),
}
# fmt: on


@dataclass
class Trace:
    """One learner's run: greedy success at each evaluation, and CPU to the first 95%."""

    steps: list[int] = field(default_factory=list)
    success: list[float] = field(default_factory=list)
    cpu: list[float] = field(default_factory=list)  # learning CPU seconds at each evaluation

    def first(self) -> int | None:
        """Index of the first evaluation at >= 95%, or None."""
        return next((i for i, s in enumerate(self.success) if s >= SUCCESS), None)


def progress(who: str, trace: Trace) -> None:
    """The latest evaluation, on stderr (long runs on a loaded machine)."""
    cpu = f", {trace.cpu[-1]:.1f} s CPU" if trace.cpu else ""
    print(
        f"  {who}: {trace.steps[-1]:,} steps, success {trace.success[-1]:.3f}{cpu}", file=sys.stderr
    )


def held_out_starts(joints: int) -> np.ndarray:
    task = ArmReach(joints=joints)
    rng = np.random.default_rng([7, joints])
    return np.array([task.random_start(rng) for _ in range(STARTS)])


# ---------------------------------------------------------------------------------------- studio


class _Every(gymnasium.Wrapper):
    """Calls ``tick(n)`` before the step that follows ``n`` learnt real steps, ``n`` a multiple of
    ``rhythm``, and ends the last episode at ``budget`` steps or when ``tick`` returns True
    (stopping ``live``)."""

    def __init__(self, env, rhythm: int, budget: int, tick: Callable[[int], bool], live):
        super().__init__(env)
        self.rhythm, self.budget, self.tick, self.live, self.count = rhythm, budget, tick, live, 0

    def step(self, action):
        if self.count and self.count % self.rhythm == 0 and self.tick(self.count):
            self.budget = self.count + 1
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.count += 1
        if self.count >= self.budget:
            self.live.stop()
            truncated = True
        return obs, reward, terminated, truncated, info


def studio_trace(
    joints: int,
    config: DynaQConfig,
    seed: int,
    budget: int,
    coding: dict | None = None,
    stop_at_target: bool = False,
) -> Trace:
    """The studio's learner, its greedy success every ``RHYTHM[joints]`` steps; ``coding``:
    the tile coding's ``tilings`` and ``tiles`` when not the task's defaults."""
    task = ArmReach(joints=joints)
    starts = held_out_starts(joints)
    features = task.features(**(coding or {}))
    live = LiveProgress(1, MAX_EPISODES)
    trace = Trace()

    def success(weights: np.ndarray, coder) -> float:
        return float(np.mean([greedy_rollout(task, coder, weights, s, CAP)[1] for s in starts]))

    def tick(n: int) -> bool:
        assert live.snapshot is not None
        now = live.snapshot()
        trace.steps.append(n)
        trace.success.append(success(now.weights[0], now.coder))
        progress(f"studio seed {seed}", trace)
        return stop_at_target and trace.success[-1] >= SUCCESS

    def make() -> gymnasium.Env:
        return _Every(
            gymnasium.make(ARM_REACH_ID, joints=joints), RHYTHM[joints], budget, tick, live
        )

    result = run_experiments(
        make, config, 1, MAX_EPISODES, seed, features=features, workers=1, live=live
    )
    steps = result.steps[0][result.steps[0] >= 0]
    trace.steps.append(int(steps.sum()))
    trace.success.append(success(result.weights[0], result.coder))
    hit = trace.first()
    if hit is not None:  # CPU: the compiled kernel, to the end of the episode of the hit
        episodes = int(np.searchsorted(np.cumsum(steps), trace.steps[hit])) + 1
        make_plain = lambda: gymnasium.make(ARM_REACH_ID, joints=joints)  # noqa: E731
        cpu = time.process_time()
        again = run_experiments(make_plain, config, 1, episodes, seed, features=features, workers=1)
        cpu = time.process_time() - cpu
        compiled = again.steps[0]
        # the budget may have cut the Python loop's last episode short
        same = np.array_equal(compiled[:-1], steps[: episodes - 1])
        if not same or compiled[-1] < steps[episodes - 1]:
            raise AssertionError("the compiled kernel and the Python loop learnt differently")
        trace.cpu = [cpu * trace.steps[hit] / compiled.sum()] * len(trace.steps)
    return trace


def studio_demos_trace(
    joints: int, config: DynaQConfig, seed: int, budget: int, stop_at_target: bool = False
) -> Trace:
    """The studio's learner taught by 3 straight demonstrations from random starts
    (``bench_demos.demonstrations`` of the seed: the same as there), its default actions
    following them. Greedy success is judged at the end of the first episode at or past every
    ``RHYTHM`` real steps, on a compiled run of that many episodes: a run's first E episodes
    learn the same whatever comes after (checked at every judgement), so no Python loop is
    needed to stop it there. The demonstrations' steps count as real steps."""
    from bench_demos import demonstrations

    task = ArmReach(joints=joints)
    demos = demonstrations(task, seed)
    starts = held_out_starts(joints)
    features = task.features()

    def run(episodes: int):
        return run_experiments(
            lambda: gymnasium.make(ARM_REACH_ID, joints=joints),
            config, 1, episodes, seed, demos, features, workers=1,
        )  # fmt: skip

    trace, episodes, mark = Trace(), 64, RHYTHM[joints]
    steps = run(episodes).steps[0]
    while mark <= budget:
        while steps.sum() < mark:
            episodes *= 2
            steps = run(episodes).steps[0]
        upto = int(np.searchsorted(np.cumsum(steps), mark)) + 1
        cpu = time.process_time()
        result = run(upto)
        cpu = time.process_time() - cpu
        if not np.array_equal(result.steps[0], steps[:upto]):
            raise AssertionError("a shorter run learnt differently from the longer one's start")
        ok = greedy_success(result.task, result.coder, result.weights[0], starts, CAP)
        trace.steps.append(int(steps[:upto].sum()))
        trace.success.append(float(ok.mean()))
        trace.cpu.append(cpu)
        progress(f"studio with demonstrations seed {seed}", trace)
        if stop_at_target and trace.success[-1] >= SUCCESS:
            break
        mark = trace.steps[-1] + RHYTHM[joints]
    return trace


def warm_up(joints: int) -> None:
    """Compile the kernels before anything is timed."""
    task = ArmReach(joints=joints)
    for config, _ in STUDIO.values():
        run_experiments(
            lambda: gymnasium.make(ARM_REACH_ID, joints=joints),
            config, 1, 2, 0, features=task.features(), workers=1,
        )  # fmt: skip


# ------------------------------------------------------------------------------------------- SB3


def _scaled(q: np.ndarray, task: ArmReach) -> np.ndarray:
    """Joint angles rescaled from the limits to [-1, 1]."""
    return 2.0 * (q - task.lower) / (task.upper - task.lower) - 1.0


class _Scaled(gymnasium.ObservationWrapper):
    def __init__(self, env: gymnasium.Env) -> None:
        super().__init__(env)
        self.task = env.unwrapped.task
        shape = self.task.lower.shape
        self.observation_space = gymnasium.spaces.Box(-1.0, 1.0, shape, np.float32)

    def observation(self, observation):
        return _scaled(np.asarray(observation), self.task).astype(np.float32)


@njit(cache=False)
def _advance(params, states, actions, before, running, reached):
    """One greedy step of every running rollout. A rollout back on the state of two steps ago
    (bit for bit) or stuck in place loops for ever under a deterministic policy: it has failed."""
    for i in range(states.shape[0]):
        if not running[i]:
            continue
        last = states[i].copy()
        _, done = reach_step(params, states[i], actions[i])
        if done:
            running[i] = False
            reached[i] = True
        elif np.array_equal(states[i], before[i]) or np.array_equal(states[i], last):
            running[i] = False
        before[i] = last


def peer_success(model, task: ArmReach, starts: np.ndarray, vec_normalize) -> float:
    """Greedy success of an SB3 model from ``starts``, all rolled out at once."""
    states = np.ascontiguousarray(starts, np.float64).copy()
    before = np.full_like(states, np.nan)
    running = np.ones(len(states), np.bool_)
    reached = np.zeros(len(states), np.bool_)
    for _ in range(CAP):
        if not running.any():
            break
        obs = _scaled(states, task).astype(np.float32)
        if vec_normalize is not None:
            obs = vec_normalize.normalize_obs(obs)
        actions, _ = model.predict(obs, deterministic=True)
        _advance(task.params, states, np.asarray(actions, np.int64), before, running, reached)
    return float(reached.mean())


def peer_trace(
    joints: int, peer: Peer, seed: int, budget: int, stop_at_target: bool = False
) -> Trace:
    import torch
    from stable_baselines3 import DQN, PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    torch.set_num_threads(1)
    task = ArmReach(joints=joints)
    starts = held_out_starts(joints)
    rhythm = RHYTHM[joints]
    trace = Trace()

    def make() -> gymnasium.Env:
        return _Scaled(gymnasium.make(ARM_REACH_ID, joints=joints))

    env = make_vec_env(make, n_envs=peer.n_envs, seed=seed)
    norm = VecNormalize(env, gamma=peer.kwargs.get("gamma", 0.99)) if peer.normalize else None
    kwargs = dict(peer.kwargs)
    for key in ("learning_rate", "clip_range"):
        if isinstance(kwargs.get(key), str):  # the Zoo's "lin_x": linear from x to 0
            start = float(kwargs[key][4:])
            kwargs[key] = lambda progress, start=start: progress * start
    algo = DQN if peer.algo == "DQN" else PPO
    model = algo("MlpPolicy", norm or env, seed=seed, device="cpu", verbose=0, **kwargs)
    spent = {"eval": 0.0, "start": 0.0}

    class Every(BaseCallback):
        next_tick = rhythm

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next_tick:
                t = time.process_time()
                trace.steps.append(self.num_timesteps)
                trace.success.append(peer_success(model, task, starts, norm))
                trace.cpu.append(t - spent["start"] - spent["eval"])
                spent["eval"] += time.process_time() - t
                progress(f"{peer.algo} seed {seed}", trace)
                while self.next_tick <= self.num_timesteps:
                    self.next_tick += rhythm
                return not (stop_at_target and trace.success[-1] >= SUCCESS)
            return True

    spent["start"] = time.process_time()
    model.learn(total_timesteps=budget, callback=Every())
    t = time.process_time()
    trace.steps.append(int(model.num_timesteps))
    trace.success.append(peer_success(model, task, starts, norm))
    trace.cpu.append(t - spent["start"] - spent["eval"])
    env.close()
    return trace


def have_sb3() -> bool:
    try:
        import stable_baselines3  # noqa: F401
        import torch  # noqa: F401
    except ImportError:
        return False
    return True


# ---------------------------------------------------------------------------------------- report


@dataclass
class Row:
    name: str
    traces: list[Trace]

    def hits(self) -> list[tuple[int, float] | None]:
        out = []
        for t in self.traces:
            i = t.first()
            out.append(None if i is None else (t.steps[i], t.cpu[i]))
        return out

    def mean_steps(self) -> float | None:
        hits = self.hits()
        return None if None in hits else float(np.mean([h[0] for h in hits]))

    def mean_cpu(self) -> float | None:
        hits = self.hits()
        return None if None in hits else float(np.mean([h[1] for h in hits]))

    def line(self) -> str:
        hits = self.hits()
        each = ", ".join("-" if h is None else f"{h[0] / 1e3:.0f}" for h in hits)
        cpus = ", ".join("-" if h is None else f"{h[1]:.2f}" for h in hits)
        mean = self.mean_steps()
        cpu = self.mean_cpu()
        reached = sum(h is not None for h in hits)
        final = np.mean([t.success[-1] for t in self.traces])
        steps_text = "not reached by all" if mean is None else f"{mean / 1e3:,.1f} k"
        cpu_text = "-" if cpu is None else f"{cpu:.2f} s"
        return (
            f"| {self.name} | {steps_text} ({each}) | {cpu_text} ({cpus}) | "
            f"{reached}/{len(hits)} | {100 * final:.1f}% |"
        )


def compare(rows: list[Row], joints: int) -> list[str]:
    """Each studio row against the best peer (fewest mean steps to 95%): the lines printed."""
    peers = [r for r in rows if r.name.startswith("SB3") and r.mean_steps() is not None]
    if not peers:
        return [f"{joints} joints: no peer reached {SUCCESS:.0%} on every seed; no ratio."]
    best = min(peers, key=lambda r: r.mean_steps() or 0.0)
    lines = [f"{joints} joints, best peer: {best.name}."]
    for row in rows:
        if row.name.startswith("SB3"):
            continue
        steps, cpu = row.mean_steps(), row.mean_cpu()
        if steps is None or cpu is None:
            lines.append(f"  {row.name}: did not reach {SUCCESS:.0%} on every seed.")
            continue
        steps_ratio = steps / (best.mean_steps() or 1.0)
        cpu_ratio = (best.mean_cpu() or 0.0) / max(cpu, 1e-9)
        met = steps_ratio < 1.0 and cpu_ratio >= 10.0
        lines.append(
            f"  {row.name}: real steps {steps_ratio:.2f}x the peer's (goal < 1), "
            f"{cpu_ratio:.1f}x less CPU (goal >= 10): goal {'met' if met else 'NOT met'}."
        )
    return lines


def main(argv: list[str] | None = None) -> list[Row]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--joints", type=int, nargs="+", default=[3, 6], choices=[3, 4, 5, 6])
    parser.add_argument("--seeds", type=int, default=3, help="how many paired seeds")
    parser.add_argument("--first-seed", type=int, default=0, help="seeds from this one on")
    parser.add_argument("--budget", type=int, default=None, help="real steps per run")
    parser.add_argument(
        "--quick",
        action="store_true",
        help="3 joints, 1 seed, 6,000 steps, the studio defaults and wider tilings",
    )
    parser.add_argument("--studio-only", action="store_true", help="skip the SB3 learners")
    parser.add_argument(
        "--stop-at-target",
        action="store_true",
        help=f"end each run at its first evaluation at >= {SUCCESS:.0%} (saves CPU; the final "
        "success is then that run's last evaluation)",
    )
    parser.add_argument(
        "--learners", nargs="*", default=None, help="only the learners whose names contain these"
    )
    args = parser.parse_args(argv)
    if args.quick:
        args.joints, args.seeds, args.studio_only = [3], 1, True
        args.learners = args.learners or ["studio defaults", "32 tilings"]
    peers = {} if args.studio_only else PEERS
    studio, studio_demos = STUDIO, STUDIO_DEMOS
    if args.learners is not None:
        peers = {k: v for k, v in peers.items() if any(p in k for p in args.learners)}
        studio = {k: v for k, v in studio.items() if any(p in k for p in args.learners)}
        studio_demos = {k: v for k, v in studio_demos.items() if any(p in k for p in args.learners)}
    if peers and not have_sb3():
        print(f"Stable-Baselines3 is not installed: measuring the studio only ({INSTALL} adds it).")
        peers = {}
    all_rows = []
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    for joints in args.joints:
        budget = args.budget or (QUICK_BUDGET if args.quick else BUDGET.get(joints, 300_000))
        print(
            f"\nArmReach-v0, {joints} joints, default shaping; greedy success from {STARTS} "
            f"held-out starts every {RHYTHM.get(joints, 5_000):,} real steps; budget "
            f"{budget:,} steps; seeds {seeds.start}..{seeds.stop - 1}\n",
            flush=True,
        )
        RHYTHM.setdefault(joints, 5_000)
        warm_up(joints)
        rows = []
        for name, (config, coding) in studio.items():
            traces = [
                studio_trace(joints, config, s, budget, coding, args.stop_at_target) for s in seeds
            ]
            rows.append(Row(name, traces))
            print(rows[-1].line(), flush=True)
        for name, config in studio_demos.items():
            traces = [
                studio_demos_trace(joints, config, s, budget, args.stop_at_target) for s in seeds
            ]
            rows.append(Row(name, traces))
            print(rows[-1].line(), flush=True)
        for name, peer in peers.items():
            traces = [peer_trace(joints, peer, s, budget, args.stop_at_target) for s in seeds]
            rows.append(Row(name, traces))
            print(rows[-1].line(), flush=True)
        print(
            f"\n| learner | steps to {SUCCESS:.0%}, mean (per seed, k) | CPU to {SUCCESS:.0%} (per seed) | seeds reaching | final success |"
        )
        print("|---|---|---|---|---|")
        for r in rows:
            print(r.line())
        print("\n".join(compare(rows, joints)))
        all_rows += rows
    return all_rows


if __name__ == "__main__":
    main()
