"""Safety: no checked export exceeds a limit; a colliding pose, an over-speed segment and a
target out of reach are each refused in one sentence naming what and where."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.export import (
    ExportError,
    Motion,
    SafetyError,
    check_trajectory,
    export_motion,
    recording_motion,
    time_path,
)
from studio.export._timing import STILL_RAD
from studio.kinematics import TABLE, HumanArm, load_robot, robot_names

from .conftest import write_arm_recording
from .test_roundtrip import read_csv

PUMA = load_robot("puma560", geometry=False)
"""The Puma560's joints and limits without its collision geometry: these tests are about the
timing and the limits, over paths across its whole range, many of which fold its links into each
other (its self-collision and floor checks are tested in tests/kinematics/test_urdf.py)."""


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


def _across_range(robot, waypoints) -> np.ndarray:
    """Waypoints given from -1 (a joint's lower limit) to 1 (its upper limit), in radians."""
    return robot.lower + (np.asarray(waypoints, float) + 1.0) / 2.0 * (robot.upper - robot.lower)


def _export_exactly(q: np.ndarray, rate: float, fraction: float, out) -> np.ndarray:
    """Export the path ``q`` as a policy of the Puma560 and check what was written: no finding,
    every limit kept, from the first waypoint to the last (a path that never leaves its start
    by ``STILL_RAD`` is held still there). Returns the rows."""
    motion = Motion("policy", "random", PUMA, np.zeros(len(q)), q, False, rate)
    done = export_motion(motion, "csv", out, fraction=fraction)
    assert not done.findings and done.timed_by == "toppra"
    rows = read_csv(out)[1]
    _within_limits(PUMA, rows)
    assert np.abs(rows[0, 1:] - q[0]).max() <= 1e-7
    assert np.abs(rows[-1, 1:] - q[-1]).max() <= STILL_RAD + 1e-7
    return rows


@settings(max_examples=25, deadline=None)
@given(
    waypoints=st.lists(
        st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6), min_size=2, max_size=6
    ),
    rate=st.sampled_from([25.0, 50.0, 110.0]),
    fraction=st.floats(0.2, 1.0),
)
def test_no_checked_export_exceeds_a_limit(waypoints, rate, fraction, tmp_path_factory):
    """Every path through waypoints within the Puma560's joint limits is exported, and what is
    written keeps every limit from its first waypoint to its last.

    No refusal is legitimate here, neither a timing that fails (``ExportError``) nor a
    refusal by the checks (``SafetyError``): the timing keeps the velocities and accelerations
    within the limits and the curve within the waypoints' range, and :data:`PUMA` has no
    collision geometry (a colliding pose is refused in the test below)."""
    out = tmp_path_factory.mktemp("prop") / "t.csv"
    _export_exactly(_across_range(PUMA, waypoints), rate, fraction, out)


@settings(max_examples=25, deadline=None)
@given(
    name=st.sampled_from(robot_names()),
    data=st.data(),
    rate=st.sampled_from([25.0, 50.0, 110.0]),
    fraction=st.floats(0.2, 1.0),
)
def test_every_robot_times_every_path_within_its_limits(name, data, rate, fraction):
    arm = load_robot(name, geometry=False)
    count = data.draw(st.integers(2, 6), label="waypoints")
    joints = st.lists(st.floats(-1.0, 1.0), min_size=arm.nq, max_size=arm.nq)
    q = _across_range(arm, data.draw(st.lists(joints, min_size=count, max_size=count)))
    times, samples = time_path(arm, q, rate, fraction=fraction)
    assert check_trajectory(arm, times, samples) == []  # positions, velocities, accelerations
    assert np.abs(samples[-1] - q[-1]).max() <= STILL_RAD


# Paths the timing once failed on (the property tests found them), each for another reason.
TIMING_FAILED = {
    # TOPP-RA ran on the path's share in [0, 1]: along a path of half a milliradian, the
    # share's path speed squared is in the millions, beyond what its LP solver resolves
    "a path of half a milliradian": ([[0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 1e-4]], 25.0, 1.0),
    # every joint turns back at the middle waypoint, one at its limit: the curve that stays
    # within the limits stops there, and the LP solver lost every digit next to the stop
    "every joint turning back at once": (
        [[-0.3, -0.8, -1, -1, 0, -1], [-0.2, 1, 0.4, 0, 0.5, 0], [-1, 0, 0, -0.3, 0.4, -0.1]],
        50.0,
        0.8,
    ),
    # a sharp turn between two grid points: over the acceleration limit after every retiming
    "a sharp turn between grid points": (
        [
            [0, 0.13, 0.49, 0.92, -0.72, 0],
            [0, 0.16, 0, 0.75, 0.73, 0.45],
            [-0.78, -0.65, -0.65, 0, 0.82, 0.75],
            [-0.78, -0.65, -0.65, 0, 0.49, 0.75],
            [0.7, 0.49, -1, -0.12, 0.73, -0.46],
        ],
        50.0,
        0.8,
    ),
    # the spline bulged 0.3 mrad past joint 1's limit between the 400 points it was checked at
    "a spline past a limit between the points checked": (
        [
            [0.0958, 0.9098, 0, 0, 0, 0.008],
            [-0.9991, 0, 0, -0.5021, 0, 0],
            [0, 0.82, 0.5255, -0.5, 0, 0],
            [-0.8976, -0.1342, -0.0719, 0.1382, -0.6447, 0],
            [0.6135, 0, 0.5336, -0.7726, 0, 0.5622],
            [-0.3886, -1, 0.0055, 0, 0.5816, 0],
        ],
        110.0,
        0.27,
    ),
}


