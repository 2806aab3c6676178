"""Do joint-path demonstrations speed up the continuous arm task? Paired seeds, 95% intervals.

``python benchmarks/bench_demos.py [--pairs 6] [--episodes 1000] [--joints 6]`` measures, through
``run_experiments`` (zero planning unless ``--planning-steps``, the paper's alpha, gamma and epsilon, an episode cap of
3,000 steps), for each pair ``k``: 3 straight joint-space demonstrations from random starts to
the goal and 200 held-out random starts, drawn from ``default_rng([k, joints])``; the run with
and the run without demonstrations share the seed ``k`` (the same start states, the same draws).

1. The paper's reward (``shaping=0``): the real steps of the first 20 own episodes (those after
   the replayed demonstrations) with demonstrations over those without (goal <= 0.5), and the
   greedy success from the 200 held-out starts after ``--episodes`` episodes, the demonstrations'
   episodes counted in the budget.
2. Control: demonstrations to a *different* goal (a random pose), replayed and shaping as the
   real ones would, must not help reach this goal.
3. Control: the default shaping, with against without demonstrations (goal: never more than 2
   points lower).
4. Variants of the demonstrations' potential (``--variants``): its weight and kappa
   (:mod:`studio.learning.tasks._demo_shaping`), and the replay alone (weight 0, the earlier method).
5. ``--long N``: greedy success with demonstrations under the paper's reward after N episodes.
6. ``--actions SET``: every run with that action set (default: the task's default, ``follow``)
   and its default features; with ``follow`` the demonstrations are also the paths its follow
   action follows (without demonstrations it moves one joint per action, on the same features).
7. ``--planning-steps N``: every run with full planning of N steps (the studio's default is
   100) instead of none.

Each figure is the mean over pairs with a 95% t interval of the paired difference or ratio. The
machine may be shared: the figures are counts (steps, successes), not times, so load does not
change them.
"""

from __future__ import annotations

import argparse
import functools
import time
from contextlib import contextmanager

import gymnasium
import numpy as np
from scipy import stats

import studio.learning.linear._env as linear_env
import studio.learning.linear._linear as linear
from studio.learning import ACTION_SETS, ArmReach, DynaQConfig, LearningError, run_experiments
from studio.learning.linear._linear import greedy_success
from studio.learning.paper._beyond import demonstration_paths
from studio.learning.tasks._demo_shaping import demo_potential

CAP = 3_000
DEMOS = 3
STARTS = 200
FIRST_OWN = 20
ACTIONS: dict[str, str] = {}  # the action set of every run, when --actions names one
PLANNING: dict[str, object] = {"planning": "zero"}  # every run's planning (--planning-steps)
SECTIONS = ("paper", "other-goal", "default", "long")


def interval(values: np.ndarray) -> str:
    """``mean [low, high]`` (95% t interval over pairs)."""
    v = np.asarray(values, dtype=np.float64)
    mean = float(v.mean())
    if v.size < 2 or float(v.std()) == 0.0:
        return f"{mean:.3f} [{mean:.3f}, {mean:.3f}]"
    half = float(stats.t.ppf(0.975, v.size - 1) * v.std(ddof=1) / np.sqrt(v.size))
    return f"{mean:.3f} [{mean - half:.3f}, {mean + half:.3f}]"


@contextmanager
def potential_variant(weight: float | None, kappa: float | None):
    """Run with another weight or kappa of the demonstrations' potential (None: the default)."""
    original = linear.demo_potential
    kwargs = {k: v for k, v in (("weight", weight), ("kappa", kappa)) if v is not None}
    linear.demo_potential = functools.partial(demo_potential, **kwargs)
    try:
        yield
    finally:
        linear.demo_potential = original


@contextmanager
def demonstrations_for(goal_task: ArmReach):
    """Walk the demonstrations with ``goal_task``'s goal (the control: they end elsewhere)."""
    originals = [(module, module.env_demonstrations) for module in (linear, linear_env)]

    def walk(demos, task):
        pairs = [goal_task.demonstration_actions(d, i) for i, d in enumerate(demos)]
        return [p[0] for p in pairs], [p[1] for p in pairs]

    # both the check of the demonstrations as given and the walk the learner replays
    for module, _ in originals:
        module.env_demonstrations = walk
    try:
        yield
    finally:
        for module, original in originals:
            module.env_demonstrations = original


_WITHOUT: dict[tuple, tuple] = {}


def without(joints, shaping, episodes, seed):
    """The run without demonstrations (computed once per seed: every comparison pairs with it)."""
    key = (joints, shaping, episodes, seed, tuple(ACTIONS.items()))
    if key not in _WITHOUT:
        _WITHOUT[key] = one_run(joints, shaping, episodes, seed, [])
    return _WITHOUT[key]


def one_run(joints, shaping, episodes, seed, demos):
    """``(steps (episodes,), greedy success over the held-out starts)`` of one experiment."""
    task = ArmReach(joints=joints, shaping=shaping, **ACTIONS)
    result = run_experiments(
        lambda: gymnasium.make("TeachStudio/ArmReach-v0", joints=joints, shaping=shaping, **ACTIONS),
        DynaQConfig(**PLANNING, max_steps_per_episode=CAP),
        1, episodes, seed, demos, task.features(), workers=1,
    )  # fmt: skip
    starts = np.random.default_rng([seed, joints, 7]).uniform(
        task.lower, task.upper, (STARTS, joints)
    )
    success = greedy_success(result.task, result.coder, result.weights[0], starts, CAP).mean()
    return result.steps[0], float(success)


