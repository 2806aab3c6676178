"""Likeness metrics: exact small cases, the issue's sanity laws, and the card's two columns."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.learning import (
    LearningError,
    LikenessCard,
    dtw_distance,
    frechet_distance,
    ldlj,
    likeness_card,
    sparc,
)
from studio.learning.likeness._likeness import (
    joint_shares,
    js_divergence,
    moving_span,
    moving_together,
)


def min_jerk(u: np.ndarray) -> np.ndarray:
    return u**3 * (10.0 - 15.0 * u + 6.0 * u**2)


START = np.array([0.0, 0.2, -0.4])
END = np.array([1.0, -0.3, 0.5])


def reach(n: int = 200, duration: float = 2.0, warp: float = 1.0):
    """A minimum-jerk reach from START to END, sampled at ``u**warp`` of the way in time."""
    u = np.linspace(0.0, 1.0, n) ** warp
    return np.linspace(0.0, duration, n), START + min_jerk(u)[:, None] * (END - START)


def staircase(n_per_joint: int = 10, duration: float = 2.0):
    """The same start and end, one joint at a time in small constant-speed steps with stops."""
    points = [START.copy()]
    for j in range(3):
        for k in range(1, n_per_joint + 1):
            step = points[-1].copy()
            step[j] = START[j] + (END[j] - START[j]) * k / n_per_joint
            points += [step, step.copy()]  # move, then stop for as long
    q = np.repeat(np.array(points), 5, axis=0)
    for j in range(3):  # linear ramps between the held points (no teleporting)
        q[:, j] = np.convolve(np.pad(q[:, j], 2, mode="edge"), np.ones(5) / 5, mode="valid")
    return np.linspace(0.0, duration, len(q)), q


def test_dtw_exact_small_cases():
    assert dtw_distance([0.0, 1.0, 2.0], [0.0, 0.0, 1.0, 2.0]) == 0.0
    # pairs (0,0), (1,1): costs 0 and 1 over 2 pairs
    assert dtw_distance([[0.0], [1.0]], [[0.0], [2.0]]) == pytest.approx(0.5)
    # 2-D: a constant offset of (3, 4) is 5 per pair
    a = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])
    assert dtw_distance(a, a + [3.0, 4.0]) == pytest.approx(5.0)


def test_dtw_of_a_time_warped_copy_is_below_a_hundredth_of_a_radian():
    _, q = reach()
    _, warped = reach(warp=1.6)
    _, slower = reach(n=350)
    assert dtw_distance(q, warped) < 0.01
    assert dtw_distance(q, slower) < 0.01
    # and it does see a different path
    assert dtw_distance(q, q + 0.1) > 0.1


def test_frechet_exact_small_cases():
    assert frechet_distance([[0, 0], [1, 0]], [[0, 1], [1, 1]]) == pytest.approx(1.0)
    # the leash must span the far detour of the second path
    assert frechet_distance([[0, 0], [2, 0]], [[0, 0], [1, 3], [2, 0]]) == pytest.approx(
        math.hypot(1, 3)
    )
    path = np.random.default_rng(0).normal(size=(20, 3))
    assert frechet_distance(path, path) == 0.0


@settings(max_examples=30, deadline=None)
@given(st.integers(2, 15), st.integers(2, 15), st.integers(0, 10_000))
def test_frechet_bounds_dtw_and_endpoints(n, m, seed):
    rng = np.random.default_rng(seed)
    a, b = rng.normal(size=(n, 2)), rng.normal(size=(m, 2))
    d = frechet_distance(a, b)
    ends = max(np.linalg.norm(a[0] - b[0]), np.linalg.norm(a[-1] - b[-1]))
    assert d >= ends - 1e-12  # both walkers start and end together
    assert dtw_distance(a, b) <= d + 1e-12  # a mean along a coupling <= its max
    assert frechet_distance(b, a) == pytest.approx(d)


def reference_dtw(a: np.ndarray, b: np.ndarray) -> float:
    """Every monotone alignment's total and length by plain recursion over the full table."""
    n, m = len(a), len(b)
    best: dict[tuple[int, int], tuple[float, int]] = {(0, 0): (np.linalg.norm(a[0] - b[0]), 1)}
    for i in range(n):
        for j in range(m):
            if (i, j) == (0, 0):
                continue
            before = [best[p] for p in ((i - 1, j - 1), (i - 1, j), (i, j - 1)) if min(p) >= 0]
            total, steps = min(before, key=lambda x: x[0])
            best[i, j] = (total + np.linalg.norm(a[i] - b[j]), steps + 1)
    total, steps = best[n - 1, m - 1]
    return total / steps


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 9), st.integers(1, 9), st.integers(0, 10_000))
def test_dtw_matches_the_full_table_recursion(n, m, seed):
    rng = np.random.default_rng(seed)
    a, b = rng.normal(size=(n, 2)), rng.normal(size=(m, 2))
    assert dtw_distance(a, b) == pytest.approx(reference_dtw(a, b))