@pytest.mark.parametrize("case", sorted(TIMING_FAILED))
def test_a_path_the_timing_once_failed_on_is_exported(case, tmp_path):
    waypoints, rate, fraction = TIMING_FAILED[case]
    q = _across_range(PUMA, waypoints)
    rows = _export_exactly(q, rate, fraction, tmp_path / "t.csv")
    assert len(rows) > 1 and np.abs(rows[-1, 1:] - q[-1]).max() <= 1e-7  # it moved, to the end


def test_a_path_that_never_leaves_its_start_is_held_still_there(tmp_path):
    """Hypothesis's first failing example: a step of half a microradian, no motion any arm
    makes, is held still rather than refused."""
    q = _across_range(PUMA, [[0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 1.192092896e-07]])
    rows = _export_exactly(q, 25.0, 1.0, tmp_path / "t.csv")
    assert len(rows) == 1 and np.allclose(rows[0, 1:], q[0])


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
        and f.endswith("exceeds its limit 2.400 rad/s by 0.069 rad/s")
        for f in err.value.findings
    )
    assert out.read_text() == "an earlier export\n"  # nothing already written lost


def test_a_colliding_pose_is_refused_naming_the_link_pair_and_the_margin(tmp_path):
    panda = load_robot("panda")
    rng = np.random.default_rng(7)
    while True:
        pose = rng.uniform(panda.lower, panda.upper)
        hits = panda.self_collisions(pose, 0.0)
        if hits and not panda.table_contacts(pose, 0.005):  # the table is the next test's
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


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_a_pose_into_the_table_is_refused_naming_the_link_and_how_deep(name, tmp_path):
    """The robot stands on a table, the plane of its base: a hand or an elbow driven below it
    is refused as a collision is, though no two links touch."""
    arm = load_robot(name)
    rng = np.random.default_rng(3)
    while True:
        pose = rng.uniform(arm.lower, arm.upper)
        under = arm.table_contacts(pose, 0.0)
        if under and under[0].distance < -0.05 and not arm.self_collisions(pose, 0.005):
            break
    assert all(c.link_b == TABLE for c in under)
    q = np.repeat(pose[None], 11, axis=0)
    motion = Motion("recording", "low", arm, np.arange(11) / 10.0, q, True, 10.0)
    with pytest.raises(SafetyError) as err:
        export_motion(motion, "csv", tmp_path / "low.csv")
    message = str(err.value)
    deepest = under[0]
    assert (
        f"sample 0 (t = 0.000 s): link {deepest.link_a} reaches {-deepest.distance * 100:.2f} "
        "cm below the table top the robot stands on" in message
    )
    assert "--retime" not in message  # timing cannot lift a pose out of the table
    assert not (tmp_path / "low.csv").exists()


def test_a_target_out_of_reach_is_refused_naming_the_sample(tmp_path):
    arm = HumanArm()
    # a pose whose mapped hand the Z1 cannot reach (7.2 cm off; since the SO-100 keeps its
    # targets out of the column around its first axis, it reaches every one of these poses)
    pose = np.random.default_rng(0).uniform(arm.lower, arm.upper, size=(24, 7))[16]
    rec = write_arm_recording(tmp_path / "far.tape.csv", np.repeat(pose[None], 12, axis=0))
    motion = recording_motion(rec, "z1")
    with pytest.raises(SafetyError) as refused:
        export_motion(motion, "csv", tmp_path / "far.csv")
    reach = r"frame \d+ \(t = [\d.]+ s of the source\): the hand's target is [\d.]+ cm out of the Unitree Z1's reach"  # fmt: skip
    assert any(re.search(reach, said) for said in refused.value.findings), refused.value.findings
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


def _toppra_fails(monkeypatch, when) -> None:
    """Make TOPP-RA find no timing for a path of waypoints ``q`` where ``when(q)``."""
    import toppra.algorithm

    compute = toppra.algorithm.TOPPRA.compute_trajectory

    def failing(self, *args, **kwargs):
        return None if when(self.path.waypoints[1]) else compute(self, *args, **kwargs)

    monkeypatch.setattr(toppra.algorithm.TOPPRA, "compute_trajectory", failing)


def test_where_toppra_fails_the_path_is_timed_in_parts_stopping_between_them(monkeypatch, tmp_path):
    _toppra_fails(monkeypatch, lambda q: len(q) > 2)  # only single steps get a timing
    q = _across_range(PUMA, [[0, 0, 0, 0, 0, 0], [0.5, 0.2, 0, 0, 0, 0], [0.5, 0.6, 0.3, 0, 0, 0]])
    rows = _export_exactly(q, 50.0, 0.8, tmp_path / "t.csv")
    t, samples = rows[:, 0], rows[:, 1:]
    nearest = int(np.argmin(np.abs(samples - q[1]).max(axis=1)))
    # it comes to rest at the middle waypoint, between two samples of the rate's grid
    assert np.abs(samples[nearest] - q[1]).max() < 1e-3
    speed = np.abs(np.diff(samples, axis=0)).max(axis=1) / np.diff(t)
    assert speed[nearest - 1 : nearest + 1].max() < 0.05 < speed.max()


def test_a_step_toppra_cannot_time_is_refused_naming_its_samples(monkeypatch, tmp_path):
    _toppra_fails(monkeypatch, lambda q: True)
    q = _across_range(PUMA, [[0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0], [0.5, 0, 0, 0, 0, 0]])
    motion = Motion("policy", "p", PUMA, np.zeros(len(q)), q, False, 50.0)
    with pytest.raises(ExportError) as err:
        export_motion(motion, "csv", tmp_path / "t.csv")
    message = str(err.value)
    assert "\n" not in message and message.endswith(".")
    assert "from its sample 0 to its sample 2" in message  # sample 1 repeats sample 0
    assert "smooth the path there" in message
    assert not (tmp_path / "t.csv").exists()
