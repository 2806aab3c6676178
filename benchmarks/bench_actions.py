"""Which action set of the continuous arm task learns and looks better: one joint per action,
also two joints together (the diagonals), or any joints at once; and for the multi-joint sets,
one weight column per action against the factored action value (``studio.learning.linear._factored``:
a per-joint term for each joint's part of the move, each learning from its joint's share of the
reward).

``python benchmarks/bench_actions.py [--quick]`` (several minutes on one free core). For 3 and 6
joints and each variant of :data:`VARIANTS`, with the environment's default reward (shaping 5),
zero planning and the default per-joint tilings:

- learning: each budget of episodes is trained afresh (same seeds, so a budget's run is a prefix
  of the next one's), and its greedy policy is judged from 200 held-out random starts; the table
  shows the real steps and CPU seconds of the first budget whose mean greedy success reaches
  95%, and the success of the largest budget;
- looks: from 10 held-out starts, the greedy rollout of the largest budget's policy against a
  demonstration-like reference, the straight joint-space line from that start to the goal with
  a minimum-jerk time course (peak joint speed one step per 0.04 s, as a rollout's), on the
  likeness card (``policy_likeness_card``): LDLJ (higher is smoother; the reference's beside it),
  Jensen-Shannon divergence of the joint shares, the share of time two or more joints move
  together (the reference's: 100%), DTW per sample and duration, averaged over the rollouts that
  reach the goal (how many do is shown).

Last, the learner's speed per action set at six joints (real steps per CPU second, 300 episodes;
``--speed`` prints only this): every action's value is summed at every step, so it falls with
the number of actions; one joint per action keeps its own fast path in the dynamics.

Figures from a shared machine are noisy in CPU seconds; the steps and successes are exact for
the seeds.
"""

from __future__ import annotations

import argparse
import functools
from contextlib import contextmanager

import gymnasium
import numpy as np

import studio.learning.linear._linear as linear
from studio.learning import (
    ACTION_SETS,
    ArmReach,
    DynaQConfig,
    TilePolicyFile,
    policy_likeness_card,
    run_experiments,
)
from studio.learning.linear._linear import greedy_success
from studio.learning.linear._policy import DEFAULT_SECONDS_PER_STEP
from studio.learning.tasks._gym import ARM_REACH_ID

SEED = 0
STARTS = 200
LOOK_STARTS = 10
REFERENCE_SAMPLES = 100
SUCCESS = 0.95
CAP = 3_000
BUDGETS = {3: (250, 500, 1000, 2000, 4000), 6: (500, 1000, 2000, 4000)}
QUICK_BUDGETS = {3: (250, 1000), 6: (500, 2000)}
VARIANTS = (
    ("single", False),
    ("pairs", False),
    ("pairs", True),
    ("all", False),
    ("all", True),
)
"""(action set, factored value): one joint per action has one column per action either way."""


def name(actions: str, factored: bool) -> str:
    """A variant's name on the command line: the action set, ``+factored`` when factored."""
    return actions + ("+factored" if factored else "")


@contextmanager
def columns_per_action(factored: bool):
    """Learn a multi-joint set with one weight column per action (``factored=False``)."""
    original = linear.value_factors
    if not factored:
        linear.value_factors = lambda *args: None
    try:
        yield
    finally:
        linear.value_factors = original