def test_js_divergence_exact_small_cases():
    assert js_divergence([1, 0], [0, 1]) == pytest.approx(1.0)
    assert js_divergence([0.3, 0.7], [0.3, 0.7]) == 0.0
    # p = (1, 0), q = (1/2, 1/2): m = (3/4, 1/4)
    expected = 0.5 * math.log2(4 / 3) + 0.5 * (0.5 * math.log2(2 / 3) + 0.5 * math.log2(2))
    assert js_divergence([1, 0], [0.5, 0.5]) == pytest.approx(expected)
    assert math.isnan(js_divergence([0, 0], [1, 0]))
    with pytest.raises(LearningError, match="same length"):
        js_divergence([1, 0], [1, 0, 0])


def test_minimum_jerk_is_smoother_than_a_staircase_between_the_same_points():
    t, q = reach()
    ts, qs = staircase()
    np.testing.assert_allclose(qs[0], q[0])
    np.testing.assert_allclose(qs[-1], q[-1])
    smooth, stairs = ldlj(t, q), ldlj(ts, qs)
    assert smooth > stairs + 3
    # the published value for a minimum-jerk reach: -ln(720 / 1.875^2) = -5.24
    assert smooth == pytest.approx(-math.log(720 / 1.875**2), abs=0.1)


def test_ldlj_does_not_depend_on_amplitude_or_duration():
    t, q = reach()
    assert ldlj(t * 3, q * 0.1, cutoff_hz=None) == pytest.approx(ldlj(t, q, cutoff_hz=None))
    # the low-pass is in hertz, so three times slower loses a little less to it
    assert ldlj(t * 3, q * 0.1) == pytest.approx(ldlj(t, q), rel=0.01)
    assert math.isnan(ldlj(t, np.zeros_like(q)))


def test_the_low_pass_removes_sensor_noise_and_keeps_the_reach():
    t, q = reach()
    rng = np.random.default_rng(0)
    noisy = q + rng.normal(0.0, 0.0002, q.shape)  # white, 0.01 degree a sample at 100 Hz
    clean = ldlj(t, q)
    assert ldlj(t, q, cutoff_hz=None) == pytest.approx(clean, abs=0.05)
    raw = ldlj(t, noisy, cutoff_hz=None)
    assert raw < clean - 5  # unfiltered, jerk measures the noise
    assert clean > ldlj(t, noisy) > clean - 0.35 * (clean - raw)
    # a cutoff at or above the rate's Nyquist frequency leaves the samples as they are
    assert ldlj(t, noisy, cutoff_hz=50.0) == ldlj(t, noisy, cutoff_hz=None)
    for bad in (0.0, -1.0, math.nan, "10"):
        with pytest.raises(LearningError, match="cutoff_hz"):
            ldlj(t, q, cutoff_hz=bad)


@pytest.fixture(scope="module")
def recorded_reach(tmp_path_factory):
    """The same simulated reach recorded by a tape with and without its sensor noise:
    ``{noise_rad: demonstration}``."""
    from studio.capture import (
        OperatorConfig,
        RecordingWriter,
        goal_configuration,
        read_recording,
        simulate,
    )
    from studio.learning import ArmGrid
    from studio.motion import extract_demonstration

    grid, folder, demos = ArmGrid(), tmp_path_factory.mktemp("noise"), {}
    for noise in (0.002, 0.0):
        operator = OperatorConfig(noise_rad=noise)
        sim = simulate(3.5, seed=11, goal=goal_configuration(grid), operator=operator)
        path = folder / f"reach-{noise}.tape.csv"
        with RecordingWriter(path, config=sim.config, source="simulator") as writer:
            writer.write_many(sim.frames)
        rec = read_recording(path)
        demos[noise] = extract_demonstration(rec, sim.reach_start / 110, rec.duration, grid=grid)
    return demos


