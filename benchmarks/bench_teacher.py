"""Every baseline beside Dyna-Q on one split: what did the work when a robot learns from demonstrations?

``python benchmarks/bench_teacher.py [--episodes 1000] [--starts 200] [--planning-steps 0]
[--seed 0] [--quick]``

The split, the same for every row:

- the Puma560, the continuous task over its six joints (2-degree steps, episodes capped at 3,000
  steps), the paper's reward: +100 at the goal, -1 a step, no shaping toward the goal
  (``shaping=0``) unless a row says so;
- the goal: the shipped sample ``sample-reach-1``'s final pose, reached when the tool is within
  2 cm of it. The three samples end at three wrist rolls (joint 4 at -158, -11 and -116 degrees,
  joint 5 near 0), so no one tool orientation is reached by all three: the goal leaves the
  orientation free (``angle_tolerance_deg=180``). On the Puma560 the tool frame is the wrist
  centre, so joints 4-6 then move nothing that counts; a policy may learn to leave them;
- the three samples (``sample-reach-1..3``) as the demonstrations, where a row has any;
- 200 held-out random starts across the joint limits (``default_rng([seed, 99])``), the same
  for every row.

The rows: the teacher (the demonstrations followed at every step, no learning); the DMP fitted
to ``sample-reach-1`` (a movement primitive learns one demonstration); behaviour cloning (one
nearest neighbour over the demonstrated states, moving toward the state the demonstration went to
next from it); and linear Dyna-Q (zero planning unless
``--planning-steps``, the paper's alpha 0.1, gamma 0.95, epsilon 0.1, per-joint tile coding):
without demonstrations (one joint per action); with the paper's replay only (the demonstrations
replayed as the first episodes, one joint per action); with the follow option (the action that
follows the demonstrations beside the single joints, no potential); with the demonstration
potential (Brys et al. 2015, weight 5, one joint per action); with both, the studio's
default when demonstrations are given; with the potential and every joint -1, 0 or +1 at
once (``actions="all"``, the factored value), the agent's own way to cut the demonstrated paths
short with direct multi-joint moves; and with the potential, those moves and the follow action
(``actions="all-follow"``: its greedy policy hands the motion to the follow action where its
moves would loop, and the line after the table says how it does without that hand-over).

The columns: greedy success from the held-out starts; collisions (the share of starts whose
rollout touches the robot itself or the table, by the robot's collision geometry, at every
state of a rollout up to 100 steps and 100 evenly spaced states of a longer one); mean time to
the goal over the starts that reach it, at one pace for every row (the demonstrations' own: their
moving time over their steps along the follow action, a 2-degree step of the joint that moves
most) and its ratio to the teacher's; the real steps to 95% success (the first of the budgets
``episodes/8, /4, /2, /1``, each trained afresh on the same seed, whose greedy policy reaches
95%: every real step of it, the demonstrations' included); the CPU seconds to learn (the largest
budget; fitting for the baselines). Then the two goals: better than the teacher (success at
least its, mean time at most 0.9x its), and the first 20 own episodes with demonstrations and
the potential off against those without (at most 0.6x).
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

import numpy as np

from studio.kinematics import load_robot
from studio.learning import (
    ArmReach,
    LiveProgress,
    RunRequest,
    Start,
    demonstrated_pace,
    fit_dmp_policy,
    learner,
    resolve_run,
)
from studio.learning.linear._greedy import greedy_rollout, greedy_success, hand_over_action
from studio.learning.runs._train import train_learner
from studio.motion import training_demonstration
from studio.samples import SAMPLES_DIR

ROBOT = "puma560"
JOINTS = 6
CAP = 3_000
SUCCESS = 0.95
FIRST_OWN = 20
SAMPLES = ("sample-reach-1", "sample-reach-2", "sample-reach-3")
SPLIT = {"shaping": 0.0, "angle_tolerance_deg": 180.0, "joints": JOINTS}
"""The task every row shares (its goal added from the first sample): the paper's reward, the
tool within 2 cm, its orientation free."""
COLLISION_CHECKS = 100
"""Most states of one rollout checked for contact (evenly spaced)."""
DYNA_ROWS = {
    "Dyna-Q, no demonstrations": {"actions": "single", "demo_potential": 0.0, "demos": False},
    "Dyna-Q, the paper's replay only": {"actions": "single", "demo_potential": 0.0},
    "Dyna-Q + follow option": {"actions": "follow", "demo_potential": 0.0},
    "Dyna-Q + demonstration potential": {"actions": "single", "demo_potential": 5.0},
    "Dyna-Q + follow + potential (default)": {"actions": "follow"},
    "Dyna-Q + potential, any joints at once": {"actions": "all", "demo_potential": 5.0},
    "Dyna-Q + potential, any joints or follow": {"actions": "all-follow", "demo_potential": 5.0},
}


@dataclass
class Row:
    name: str
    success: float
    collisions: float
    mean_seconds: float
    steps_to_95: str
    cpu: float
    first_own: int | None = None
    alone: float | None = None
    """With a hand-over to the follow action: the greedy policy's success without it."""


