"""Safety: no checked export exceeds a limit; a colliding pose, an over-speed segment and a
target out of reach are each refused in one sentence naming what and where."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.export import (
    Motion,
    SafetyError,
    check_trajectory,
    export_motion,
    recording_motion,
)
from studio.kinematics import HumanArm, load_robot

from .conftest import write_arm_recording
from .test_roundtrip import read_csv

PUMA = load_robot("puma560")


def _within_limits(robot, rows: np.ndarray) -> None:
    """An independent check of a written CSV: positions, velocities, accelerations."""
    t, q = rows[:, 0], rows[:, 1:]
    assert (q >= robot.lower - 1e-6).all() and (q <= robot.upper + 1e-6).all()
    if len(t) > 1:
        v = np.diff(q, axis=0) / np.diff(t)[:, None]
        assert (np.abs(v) <= robot.velocity * (1 + 1e-5)).all()
    if len(t) > 2:
        a = np.diff(v, axis=0) / ((t[2:] - t[:-2]) / 2)[:, None]
        assert (np.abs(a) <= robot.acceleration * (1 + 1e-5)).all()


@settings(max_examples=25, deadline=None)
@given(
    waypoints=st.lists(
        st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6), min_size=2, max_size=6
    ),
    rate=st.sampled_from([25.0, 50.0, 110.0]),
    fraction=st.floats(0.2, 1.0),
)
def test_no_checked_export_exceeds_a_limit(waypoints, rate, fraction, tmp_path_factory):
    q = PUMA.lower + (np.array(waypoints) + 1.0) / 2.0 * (PUMA.upper - PUMA.lower)
    motion = Motion("policy", "random", PUMA, np.zeros(len(q)), q, False, rate)
    out = tmp_path_factory.mktemp("prop") / "t.csv"
    try:
        export_motion(motion, "csv", out, fraction=fraction)
    except SafetyError:
        assert not out.exists()  # refused: nothing written
        return
    _within_limits(PUMA, read_csv(out)[1])


def test_a_path_in_the_middle_of_the_range_is_exported(tmp_path):
    q = np.array([np.zeros(6), np.full(6, 0.5), np.full(6, -0.3)])
    done = export_motion(
        Motion("policy", "p", PUMA, np.zeros(3), q, False, 50.0), "csv", tmp_path / "t.csv"
    )
    assert not done.findings and done.timed_by == "toppra"
    _within_limits(PUMA, read_csv(tmp_path / "t.csv")[1])
    assert np.allclose(done.q[0], q[0]) and np.allclose(done.q[-1], q[-1])


def test_an_over_speed_segment_is_refused_naming_the_joint_and_the_sample(tmp_path):
    t = np.arange(401) / 100.0
    s = t / t[-1]
    q = np.zeros((len(t), 6))
    q[:, 2] = 1.0 * (10 * s**3 - 15 * s**4 + 6 * s**5)
    q[200:, 2] += np.clip((t[200:] - 2.0) / 0.1, 0.0, 1.0) * 0.2  # 2 rad/s for 0.1 s at t = 2 s
    out = tmp_path / "fast.csv"
    out.write_text("an earlier export\n")
    motion = Motion("policy", "fast", PUMA, t, q, True, 100.0)
    with pytest.raises(SafetyError) as err:
        export_motion(motion, "csv", out)
    message = str(err.value)
    assert "\n" not in message and message.endswith(".")
    assert "sample 200 (t = 2.000 s): joint joint3 acceleration" in message
    assert "--unchecked" in message
    assert any(
        f.startswith("sample 201 (t = 2.010 s): joint joint3 velocity 2.469 rad/s")
        and f.endswith("exceeds its limit 1.000 rad/s by 1.469 rad/s")
        for f in err.value.findings
    )
    assert out.read_text() == "an earlier export\n"  # nothing already written lost


def test_a_colliding_pose_is_refused_naming_the_link_pair_and_the_margin(tmp_path):
    panda = load_robot("panda")
    rng = np.random.default_rng(7)
    while True:
        pose = rng.uniform(panda.lower, panda.upper)
        hits = panda.self_collisions(pose, 0.0)
        if hits:
            break
    q = np.repeat(pose[None], 11, axis=0)
    motion = Motion("recording", "still", panda, np.arange(11) / 10.0, q, True, 10.0)
    with pytest.raises(SafetyError) as err:
        export_motion(motion, "mcap", tmp_path / "c.mcap")
    message = str(err.value)
    assert "sample 0 (t = 0.000 s): links " in message
    assert "inside the 0.5 cm self-collision margin" in message
    pairs = {(h.link_a, h.link_b) for h in panda.self_collisions(pose, 0.005)}
    named = message.split("links ", 1)[1].split(" overlap")[0].split(" are ")[0]
    assert tuple(named.split(" and ")) in pairs
    assert not (tmp_path / "c.mcap").exists()
    assert check_trajectory(panda, motion.times, q)  # and the checks say the same


def test_a_target_out_of_reach_is_refused_naming_the_sample(tmp_path):
    arm = HumanArm()
    # a pose whose scaled hand the SO-100, facing the operator, cannot reach (12.8 cm off)
    pose = np.random.default_rng(0).uniform(arm.lower, arm.upper, size=(24, 7))[23]
    rec = write_arm_recording(tmp_path / "far.tape.csv", np.repeat(pose[None], 12, axis=0))
    motion = recording_motion(rec, "so100")
    with pytest.raises(SafetyError, match=r"frame \d+ \(t = [\d.]+ s of the source\): the hand's target is "
                       r"[\d.]+ cm out of the SO-100 \(LeRobot\)'s reach"):  # fmt: skip
        export_motion(motion, "csv", tmp_path / "far.csv")
    assert not (tmp_path / "far.csv").exists()


def test_a_path_along_a_joint_limit_never_overshoots_it(tmp_path):
    """Waypoints on a limit: a cubic spline through them bulges past it; the export must not."""
    up = PUMA.upper[0]
    q = np.zeros((5, 6))
    q[:, 0] = [0.0, 0.8 * up, up, up, 0.2 * up]
    q[:, 1] = [0.0, 0.1, 0.2, 0.3, 0.4]
    motion = Motion("policy", "edge", PUMA, np.zeros(5), q, False, 50.0)
    done = export_motion(motion, "csv", tmp_path / "edge.csv")
    assert not done.findings and done.q[:, 0].max() <= up
    _within_limits(PUMA, read_csv(tmp_path / "edge.csv")[1])


def test_a_path_that_comes_back_to_where_it_started_is_timed(tmp_path):
    """Thinning such a path (its turn within the path tolerance) can leave a step of zero
    length, which the spline cannot take."""
    a, b = np.zeros(6), np.full(6, 1e-3)
    q = np.array([a, b, a])
    done = export_motion(
        Motion("policy", "p", PUMA, np.zeros(len(q)), q, False, 50.0), "csv", tmp_path / "t.csv"
    )
    _within_limits(PUMA, read_csv(tmp_path / "t.csv")[1])
    assert np.allclose(done.q[0], a) and np.allclose(done.q[-1], a)