def test_the_card_reads_a_recorded_reach_as_the_same_reach_without_the_tapes_noise(
    recorded_reach,
):
    from studio.learning import puma_tool_positions

    def card_ldlj(demo) -> float:
        card = likeness_card(
            demo.times, demo.q_robot, demo.times, demo.q_robot, puma_tool_positions
        )
        return card.demonstration.ldlj

    noisy, clean = recorded_reach[0.002], recorded_reach[0.0]
    np.testing.assert_array_equal(noisy.times, clean.times)
    assert abs(card_ldlj(noisy) - card_ldlj(clean)) < 0.2 * abs(card_ldlj(clean))
    # a demonstration cut from a recording is fitted with the future too (smoothed), so even
    # the joint-space form reads the two alike (it read the tape's noise 40-60% off before)
    raw_noisy, raw_clean = (ldlj(d.times, d.q_robot, cutoff_hz=None) for d in (noisy, clean))
    assert abs(raw_noisy - raw_clean) < 0.1 * abs(raw_clean)
    # noise left in a path (as live), the card still reads it as the clean one; that form not
    shaken = clean.q_robot + np.random.default_rng(0).normal(0.0, 0.004, clean.q_robot.shape)
    card = likeness_card(clean.times, shaken, clean.times, shaken, puma_tool_positions)
    assert abs(card.demonstration.ldlj - card_ldlj(clean)) < 0.2 * abs(card_ldlj(clean))
    raw_shaken = ldlj(clean.times, shaken, cutoff_hz=None)
    assert abs(raw_shaken - raw_clean) > 0.3 * abs(raw_clean)


def test_joint_shares_and_moving_together():
    t, q = reach()
    shares = joint_shares(q)
    np.testing.assert_allclose(shares, np.abs(END - START) / np.abs(END - START).sum())
    assert moving_together(t, q) > 0.9
    ts, qs = staircase()
    assert moving_together(ts, qs) < 0.1  # one joint at a time
    # the moving span leaves out the stillness a cut holds before and after the motion
    rate = 1.0 / (t[1] - t[0])
    held = np.arange(1, 51) / rate
    padded_t = np.r_[t[0] - held[::-1], t, t[-1] + held]
    padded_q = np.r_[[q[0]] * 50, q, [q[-1]] * 50]
    assert moving_span(padded_t, padded_q) <= t[-1] - t[0] + 1e-9
    assert moving_span(padded_t, padded_q) >= 0.8 * (t[-1] - t[0])  # the bell's slow ends
    assert moving_span(t, np.repeat(q[:1], len(t), axis=0)) == 0.0


def fake_tool(q: np.ndarray) -> np.ndarray:
    """A stand-in forward kinematics: the first three joints are the position."""
    return np.asarray(q)[:, :3]


def test_the_card_holds_the_policy_and_the_demonstration_side_by_side():
    t, q = reach()
    ts, qs = staircase()
    card = likeness_card(ts, qs, t, q, fake_tool)
    assert isinstance(card, LikenessCard)
    assert card.demonstration.ldlj == pytest.approx(ldlj(t, fake_tool(q)))
    assert card.policy.ldlj == pytest.approx(ldlj(ts, fake_tool(qs)))
    assert card.policy.sparc == pytest.approx(sparc(ts, fake_tool(qs)))
    assert card.demonstration.sparc > card.policy.sparc  # a reach against a staircase
    assert card.dtw_rad == pytest.approx(dtw_distance(qs, q))
    assert card.frechet_m == pytest.approx(frechet_distance(qs, q))
    assert card.policy.duration_s == pytest.approx(2.0)
    data = json.loads(json.dumps(card.to_dict()))
    assert set(data) == {"dtw_rad", "frechet_m", "shares_js", "policy", "demonstration"}
    assert data["policy"]["ldlj"] < data["demonstration"]["ldlj"]
    text = card.text()
    assert "DTW" in text and "LDLJ" in text and "demonstration" in text
    # the same motion is its own perfect likeness
    same = likeness_card(t, q, t, q, fake_tool)
    assert same.dtw_rad == 0.0 and same.frechet_m == 0.0 and same.shares_js == 0.0


def test_the_card_compares_only_the_learned_joints_when_asked():
    t, q = reach()
    noisy = q.copy()
    noisy[:, 2] += 0.2 * np.sin(np.arange(len(t)))
    card = likeness_card(t, noisy, t, q, fake_tool, joints=2)
    assert card.dtw_rad == 0.0
    assert len(card.policy.joint_shares) == 2
    assert card.frechet_m > 0  # the tool still sees every joint