def demonstrations():
    return [
        training_demonstration(SAMPLES_DIR / f"{name}.demo.json", ROBOT, name, name)
        for name in SAMPLES
    ]


def collided(arm, task: ArmReach, path: np.ndarray) -> bool:
    """Whether any checked state of the joint path touches the robot or the table."""
    rows = np.unique(np.linspace(0, len(path) - 1, min(len(path), COLLISION_CHECKS)).astype(int))
    return any(arm.contacts(task.full_q(path[i])) for i in rows)


def judge(name, walks, task, pace, arm, steps_to_95, cpu, first_own=None) -> Row:
    """A row of ``walks``: each start's joint path and whether it reached the goal."""
    reached = np.array([r for _, r in walks])
    steps = np.array([len(p) - 1 for p, _ in walks], dtype=float)
    hits = [collided(arm, task, p) for p, _ in walks]
    mean = float(steps[reached].mean() * pace) if reached.any() else float("nan")
    return Row(name, float(reached.mean()), float(np.mean(hits)), mean, steps_to_95, cpu, first_own)


def baseline_rows(task, demos, starts, pace, arm) -> list[Row]:
    """The teacher, behaviour cloning and the DMP."""
    paths = [np.asarray(d.q_robot)[:, :JOINTS] for d in demos]
    rows = []
    for kind, name in (
        ("teacher", "teacher (the demonstrations followed)"),
        ("cloning", "behaviour cloning"),
    ):
        t = time.process_time()
        policy = learner(kind).fit(task, paths, pace)  # type: ignore[attr-defined]
        cpu = time.process_time() - t
        walks = [policy.walk(s, CAP) for s in starts]
        ok = np.mean([r for _, r in walks]) >= SUCCESS
        rows.append(judge(name, walks, task, pace, arm, "0 (no learning)" if ok else "never", cpu))
    t = time.process_time()
    first = demos[0]
    dmp = fit_dmp_policy(first.times, first.q_robot, robot=ROBOT)
    cpu = time.process_time() - t
    walks, seconds = [], []
    for s in starts:
        pose = first.q_robot[0].copy()
        pose[:JOINTS] = s
        out = learner("dmp").roll_out(dmp, Start(q=pose), 50.0)
        at = next((k for k, q in enumerate(out.q) if task.success(q[:JOINTS])), None)
        walks.append((out.q[: (len(out.q) if at is None else at + 1), :JOINTS], at is not None))
        seconds.append(np.nan if at is None else out.times[at])
    row = judge("DMP (sample-reach-1)", walks, task, pace, arm, "never", cpu)
    hit = [w[1] for w in walks]
    row.mean_seconds = float(np.nanmean(np.asarray(seconds)[hit])) if any(hit) else float("nan")
    row.steps_to_95 = "0 (no learning)" if row.success >= SUCCESS else "never"
    return [*rows, row]


def dyna_run(settings, demos, goal, episodes, seed, planning_steps):
    reach = {**SPLIT, "goal": goal, **{k: v for k, v in settings.items() if k != "demos"}}
    config = {"planning": "zero"}
    if planning_steps:
        config = {"planning": "full", "planning_steps": planning_steps}
    request = RunRequest(
        task="arm-reach",
        reach=reach,
        config={**config, "max_steps_per_episode": CAP},
        experiments=1,
        episodes=episodes,
        seed=seed,
        demonstrations=demos if settings.get("demos", True) else (),
    )
    record = resolve_run(request)
    return train_learner(record, LiveProgress(1, episodes), workers=1)