def demonstrations(task: ArmReach, k: int) -> list[np.ndarray]:
    """Seed ``k``'s demonstrations to ``task``'s goal, redrawn while a straight line's walk
    misses the goal's tolerance (``run_experiments`` refuses such a demonstration)."""
    rng = np.random.default_rng([k, task.joints])
    while True:
        demos = demonstration_paths(task, DEMOS, rng)
        try:
            for i, d in enumerate(demos):
                task.demonstration_actions(d, i)
        except LearningError:
            continue
        return demos


def pair(joints, shaping, episodes, k, context=None):
    """The paired figures of seed ``k``: first-20 steps with and without, success with and without."""
    demos = demonstrations(ArmReach(joints=joints), k)
    with context() if context else _nothing():
        steps_with, success_with = one_run(joints, shaping, episodes, k, demos)
    steps_without, success_without = without(joints, shaping, episodes, k)
    first_with = int(steps_with[DEMOS : DEMOS + FIRST_OWN].sum())
    first_without = int(steps_without[:FIRST_OWN].sum())
    print(
        f"    pair {k}: first {FIRST_OWN} {first_with} / {first_without}, success "
        f"{success_with:.3f} / {success_without:.3f}",
        flush=True,
    )
    return first_with, first_without, success_with, success_without


@contextmanager
def _nothing():
    yield


def report(name, rows):
    rows = np.asarray(rows, dtype=np.float64)
    ratio = rows[:, 0] / rows[:, 1]
    print(f"\n{name} ({len(rows)} pairs)")
    print(f"  first {FIRST_OWN} own episodes, real steps: with {interval(rows[:, 0])}")
    print(f"                                  without {interval(rows[:, 1])}")
    print(f"  ratio with / without {interval(ratio)}")
    print(f"  greedy success: with {interval(rows[:, 2])}, without {interval(rows[:, 3])}")
    print(f"  difference with - without {interval(rows[:, 2] - rows[:, 3])}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=6)
    parser.add_argument("--first", type=int, default=0, help="the first pair's seed")
    parser.add_argument("--episodes", type=int, default=1000)
    parser.add_argument("--joints", type=int, default=6)
    parser.add_argument("--variants", action="store_true", help="also the potential's variants")
    parser.add_argument("--skip-controls", action="store_true")
    parser.add_argument(
        "--sections",
        nargs="*",
        choices=SECTIONS,
        default=list(SECTIONS),
        help="which figures to measure (default: all; lets several processes share a run)",
    )
    parser.add_argument(
        "--long", type=int, default=0, help="also greedy success with demonstrations after N"
    )
    parser.add_argument("--actions", choices=ACTION_SETS, help="every run's action set")
    parser.add_argument(
        "--planning-steps", type=int, default=0, help="full planning with N steps (0: none)"
    )
    args = parser.parse_args()
    if args.planning_steps > 0:
        PLANNING.update(planning="full", planning_steps=args.planning_steps)
    if args.actions:
        ACTIONS["actions"] = args.actions
    j, n, pairs = args.joints, args.episodes, range(args.first, args.first + args.pairs)
    print(
        f"{j} joints, {n} episodes (demonstrations counted), {DEMOS} demonstrations, cap {CAP}, "
        f"actions {args.actions or ArmReach().actions}"
    )
    t0 = time.perf_counter()
    if "paper" in args.sections:
        rows = [pair(j, 0.0, n, k) for k in pairs]
        report("paper's reward (shaping 0), the default method", rows)
    if args.variants:
        for weight, kappa in ((0.0, None), (1.0, None), (5.0, 2.0), (10.0, None)):
            ctx = functools.partial(potential_variant, weight, kappa)
            rows = [pair(j, 0.0, n, k, ctx) for k in pairs]
            report(f"shaping 0, potential weight {weight}, kappa {kappa or 'default'}", rows)
    if not args.skip_controls and "other-goal" in args.sections:
        rows = []
        for k in pairs:
            other = ArmReach(
                joints=j,
                goal=tuple(ArmReach(joints=j).random_start(np.random.default_rng([k, 99]))),
            )
            ctx = functools.partial(demonstrations_for, other)
            rows.append(pair_other(j, n, k, other, ctx))
        report("control: shaping 0, demonstrations to a different goal", rows)
    if not args.skip_controls and "default" in args.sections:
        report("control: default shaping", [pair(j, ArmReach().shaping, n, k) for k in pairs])
    if args.long and "long" in args.sections:
        success = []
        for k in pairs:
            demos = demonstrations(ArmReach(joints=j), k)
            success.append(one_run(j, 0.0, args.long, k, demos)[1])
            print(f"    pair {k}: {success[-1]:.3f}", flush=True)
        print(
            f"\nshaping 0, with demonstrations, {args.long} episodes: success {interval(success)}"
        )
    print(f"\n({time.perf_counter() - t0:.0f} s wall)")


def pair_other(joints, episodes, k, other, context):
    """Like :func:`pair`, with demonstrations that end at ``other``'s goal."""
    demos = demonstrations(other, k)
    with context():
        steps_with, success_with = one_run(joints, 0.0, episodes, k, demos)
    steps_without, success_without = without(joints, 0.0, episodes, k)
    return (
        int(steps_with[DEMOS : DEMOS + FIRST_OWN].sum()),
        int(steps_without[:FIRST_OWN].sum()),
        success_with,
        success_without,
    )


if __name__ == "__main__":
    main()
