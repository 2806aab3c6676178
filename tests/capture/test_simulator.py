"""The simulated operator: reproducible, natural (minimum-jerk), on the tape's forward model."""

from __future__ import annotations

import time

import numpy as np
import pytest

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
    bend, twist = tape_from_arm(HumanArm(sim.config.side), sim.q_human, sim.config, in_time=True)
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


def _read_with_times(source, count: int) -> tuple[list, list[float]]:
    """Read ``count`` frames (or give up after a generous wait); each with a time it was read.
    A late source hands over several frames in one read: those past ``count`` are left out."""
    got: list = []
    read_at: list[float] = []
    deadline = time.monotonic() + 30.0  # only a hung source reaches this
    while len(got) < count and time.monotonic() < deadline:
        frames = source.read(timeout=0.05)
        now = time.monotonic()  # after the frames were released: an upper bound on their release
        got += frames
        read_at += [now] * len(frames)
    return got[:count], read_at[:count]


def test_live_source_keeps_110_hz_without_drops():
    """Paced on absolute deadlines (frame k no earlier than start + k / 110 s), every frame, in
    order, stamped with its own time k / 110. A busy machine can only make frames late, which
    the deadlines catch up without drops; nothing here depends on how fast the machine is."""
    source = SimulatorSource(seed=0)
    before = time.monotonic()
    source.start()
    try:
        got, read_at = _read_with_times(source, 165)  # 1.5 s of frames
    finally:
        source.stop()
    status = source.status()
    assert status.dropped == 0 and status.error is None
    assert [f.frame for f in got] == list(range(165))
    assert [f.t for f in got] == pytest.approx([k / 110 for k in range(165)], abs=1e-12)
    # paced, not dumped: no frame is out before its deadline (to the clock's resolution)
    early = [k for k, at in enumerate(read_at) if at - before < k / 110 - 1e-6]
    assert early == []
    assert read_at[-1] - before >= 164 / 110  # 1.5 s of frames took at least 1.5 s


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


def test_tremor_is_a_small_8_to_12_hz_oscillation_on_the_motion():
    still = simulate(4.0, seed=5, operator=OperatorConfig(tremor_rad=0.0))
    shaky = simulate(4.0, seed=5)
    tremor = shaky.q_human - still.q_human  # same seed: the same motion, plus the tremor
    amplitude = OperatorConfig().tremor_rad
    assert 0.3 * amplitude < np.abs(tremor).max() <= amplitude + 1e-12
    window = np.hanning(tremor.shape[0])[:, None]
    spectrum = (np.abs(np.fft.rfft(tremor * window, axis=0)) ** 2).sum(axis=1)  # power
    freqs = np.fft.rfftfreq(tremor.shape[0], 1 / 110)
    band = (freqs >= 7.5) & (freqs <= 12.5)
    assert spectrum[band].sum() > 0.95 * spectrum.sum()


def _still_runs(q: np.ndarray) -> list[int]:
    """Lengths (frames) of the runs of identical consecutive poses."""
    same = np.all(np.diff(q, axis=0) == 0, axis=1)
    edges = np.diff(np.concatenate([[0], same.astype(np.int8), [0]]))
    return list(np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1) + 1)


def test_the_operator_pauses_between_movements_as_configured():
    op = OperatorConfig(tremor_rad=0.0, pause_probability=1.0, pause_seconds=(0.3, 0.5))
    runs = _still_runs(simulate(10.0, seed=2, operator=op).q_human)
    long_runs = [r for r in runs if r > 2]
    assert len(long_runs) >= 3  # a pause after every movement
    assert all(0.3 * 110 - 2 <= r <= 0.5 * 110 + 2 for r in long_runs)
    never = OperatorConfig(tremor_rad=0.0, pause_probability=0.0)
    assert max(_still_runs(simulate(10.0, seed=2, operator=never).q_human), default=0) <= 2


@pytest.mark.parametrize("goal", [(5, 6, 2), (3, 7, 4)])
def test_goal_configuration_is_in_the_goal_bin_and_mirrors_off_the_arm_limits(goal):
    from studio.capture import goal_configuration
    from studio.capture._simulator import GOAL_MARGIN_RAD
    from studio.kinematics import Retargeter
    from studio.learning import ArmGrid

    grid = ArmGrid(goal=goal)
    q_robot = goal_configuration(grid)
    assert grid.state_of_angles(q_robot[:3]) == grid.goal_state
    retargeter = Retargeter("joint", mirror=True)
    q_human = retargeter.human_from_robot(q_robot)
    arm = retargeter.arm
    assert np.all(q_human >= arm.lower + GOAL_MARGIN_RAD - 1e-9)
    assert np.all(q_human <= arm.upper - GOAL_MARGIN_RAD + 1e-9)


def test_a_given_retargeter_and_its_arm_are_the_ones_the_simulated_operator_uses():
    """``simulate(retargeter=...)`` used to hand the retargeter over as the operator's arm."""
    from studio.kinematics import HumanArm, Retargeter, tape_from_arm

    retargeter = Retargeter("joint", mirror=True, arm=HumanArm("left"))
    sim = simulate(0.5, seed=3, retargeter=retargeter)
    bend, _ = tape_from_arm(retargeter.arm, sim.q_human, sim.config, in_time=True)
    measured = np.stack([f.bend for f in sim.frames])
    assert np.abs(measured - bend).max() < 6 * OperatorConfig().noise_rad
    motion = SimulatorSource(seed=3, retargeter=retargeter)._sim.motion
    assert motion.retargeter is retargeter and motion.arm is retargeter.arm


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_simulated_tape_reads_each_bend_continuously_in_time(seed: int) -> None:
    """A region at +-90 degrees of twist reads (b, 90) or (-b, -90), the same shape; the regions
    after it flip their bends' sign with it. A real tape's readings move continuously, and the
    simulator's must too (the shipped samples flipped five regions' bends by up to 190 degrees
    from one frame to the next), also across the chunks a live source makes them in."""
    frames = simulate(10.0, seed=seed).frames
    bend = np.array([f.bend for f in frames])
    # the operator's fastest bend at 110 Hz plus the sensor noise is a few hundredths of a
    # radian; a region passing through straight may still flip the small bends after it
    # (tenths), where the readings of each pose on its own jump by up to 3.3 rad
    assert np.abs(np.diff(bend, axis=0)).max() < 0.3
    # the same readings whether made in one go or in a live source's chunks
    source = SimulatorSource(seed=seed)
    chunks = []
    while sum(len(c) for c in chunks) < len(frames):
        chunks.append(source._sim.next(37)[0])
    streamed = np.array([f.bend for c in chunks for f in c][: len(frames)])
    np.testing.assert_allclose(streamed, bend)