def test_a_motionless_policy_gives_null_smoothness_not_an_error():
    t, q = reach()
    still = np.tile(q[0], (len(t), 1))
    data = likeness_card(t, still, t, q, fake_tool).to_dict()
    assert data["policy"]["ldlj"] is None and data["shares_js"] is None


def test_bad_input_gets_one_sentence():
    t, q = reach()
    with pytest.raises(LearningError, match="same joints"):
        likeness_card(t, q[:, :2], t, q, fake_tool)
    with pytest.raises(LearningError, match="increasing time"):
        likeness_card(t[::-1], q, t, q, fake_tool)
    bad = q.copy()
    bad[3, 1] = np.nan
    with pytest.raises(LearningError, match="finite"):
        dtw_distance(bad, q)


def test_every_policy_kind_gets_a_card_from_the_demonstrations_start(tmp_path):
    from studio.capture import load_demonstration
    from studio.learning import (
        ArmReach,
        DynaQConfig,
        TilePolicyFile,
        fit_dmp_policy,
        load_policy,
        policy_likeness_card,
    )
    from studio.learning.tabular._policy import save_policy
    from studio.motion import demonstration_grid
    from studio.samples import __file__ as samples

    demo = load_demonstration(Path(samples).parent / "sample-reach-2.demo.json")
    grid = demonstration_grid(demo)
    q_table = np.zeros((grid.n_states, grid.n_actions))
    save_policy(tmp_path / "grid.policy.npz", grid, q_table, DynaQConfig())
    task = ArmReach(joints=3)
    coding = task.features(tilings=2, tiles=4)
    coder = coding.bind(task.lower, task.upper)
    tile = TilePolicyFile(
        coder=coder, weights=np.zeros((coder.size, task.n_actions)), config=DynaQConfig(), task=task
    )
    dmp = fit_dmp_policy(demo.times, demo.q_robot, learned_joints=3)
    for policy in (load_policy(tmp_path / "grid.policy.npz"), tile, dmp):
        card = policy_likeness_card(policy, demo.times, demo.q_robot)
        assert len(card.policy.joint_shares) == 3 == len(card.demonstration.joint_shares)
        assert card.demonstration.duration_s == pytest.approx(demo.times[-1] - demo.times[0])
        assert math.isfinite(card.dtw_rad) and math.isfinite(card.frechet_m)
    # the primitive is far more like its demonstration than an untrained tile policy
    assert policy_likeness_card(dmp, demo.times, demo.q_robot).dtw_rad < 0.02
    assert policy_likeness_card(tile, demo.times, demo.q_robot).dtw_rad > 0.1
    with pytest.raises(LearningError, match=r"\(N, 6\)"):
        policy_likeness_card(dmp, demo.times, demo.q_robot[:, :3])


def test_sparc_tells_a_bell_shaped_speed_from_a_constant_pace():
    t, q = reach()
    bell = sparc(t, q)
    assert bell == pytest.approx(-1.40, abs=0.05)  # a minimum-jerk reach
    line = START + np.linspace(0.0, 1.0, len(t))[:, None] * (END - START)
    assert sparc(t, line) < bell - 0.5  # the same path at a constant pace, started abruptly
    ts, qs = staircase()
    assert sparc(ts, qs) < sparc(t, line)
    assert sparc(t * 3, q * 0.1) == pytest.approx(bell, abs=0.02)  # nor amplitude, nor duration
    assert math.isnan(sparc(t, np.zeros_like(q)))
    for cutoff in (0.0, -1.0, math.nan, "10"):
        with pytest.raises(LearningError, match="cutoff_hz"):
            sparc(t, q, cutoff_hz=cutoff)
    for threshold in (0.0, 1.0, math.inf):
        with pytest.raises(LearningError, match="threshold"):
            sparc(t, q, threshold=threshold)


def test_the_cards_sparc_barely_moves_with_the_tapes_noise(recorded_reach):
    from studio.learning import puma_tool_positions

    noisy, clean = recorded_reach[0.002], recorded_reach[0.0]
    values = [
        likeness_card(
            d.times, d.q_robot, d.times, d.q_robot, puma_tool_positions
        ).demonstration.sparc
        for d in (noisy, clean)
    ]
    assert values[0] == pytest.approx(values[1], rel=0.05)
