"""The simulated operator: reproducible, natural (minimum-jerk), on the tape's forward model."""

from __future__ import annotations

import time

import numpy as np

from studio.capture import SimulatorSource, simulate
from studio.capture._simulator import OperatorConfig, minimum_jerk


def test_same_seed_same_frames_different_seed_different_frames():
    a, b, c = simulate(1.0, seed=4), simulate(1.0, seed=4), simulate(1.0, seed=5)
    assert all(x.same_as(y) for x, y in zip(a.frames, b.frames, strict=True))
    assert not np.array_equal(a.frames[50].bend, c.frames[50].bend)
    assert [f.frame for f in a.frames] == list(range(110))
    assert np.allclose([f.t for f in a.frames], np.arange(110) / 110)


def test_frames_are_the_tape_model_of_the_true_pose_plus_small_noise():
    from studio.kinematics import HumanArm, tape_from_arm

    sim = simulate(1.0, seed=2)
    bend, twist = tape_from_arm(HumanArm(sim.config.side), sim.q_human, sim.config)
    measured = np.stack([f.bend for f in sim.frames])
    noise = OperatorConfig().noise_rad
    assert np.abs(measured - bend).max() < 6 * noise
    assert 0.5 * noise < np.std(measured - bend) < 2 * noise


def test_motion_is_smooth_and_stays_in_the_arm_limits():
    from studio.kinematics import HumanArm

    sim = simulate(6.0, seed=1)
    arm = HumanArm()
    assert (sim.q_human >= arm.lower - 0.01).all() and (sim.q_human <= arm.upper + 0.01).all()
    speed = np.abs(np.diff(sim.q_human, axis=0)) * 110
    assert speed.max() < 6.0  # rad/s: a human reach, not a jump
    assert np.ptp(sim.q_human, axis=0).max() > 0.3  # and it does move


def test_minimum_jerk_profile():
    s = np.linspace(0, 1, 101)
    p = minimum_jerk(s)
    assert p[0] == 0 and p[-1] == 1 and np.all(np.diff(p) >= 0)
    assert abs(p[50] - 0.5) < 1e-12  # symmetric
    v = np.gradient(p, s)
    assert abs(v[0]) < 1e-3 and abs(v[-1]) < 1e-3  # starts and ends at rest


def test_live_source_keeps_110_hz_without_drops():
    source = SimulatorSource(seed=0)
    source.start()
    got = []
    deadline = time.monotonic() + 1.0
    while time.monotonic() < deadline:
        got += source.read(timeout=0.05)
    source.stop()
    status = source.status()
    assert status.dropped == 0 and status.error is None
    assert [f.frame for f in got] == list(range(len(got)))
    assert 60 < len(got) < 160  # paced near 110 Hz, not dumped


def test_live_source_gives_the_generator_frames():
    source = SimulatorSource(seed=7)
    source.start()
    got = []
    deadline = time.monotonic() + 5.0
    while len(got) < 40 and time.monotonic() < deadline:
        got += source.read(timeout=0.05)
    source.stop()
    expected = simulate(1.0, seed=7).frames
    assert len(got) >= 40
    assert all(a.same_as(b) for a, b in zip(got, expected, strict=False))


def test_reach_ends_where_the_robot_goal_mirrors_to():
    from studio.kinematics import Retargeter

    goal = np.array([0.3, 0.4, -1.2, 0.1, 0.2, 0.0])
    sim = simulate(4.0, seed=3, goal=goal)
    retarget = Retargeter("joint", mirror=True)
    assert np.allclose(retarget.robot_from_human(sim.q_human[-1]), goal, atol=0.01)
    assert sim.reach_start < sim.reach_end <= len(sim.frames)
    assert sim.frames[-1].trigger and not sim.frames[0].trigger  # the trigger marks the reach
