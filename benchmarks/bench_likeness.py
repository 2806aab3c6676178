"""Likeness of the movement-primitive baseline to each shipped sample demonstration.

Measures, in one run (``python benchmarks/bench_likeness.py``, about 10 s on one free core), for
each ``studio/samples/sample-reach-*.demo.json``:

1. The DMP (``fit_movement_primitive``, ``DMP_BASIS`` basis functions per joint) rolled out from
   the demonstration's own start to its own end at its sample rate, against two baselines on the
   same samples: straight-line joint interpolation over the same duration, and a minimum-jerk
   straight line. Figures: joint-space DTW per sample on the demonstration's learned joints (its
   grid's 3; goal <= 0.02 rad) and on all six, and the tool path's discrete Fréchet distance.
   The wrist joints of the samples carry sample-to-sample jitter of up to 0.07 rad (fit noise near
   the wrist singularity); the "jitter floor" column is the six-joint DTW of a 9-sample moving
   average of the demonstration itself, which no smooth motion can beat.
2. The likeness card of the DMP policy (``dmp_likeness_card``: 50 Hz, from the demonstration's
   start), the demonstration's own values beside the policy's.
3. New starts: 20 starts drawn around the demonstration's start (+-0.5 rad per joint), each
   rolled to the demonstration's goal: how many arrive, their LDLJ and their duration.
4. CPU time of one fit + rollout against the straight line's, interleaved, median of 5 (the
   machine is shared: treat the times as rough).
5. The learned policy (``--learned``, a few minutes): the continuous task with its defaults
   (six joints, the default action set and shaping, the default features), its goal the
   demonstration's last pose, trained on that one demonstration (zero planning,
   ``--episodes`` episodes (:data:`LEARN_EPISODES`), one experiment per seed in
   :data:`LEARN_SEEDS`), rolled out from the demonstration's start and scored on the likeness
   card; also its greedy success from 200 random starts. Goals: DTW <= 0.05 rad per sample on
   all six joints, LDLJ within 20% of the demonstration's. For comparison: the same with the
   other action sets (the pairs, and ``follow``: one joint, or all of them along the
   demonstration), and (``--path-potential``) with the
   demonstrations' potential over the whole demonstrated path (kappa 2, weight 5 on top of the
   task's shaping; :mod:`studio.learning.tasks._demo_shaping`), which pulls the greedy path along the
   demonstration rather than only to its end.
6. The card's smoothness against the tape's noise (``--noise``, about a minute): NOISE_REACHES
   simulated reaches, each recorded twice, with the tape's sensor noise and without it (the same
   motion, its tremor kept), cut into demonstrations; per way of measuring LDLJ (the card's: the
   tool path low-passed at ``LDLJ_CUTOFF_HZ``; the baseline: the six joints unfiltered, the card's
   form before), the median and largest change the noise makes, and the ratio of the medians.
   Other cutoffs and the first three joints are printed beside them, and the card's SPARC.

LDLJ everywhere here is the card's (``ldlj`` of the tool path, low-passed at ``LDLJ_CUTOFF_HZ``).
"""

from __future__ import annotations

import argparse
import functools
import tempfile
import time
from pathlib import Path

import gymnasium
import numpy as np

import studio.learning.linear._linear as linear
from studio.capture import (
    Demonstration,
    OperatorConfig,
    RecordingWriter,
    goal_configuration,
    load_demonstration,
    read_recording,
    simulate,
)
from studio.learning import (
    ACTION_SETS,
    DMP_BASIS,
    ArmGrid,
    ArmReach,
    DynaQConfig,
    TilePolicyFile,
    demonstrated_pace,
    dmp_likeness_card,
    dtw_distance,
    fit_dmp_policy,
    fit_movement_primitive,
    frechet_distance,
    ldlj,
    policy_likeness_card,
    puma_tool_positions,
    roll_out_primitive,
    rollout_dmp_policy,
    run_experiments,
    sparc,
)
from studio.learning.likeness._likeness import LDLJ_CUTOFF_HZ
from studio.learning.linear._linear import greedy_success
from studio.motion import extract_demonstration