def straight_line(task: ArmReach, start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The straight joint-space line from ``start`` to the goal (six joints) on a minimum-jerk
    time course whose peak joint speed is one step per :data:`DEFAULT_SECONDS_PER_STEP`."""
    goal = np.asarray(task.goal)
    full_start = task.full_q(start)
    tau = np.linspace(0.0, 1.0, REFERENCE_SAMPLES)
    s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
    q = full_start + s[:, None] * (goal - full_start)
    peak = np.abs(goal - full_start).max() / task.step * DEFAULT_SECONDS_PER_STEP
    return tau * 1.875 * peak, q


def one(joints: int, actions: str, factored: bool, budgets, experiments: int) -> dict:
    with columns_per_action(factored):
        return _one(joints, actions, factored, budgets, experiments)


def _one(joints: int, actions: str, factored: bool, budgets, experiments: int) -> dict:
    task = ArmReach(joints=joints, actions=actions)
    rng = np.random.default_rng([7, joints])
    starts = np.array([task.random_start(rng) for _ in range(STARTS)])
    config = DynaQConfig(planning="zero", max_steps_per_episode=CAP)
    make = lambda: gymnasium.make(ARM_REACH_ID, joints=joints, actions=actions)  # noqa: E731
    run_experiments(make, config, 1, 2, SEED, features=task.features(), workers=1)  # compile
    reached = None
    result = None
    success = 0.0
    first = 0.0
    for n in budgets:
        result = run_experiments(
            make, config, experiments, n, SEED, features=task.features(), workers=1
        )
        success = float(
            np.mean(
                [greedy_success(task, result.coder, w, starts, CAP).mean() for w in result.weights]
            )
        )
        first = float(result.steps[:, :20].sum() / experiments)
        if reached is None and success >= SUCCESS:
            reached = (n, result.steps.sum() / experiments, float(np.mean(result.cpu_seconds)))
    assert result is not None
    cards = []
    looked = 0
    for w in result.weights:
        policy = TilePolicyFile(coder=result.coder, weights=w, config=config, task=task)
        for start in starts[:LOOK_STARTS]:
            looked += 1
            if greedy_success(task, result.coder, w, start[None], CAP)[0]:
                times, q = straight_line(task, start)
                cards.append(policy_likeness_card(policy, times, q))
    return {
        "joints": joints,
        "actions": actions + (" factored" if factored and actions != "single" else ""),
        "n_actions": task.n_actions,
        "first": first,
        "reached": reached,
        "final": success,
        "last_budget": budgets[-1],
        "looked": f"{len(cards)}/{looked}",
        "ldlj": float(np.nanmean([c.policy.ldlj for c in cards])),
        "line_ldlj": float(np.nanmean([c.demonstration.ldlj for c in cards])),
        "js": float(np.nanmean([c.shares_js for c in cards])),
        "together": float(np.mean([c.policy.together for c in cards])),
        "dtw": float(np.mean([c.dtw_rad for c in cards])),
        "duration": float(np.mean([c.policy.duration_s for c in cards])),
        "line_duration": float(np.mean([c.demonstration.duration_s for c in cards])),
    }


def speed() -> None:
    config = DynaQConfig(planning="zero", max_steps_per_episode=CAP)
    for actions in ACTION_SETS:
        task = ArmReach(joints=6, actions=actions)
        make = functools.partial(gymnasium.make, ARM_REACH_ID, joints=6, actions=actions)
        run_experiments(make, config, 1, 2, SEED, features=task.features(), workers=1)
        result = run_experiments(make, config, 1, 300, SEED, features=task.features(), workers=1)
        real = int(result.steps.sum())
        cpu = float(result.cpu_seconds[0])
        print(
            f"six joints, {actions} ({task.n_actions} actions): {real:,} real steps in {cpu:.2f} s "
            f"CPU = {real / cpu / 1e6:.3f} M steps/s"
        )


def row(r: dict) -> str:
    if r["reached"] is None:
        learn = "not reached | - | -"
    else:
        n, steps, cpu = r["reached"]
        learn = f"{n:,} episodes | {steps / 1e3:,.0f} k | {cpu:.2f} s"
    return (
        f"| {r['joints']} | {r['actions']} ({r['n_actions']}) | {r['first']:,.0f} | {learn} "
        f"| {100 * r['final']:.0f}% "
        f"| {r['ldlj']:.2f} ({r['line_ldlj']:.2f}) | {r['js']:.3f} | {100 * r['together']:.0f}% "
        f"| {r['dtw']:.3f} | {r['duration']:.1f} ({r['line_duration']:.1f}) | {r['looked']} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="two budgets, one experiment")
    parser.add_argument("--experiments", type=int, default=2)
    parser.add_argument("--joints", type=int, nargs="*", default=[3, 6])
    parser.add_argument(
        "--variants",
        nargs="*",
        default=[name(a, f) for a, f in VARIANTS],
        choices=[name(a, f) for a, f in VARIANTS],
        help="which rows to measure (default: all)",
    )
    parser.add_argument("--speed", action="store_true", help="only the learner's speed")
    args = parser.parse_args()
    if args.speed:
        speed()
        return
    budgets = QUICK_BUDGETS if args.quick else BUDGETS
    experiments = 1 if args.quick else args.experiments
    print(
        f"ArmReach, shaping 5, zero planning, per-joint tilings, {experiments} experiment(s); "
        f"greedy success from {STARTS} held-out starts; looks from {LOOK_STARTS} starts per "
        "policy against the straight joint line (its value in brackets)\n"
    )
    print(
        f"| joints | actions (n) | first 20 episodes' real steps | first budget at {SUCCESS:.0%} "
        "| real steps | CPU | success at the last budget | LDLJ (line) | shares JS "
        "| joints together | DTW rad/sample | duration s (line) | rollouts reaching |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for joints in args.joints:
        for actions, factored in VARIANTS:
            if name(actions, factored) not in args.variants:
                continue
            r = one(joints, actions, factored, budgets[joints], experiments)
            print(row(r), flush=True)
    print()
    speed()


if __name__ == "__main__":
    main()