def dyna_rows(task, demos, starts, pace, arm, budgets, seed, planning_steps) -> list[Row]:
    goal = tuple(task.goal)
    rows = []
    for name, settings in DYNA_ROWS.items():
        reached_at = "not in " + f"{budgets[-1]:,} episodes"
        for episodes in budgets:
            result = dyna_run(settings, demos, goal, episodes, seed, planning_steps)
            walks = [
                greedy_rollout(result.task, result.coder, result.weights[0], s, CAP) for s in starts
            ]
            success = np.mean([r for _, r in walks])
            if success >= SUCCESS and reached_at.startswith("not"):
                reached_at = f"{int(result.steps[0].sum()):,} ({episodes} episodes)"
        replayed = len(demos) if settings.get("demos", True) else 0
        first = int(result.steps[0][replayed : replayed + FIRST_OWN].sum())
        cpu = float(result.cpu_seconds.sum())
        rows.append(judge(name, walks, result.task, pace, arm, reached_at, cpu, first))
        if hand_over_action(result.task) >= 0:  # the same greedy policy, never handing over
            alone = greedy_success(
                result.task, result.coder, result.weights[0], starts, CAP, hand_over=False
            )
            rows[-1].alone = float(alone.mean())
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=1000, help="the largest budget")
    parser.add_argument("--starts", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--planning-steps", type=int, default=0, help="0: zero planning")
    parser.add_argument("--quick", action="store_true", help="a tiny run for tests")
    args = parser.parse_args()
    episodes, starts_n = (30, 10) if args.quick else (args.episodes, args.starts)
    budgets = [episodes] if args.quick else sorted({max(8, episodes // d) for d in (8, 4, 2, 1)})
    demos = demonstrations()
    task = ArmReach(**SPLIT, goal=tuple(demos[0].q_robot[-1]), robot=ROBOT)
    follow = ArmReach(**SPLIT, goal=task.goal, actions="follow").with_paths(
        [d.q_robot for d in demos]
    )
    pace = demonstrated_pace(follow, [(d.times, d.q_robot) for d in demos])
    rng = np.random.default_rng([args.seed, 99])
    arm = load_robot(ROBOT)
    drawn = 0
    starts_list: list[np.ndarray] = []
    while len(starts_list) < starts_n:  # held-out starts the robot can stand in: a collision
        start = task.random_start(rng)  # counted below is one the motion makes
        drawn += 1
        if not arm.contacts(task.full_q(start)):
            starts_list.append(start)
    starts = np.array(starts_list)
    print(
        f"Puma560, {JOINTS} joints, goal: {SAMPLES[0]}'s end (tool within 2 cm, orientation free), "
        f"the paper's reward (+100 at the goal, -1 a step), {len(SAMPLES)} samples as "
        f"demonstrations, {starts_n} held-out starts, budgets {budgets} episodes, "
        f"{'zero planning' if not args.planning_steps else f'{args.planning_steps} planning steps'}, "
        f"pace {pace:.3f} s a step"
    )
    print(
        f"{starts_n} collision-free starts of {drawn} drawn ({1 - starts_n / drawn:.1%} of the "
        "task's random starts touch the robot itself or the table and are drawn again)"
    )
    rows = baseline_rows(task, demos, starts, pace, arm)
    rows += dyna_rows(task, demos, starts, pace, arm, budgets, args.seed, args.planning_steps)
    teacher = rows[0]
    print(
        "\n| row | success | collisions | mean time to the goal (s) | x teacher's | real steps to 95% | CPU s |"
    )
    print("|---|---|---|---|---|---|---|")
    for row in rows:
        ratio = row.mean_seconds / teacher.mean_seconds
        time_s = "-" if row.mean_seconds != row.mean_seconds else f"{row.mean_seconds:.2f}"
        ratio_s = "-" if ratio != ratio else f"{ratio:.2f}"
        print(
            f"| {row.name} | {row.success:.1%} | {row.collisions:.1%} | {time_s} | {ratio_s} | "
            f"{row.steps_to_95} | {row.cpu:.2f} |"
        )
    best = [
        r
        for r in rows[3:]
        if r.success >= teacher.success and r.mean_seconds <= 0.9 * teacher.mean_seconds
    ]
    print(
        f"\nBetter than its teacher (success >= {teacher.success:.1%}, mean time <= "
        f"{0.9 * teacher.mean_seconds:.2f} s): "
        + (", ".join(r.name for r in best) if best else "no Dyna-Q row")
    )
    for row in rows:
        if row.alone is not None:
            print(
                f"{row.name}: without the hand-over to the follow action where its moves loop, "
                f"its greedy policy reaches the goal from {row.alone:.1%} of the starts"
            )
    without = next(r for r in rows if r.name == "Dyna-Q, no demonstrations").first_own
    for row in rows[4:]:
        if row.first_own is not None and without and "any joints" not in row.name:
            print(
                f"First {FIRST_OWN} own episodes, {row.name}: {row.first_own:,} real steps, "
                f"{row.first_own / without:.3f}x those without demonstrations ({without:,})"
            )


if __name__ == "__main__":
    main()