SAMPLES = sorted((Path(__file__).resolve().parents[1] / "studio" / "samples").glob("*.demo.json"))
GOAL_DTW_RAD = 0.02
NEW_STARTS = 20
START_SPREAD_RAD = 0.5
REPEATS = 5
GOAL_POLICY_DTW_RAD = 0.05
GOAL_LDLJ_SHARE = 0.2
LEARN_EPISODES = 3000
LEARN_SEEDS = (0, 1, 2)
CAP = 3_000


def straight(times: np.ndarray, q: np.ndarray, min_jerk: bool) -> np.ndarray:
    u = (times - times[0]) / (times[-1] - times[0])
    if min_jerk:
        u = u**3 * (10.0 - 15.0 * u + 6.0 * u**2)
    return q[0] + u[:, None] * (q[-1] - q[0])


def moving_average(q: np.ndarray, width: int = 9) -> np.ndarray:
    padded = np.pad(q, ((width // 2, width // 2), (0, 0)), mode="edge")
    kernel = np.ones(width) / width
    return np.column_stack([np.convolve(c, kernel, mode="valid") for c in padded.T])


def reproduction(path: Path) -> bool:
    demo = load_demonstration(path)
    times, q, k = demo.times, demo.q_robot, demo.grid["joints"]
    rate = (len(times) - 1) / (times[-1] - times[0])
    _, dmp = roll_out_primitive(fit_movement_primitive(times, q), rate_hz=rate)
    tool = puma_tool_positions(q)
    rows = {
        "DMP": dmp,
        "straight line": straight(times, q, False),
        "min-jerk line": straight(times, q, True),
    }
    print(f"\n{path.name}: {len(times)} samples, {times[-1] - times[0]:.2f} s, {k} learned joints")
    print(f"  {'':<16}{'DTW 3 joints':>14}{'DTW 6 joints':>14}{'Frechet (m)':>13}{'LDLJ':>8}")
    for name, path_q in rows.items():
        print(
            f"  {name:<16}{dtw_distance(path_q[:, :k], q[:, :k]):>14.4f}"
            f"{dtw_distance(path_q, q):>14.4f}"
            f"{frechet_distance(puma_tool_positions(path_q), tool):>13.4f}"
            f"{ldlj(np.arange(len(path_q)) / rate, puma_tool_positions(path_q)):>8.2f}"
        )
    floor = dtw_distance(moving_average(q), q)
    print(f"  {'demonstration':<16}{0:>14.4f}{0:>14.4f}{0:>13.4f}{ldlj(times, tool):>8.2f}")
    print(f"  jitter floor (6 joints, a smoothed copy of the demonstration): {floor:.4f} rad")
    ok = dtw_distance(dmp[:, :k], q[:, :k]) <= GOAL_DTW_RAD
    print(
        f"  goal: DMP DTW on the learned joints <= {GOAL_DTW_RAD} rad: {'met' if ok else 'MISSED'}"
    )
    return ok


def card_and_new_starts(path: Path) -> None:
    demo = load_demonstration(path)
    policy = fit_dmp_policy(demo.times, demo.q_robot, learned_joints=demo.grid["joints"])
    print(f"\n{path.name}: likeness card of the DMP policy (50 Hz, from the demonstration's start)")
    print("  " + dmp_likeness_card(policy).text().replace("\n", "\n  "))
    rng = np.random.default_rng(0)
    reached, smooth, durations = 0, [], []
    for _ in range(NEW_STARTS):
        start = demo.q_robot[0] + rng.uniform(-START_SPREAD_RAD, START_SPREAD_RAD, 6)
        times, q, ok = rollout_dmp_policy(policy, start)
        reached += ok
        smooth.append(ldlj(times, puma_tool_positions(q)))
        durations.append(times[-1])
    print(
        f"  from {NEW_STARTS} new starts: {reached}/{NEW_STARTS} reach the goal joints, "
        f"LDLJ median {np.median(smooth):.2f}, duration median {np.median(durations):.2f} s"
    )


def timing(path: Path) -> None:
    demo = load_demonstration(path)
    dmp_s, line_s = [], []
    for _ in range(REPEATS):
        start = time.process_time()
        roll_out_primitive(fit_movement_primitive(demo.times, demo.q_robot), rate_hz=50.0)
        dmp_s.append(time.process_time() - start)
        start = time.process_time()
        straight(demo.times, demo.q_robot, True)
        line_s.append(time.process_time() - start)
    dmp, line = np.median(dmp_s), np.median(line_s)
    print(
        f"\nCPU per fit + rollout ({DMP_BASIS} basis functions, 6 joints): DMP {dmp * 1e3:.1f} ms, "
        f"min-jerk line {line * 1e3:.3f} ms (ratio {dmp / max(line, 1e-9):.0f}x; shared machine, rough)"
    )


def path_potential() -> None:
    """Every later run: the demonstrations' potential along their whole path (kappa 2), weight 5
    beyond the task's own shaping."""
    from studio.learning.tasks._demo_shaping import demo_potential

    shaping = ArmReach().shaping
    linear.demo_potential = functools.partial(demo_potential, weight=5.0 + shaping, kappa=2.0)


def learned(path: Path, actions: str | None, episodes: int) -> tuple[int, int]:
    """The learned policy's card figures against one sample; returns (seeds meeting both goals, seeds)."""
    demo = load_demonstration(path)
    settings = {} if actions is None else {"actions": actions}
    task = ArmReach(goal=tuple(demo.q_robot[-1]), **settings)
    starts = np.array([task.random_start(np.random.default_rng([k, 7])) for k in range(200)])
    config = DynaQConfig(planning="zero", max_steps_per_episode=CAP)
    make = lambda: gymnasium.make(  # noqa: E731
        "TeachStudio/ArmReach-v0", goal=task.goal, **settings
    )
    met = 0
    label = task.actions + (" (the default)" if actions is None else "")
    for seed in LEARN_SEEDS:
        result = run_experiments(
            make, config, 1, episodes, seed, [demo.q_robot], task.features(), workers=1
        )
        policy = TilePolicyFile(  # result.task: with the demonstration when it follows it
            coder=result.coder,
            weights=result.weights[0],
            config=config,
            task=result.task,
            seconds_per_step=demonstrated_pace(result.task, [(demo.times, demo.q_robot)]),
        )
        success = greedy_success(result.task, result.coder, result.weights[0], starts, CAP)
        card = policy_likeness_card(policy, demo.times, demo.q_robot)
        share = abs(card.policy.ldlj - card.demonstration.ldlj) / abs(card.demonstration.ldlj)
        ok = card.dtw_rad <= GOAL_POLICY_DTW_RAD and share <= GOAL_LDLJ_SHARE
        met += ok
        print(
            f"  {path.name} {label:<16} seed {seed}: DTW {card.dtw_rad:.3f} rad/sample, "
            f"LDLJ {card.policy.ldlj:.2f} (demonstration {card.demonstration.ldlj:.2f}, "
            f"{100 * share:.0f}% off), SPARC {card.policy.sparc:.2f} ({card.demonstration.sparc:.2f}), "
            f"together {100 * card.policy.together:.0f}% "
            f"(demonstration {100 * card.demonstration.together:.0f}%), duration "
            f"{card.policy.duration_s:.1f} s ({card.demonstration.duration_s:.1f} s), greedy "
            f"success {success.mean():.2f}, CPU {result.cpu_seconds[0]:.1f} s: "
            f"{'both goals met' if ok else 'goal missed'}",
            flush=True,
        )
    return met, len(LEARN_SEEDS)


NOISE_REACHES = 20
NOISE_SEEDS = range(11, 11 + NOISE_REACHES)
NOISE_CUTOFFS = (None, 3.0, 6.0, LDLJ_CUTOFF_HZ, 15.0)


def recorded_twice(seed: int, folder: Path) -> tuple[Demonstration, Demonstration]:
    """One simulated reach cut into a demonstration from a tape with and without sensor noise."""
    grid, demos = ArmGrid(), []
    for noise in (OperatorConfig().noise_rad, 0.0):
        sim = simulate(
            3.5, seed=seed, goal=goal_configuration(grid), operator=OperatorConfig(noise_rad=noise)
        )
        path = folder / f"reach-{seed}-{noise}.tape.csv"
        with RecordingWriter(path, config=sim.config, source="simulator") as writer:
            writer.write_many(sim.frames)
        rec = read_recording(path)
        demos.append(extract_demonstration(rec, sim.reach_start / 110, rec.duration, grid=grid))
    return demos[0], demos[1]


def noise() -> None:
    """Section 6: how far the tape's noise moves each way of measuring LDLJ."""
    with tempfile.TemporaryDirectory() as folder:
        pairs = [recorded_twice(seed, Path(folder)) for seed in NOISE_SEEDS]
    spaces = {
        "tool path": puma_tool_positions,
        "six joints": lambda q: q,
        "joints 1-3": lambda q: q[:, :3],
    }
    print(
        f"LDLJ change the tape's noise makes, {len(pairs)} simulated reaches recorded with and "
        "without it (median, largest):"
    )
    medians = {}
    for label, space in spaces.items():
        paths = [[(d.times, space(d.q_robot)) for d in pair] for pair in pairs]
        for cutoff in NOISE_CUTOFFS:
            change = []
            for (t_noisy, noisy), (t_clean, clean) in paths:
                a = ldlj(t_noisy, noisy, cutoff_hz=cutoff)
                b = ldlj(t_clean, clean, cutoff_hz=cutoff)
                change.append(abs(a - b) / abs(b))
            medians[label, cutoff] = float(np.median(change))
            name = "unfiltered" if cutoff is None else f"low-pass {cutoff:g} Hz"
            mark = "  <- the card" if (label, cutoff) == ("tool path", LDLJ_CUTOFF_HZ) else ""
            mark = mark or ("  <- before" if (label, cutoff) == ("six joints", None) else "")
            print(
                f"  {label:<11}{name:<18}{100 * medians[label, cutoff]:>6.1f}%{100 * max(change):>7.1f}%{mark}"
            )
    tools = [[(d.times, puma_tool_positions(d.q_robot)) for d in pair] for pair in pairs]
    change = [abs(sparc(*noisy) / sparc(*clean) - 1) for noisy, clean in tools]
    print(
        f"  SPARC of the tool path (the card's other row) {100 * np.median(change):>6.1f}%{100 * max(change):>7.1f}%"
    )
    ours, before = medians["tool path", LDLJ_CUTOFF_HZ], medians["six joints", None]
    print(
        f"the card's median change {100 * ours:.1f}% against {100 * before:.1f}% before: ratio {before / ours:.1f}x"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--learned", action="store_true", help="only the learned policies (5)")
    parser.add_argument(
        "--path-potential", action="store_true", help="(5) with the potential along the path"
    )
    parser.add_argument("--episodes", type=int, default=LEARN_EPISODES, help="(5) episodes")
    parser.add_argument(
        "--actions",
        nargs="*",
        default=None,
        choices=ACTION_SETS,
        help="(5) action sets (default: the default, pairs, follow)",
    )
    parser.add_argument(
        "--noise",
        action="store_true",
        help="only the card's smoothness against the tape's noise (6)",
    )
    args = parser.parse_args()
    if args.noise:
        noise()
        return
    if args.path_potential:
        path_potential()
        print("with the demonstrations' potential along the whole path (kappa 2, weight 5)")
    if args.learned or args.path_potential:
        print(
            f"learned policies: {args.episodes} episodes, one demonstration, from its start; "
            f"goals DTW <= {GOAL_POLICY_DTW_RAD} rad/sample (six joints), LDLJ within "
            f"{GOAL_LDLJ_SHARE:.0%} of the demonstration's"
        )
        sets = args.actions or [None, "pairs", "follow"]
        for actions in [None] if args.path_potential else sets:
            met = [learned(path, actions, args.episodes) for path in SAMPLES]
            print(f"  met for {sum(m for m, _ in met)}/{sum(n for _, n in met)} policies\n")
        return
    fit_movement_primitive(np.arange(3.0), np.zeros((3, 1)))  # compile nothing, warm numpy
    dtw_distance(np.zeros((2, 1)), np.zeros((2, 1)))  # compile the numba kernels once
    frechet_distance(np.zeros((2, 1)), np.zeros((2, 1)))
    met = [reproduction(path) for path in SAMPLES]
    for path in SAMPLES:
        card_and_new_starts(path)
    timing(SAMPLES[0])
    print(f"\nreproduction goal met for {sum(met)}/{len(met)} sample demonstrations")


if __name__ == "__main__":
    main()
