"""Laws of the ShapeTape model: reconstruction, its inverse, arcs, twist, configs, bad input."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from studio.kinematics import HumanArm, KinematicsError, TapeConfig, reconstruct, tape_from_arm
from studio.kinematics.human._tape import tape_angles

CONFIG = TapeConfig()
R = CONFIG.regions
angles = arrays(np.float64, (R,), elements=st.floats(-3.1, 3.1))


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + math.pi) % (2 * math.pi) - math.pi


@settings(max_examples=60, deadline=None)
@given(bend=angles, twist=angles)
def test_reconstruct_then_invert_gives_back_bend_and_twist(bend, twist):
    shape = reconstruct(bend, twist, CONFIG)
    assert shape.positions.shape == (R + 1, 3)
    assert shape.frames.shape == (R + 1, 3, 3)
    b, t = tape_angles(shape.frames)
    np.testing.assert_allclose(_wrap(b - bend), 0.0, atol=1e-9)
    np.testing.assert_allclose(_wrap(t - twist), 0.0, atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(bend=angles, twist=angles)
def test_frames_are_rotations_and_positions_advance_one_region_along_u(bend, twist):
    shape = reconstruct(bend, twist, CONFIG)
    F = shape.frames
    np.testing.assert_allclose(
        np.einsum("kji,kjl->kil", F, F), np.broadcast_to(np.eye(3), F.shape), atol=1e-12
    )
    np.testing.assert_allclose(np.linalg.det(F), 1.0, atol=1e-12)
    steps = np.diff(shape.positions, axis=0)
    np.testing.assert_allclose(steps, CONFIG.region_length * F[1:, :, 0], atol=1e-12)


def test_first_region_rotates_about_u_by_twist_then_about_new_b_by_bend():
    bend, twist = np.zeros(R), np.zeros(R)
    bend[0], twist[0] = 0.3, 0.5
    shape = reconstruct(bend, twist, TapeConfig(base=np.eye(4)))
    ct, st_, cb, sb = math.cos(0.5), math.sin(0.5), math.cos(0.3), math.sin(0.3)
    Rx = np.array([[1, 0, 0], [0, ct, -st_], [0, st_, ct]])
    Rz = np.array([[cb, -sb, 0], [sb, cb, 0], [0, 0, 1]])
    np.testing.assert_allclose(shape.frames[1], Rx @ Rz, atol=1e-15)
    np.testing.assert_allclose(shape.positions[1], CONFIG.region_length * (Rx @ Rz)[:, 0])


@settings(max_examples=40, deadline=None)
@given(kappa=st.floats(0.01, 3.0) | st.floats(-3.0, -0.01))
def test_constant_bend_without_twist_puts_the_vertices_on_a_circle(kappa):
    # Equal chords of length L, each turning by kappa, are inscribed in a circle of radius
    # L / (2 sin(|kappa| / 2)) (the continuous-arc radius L / kappa is its small-angle limit),
    # in the base frame's u-n plane.
    shape = reconstruct(np.full(R, kappa), np.zeros(R), CONFIG)
    P = shape.positions
    b = CONFIG.base[:3, 2]
    np.testing.assert_allclose((P - P[0]) @ b, 0.0, atol=1e-12)  # planar
    L = CONFIG.region_length
    radius = L / (2 * math.sin(abs(kappa) / 2))
    # Centre: on the perpendicular bisector of the first chord, on the side the tape bends to.
    chord_dir = shape.frames[1][:, 0]
    normal = np.cross(b, chord_dir) * math.copysign(1.0, kappa)
    centre = P[0] + chord_dir * L / 2 + normal * math.sqrt(radius**2 - (L / 2) ** 2)
    np.testing.assert_allclose(np.linalg.norm(P - centre, axis=1), radius, rtol=1e-9)


@settings(max_examples=40, deadline=None)
@given(twist=angles)
def test_twist_alone_gives_a_straight_tape(twist):
    shape = reconstruct(np.zeros(R), twist, CONFIG)
    u = CONFIG.base[:3, 0]
    k = np.arange(R + 1)[:, None]
    np.testing.assert_allclose(
        shape.positions, CONFIG.base[:3, 3] + k * CONFIG.region_length * u, atol=1e-12
    )
    np.testing.assert_allclose(shape.frames[:, :, 0], np.broadcast_to(u, (R + 1, 3)), atol=1e-12)
    # n turns about u by the accumulated twist.
    total = np.concatenate([[0.0], np.cumsum(twist)])
    n0, b0 = CONFIG.base[:3, 1], CONFIG.base[:3, 2]
    expected_n = np.cos(total)[:, None] * n0 + np.sin(total)[:, None] * b0
    np.testing.assert_allclose(shape.frames[:, :, 1], expected_n, atol=1e-9)


def test_reconstruct_is_vectorised_over_leading_dims():
    rng = np.random.default_rng(3)
    bend = rng.normal(0, 0.4, (2, 3, R))
    twist = rng.normal(0, 0.4, (2, 3, R))
    batch = reconstruct(bend, twist, CONFIG)
    assert batch.positions.shape == (2, 3, R + 1, 3)
    assert batch.frames.shape == (2, 3, R + 1, 3, 3)
    one = reconstruct(bend[1, 2], twist[1, 2], CONFIG)
    np.testing.assert_array_equal(batch.positions[1, 2], one.positions)
    np.testing.assert_array_equal(batch.frames[1, 2], one.frames)
    b, t = tape_angles(batch.frames)
    np.testing.assert_allclose(b, bend, atol=1e-12)
    np.testing.assert_allclose(t, twist, atol=1e-12)


def test_default_config_puts_the_shoulder_vertex_on_the_shoulder_and_the_arm_in_range():
    assert (CONFIG.length, CONFIG.regions) == (1.84, 16)
    assert CONFIG.region_length == pytest.approx(0.115)
    for side in ("right", "left"):
        config = TapeConfig(side=side)
        bend, twist = tape_from_arm(HumanArm(side), np.zeros(7), config)
        shape = reconstruct(bend, twist, config)
        np.testing.assert_allclose(shape.positions[config.shoulder_region], 0.0, atol=1e-12)
        # The back path arrives heading outwards, towards the arm's side.
        u = shape.frames[config.shoulder_region][:, 0]
        np.testing.assert_allclose(u, [0.0, -1.0 if side == "right" else 1.0, 0.0], atol=1e-12)
    arm = HumanArm()
    arm_regions = (CONFIG.wrist_region - CONFIG.shoulder_region) * CONFIG.region_length
    assert arm_regions >= arm.upper_arm_length + arm.forearm_length


def test_tape_from_arm_keeps_the_back_fixed_and_follows_the_arm():
    arm = HumanArm()
    rng = np.random.default_rng(7)
    q = rng.uniform(arm.lower, arm.upper, (20, 7))
    q[:, 3] = rng.uniform(0.2, 2.4, 20)
    bend, twist = tape_from_arm(arm, q, CONFIG)
    assert bend.shape == twist.shape == (20, R)
    s = CONFIG.shoulder_region
    np.testing.assert_array_equal(bend[:, :s], np.broadcast_to(bend[0, :s], (20, s)))
    np.testing.assert_array_equal(twist[:, :s], np.broadcast_to(twist[0, :s], (20, s)))
    assert np.ptp(bend[:, s]) > 0.1  # the shoulder crossing depends on the pose
    shape = reconstruct(bend, twist, CONFIG)
    points = arm.points(q)
    for k in range(20):
        P = shape.positions[k]
        shoulder, elbow = points[k, 0], points[k, 1]
        np.testing.assert_allclose(P[s], shoulder, atol=1e-12)
        # Whole regions lie along the upper arm until the elbow.
        d = (elbow - shoulder) / arm.upper_arm_length
        for j in range(1, int(arm.upper_arm_length // CONFIG.region_length) + 1):
            np.testing.assert_allclose(
                P[s + j], shoulder + j * CONFIG.region_length * d, atol=1e-12
            )


def test_tape_from_arm_noise_needs_a_generator_and_is_reproducible():
    arm = HumanArm()
    with pytest.raises(KinematicsError, match="rng"):
        tape_from_arm(arm, np.zeros(7), CONFIG, noise=0.01)
    a = tape_from_arm(arm, np.zeros(7), CONFIG, rng=np.random.default_rng(1), noise=0.01)
    b = tape_from_arm(arm, np.zeros(7), CONFIG, rng=np.random.default_rng(1), noise=0.01)
    np.testing.assert_array_equal(a[0], b[0])
    clean = tape_from_arm(arm, np.zeros(7), CONFIG)
    np.testing.assert_array_equal(tape_from_arm(arm, np.zeros(7), CONFIG, noise=None)[0], clean[0])
    assert 0 < np.abs(a[0] - clean[0]).max() < 0.1


def test_config_is_frozen_and_validated():
    with pytest.raises(dataclasses.FrozenInstanceError):
        CONFIG.regions = 8  # type: ignore[misc]
    with pytest.raises(ValueError):
        CONFIG.base[0, 0] = 2.0
    with pytest.raises(KinematicsError, match="wrist_region"):
        TapeConfig(shoulder_region=12, wrist_region=18)
    with pytest.raises(KinematicsError, match="shoulder_region"):
        TapeConfig(shoulder_region=10, wrist_region=10)
    with pytest.raises(KinematicsError, match="length"):
        TapeConfig(length=-1.0)
    with pytest.raises(KinematicsError, match="regions"):
        TapeConfig(regions=0)
    with pytest.raises(KinematicsError, match="base"):
        TapeConfig(base=np.ones((4, 4)))
    with pytest.raises(KinematicsError, match="base"):
        TapeConfig(base=np.eye(3))
    with pytest.raises(KinematicsError, match="base"):
        TapeConfig(base="identity")  # type: ignore[arg-type]
    with pytest.raises(KinematicsError, match="shoulder_region"):
        TapeConfig(shoulder_region=9.5)  # type: ignore[arg-type]
    with pytest.raises(KinematicsError, match="wrist_region"):
        TapeConfig(wrist_region="14")  # type: ignore[arg-type]
    with pytest.raises(KinematicsError, match="length"):
        TapeConfig(length="long")  # type: ignore[arg-type]
    # Whole numbers read back from JSON as floats are fine.
    assert TapeConfig(shoulder_region=9.0, wrist_region=14.0) == TapeConfig()


@pytest.mark.parametrize(
    ("bend", "twist", "match"),
    [
        (np.zeros(R - 1), np.zeros(R - 1), "shape"),
        (np.zeros(R), np.zeros((2, R)), "shape"),
        (np.full(R, np.nan), np.zeros(R), "NaN"),
        (np.zeros(R), np.full(R, np.inf), "NaN"),
        ("abc", np.zeros(R), "real numbers"),
        (np.zeros(R) + 1j, np.zeros(R), "complex"),
        ([[0.0] * R, [0.0] * (R - 1)], np.zeros(R), "numeric"),
    ],
)
def test_reconstruct_rejects_bad_input(bend, twist, match):
    with pytest.raises(KinematicsError, match=match):
        reconstruct(bend, twist, CONFIG)


def test_reconstruct_needs_a_tape_config():
    for config in (None, "16 regions", {"regions": 16}):
        with pytest.raises(KinematicsError, match="TapeConfig"):
            reconstruct(np.zeros(R), np.zeros(R), config)  # type: ignore[arg-type]


def test_tape_angles_rejects_bad_input():
    with pytest.raises(KinematicsError, match="shape"):
        tape_angles(np.zeros((R, 3)))
    frames = reconstruct(np.zeros(R), np.zeros(R), CONFIG).frames.copy()
    frames[3, 0, 0] = np.nan
    with pytest.raises(KinematicsError, match="NaN"):
        tape_angles(frames)
    # Not rotations: no angles would rebuild them, so none are returned.
    with pytest.raises(KinematicsError, match="rotation"):
        tape_angles(np.ones((R + 1, 3, 3)))
    # Rotations, but one step turns about n (a twist-then-bend never does): not a tape's frames.
    frames = reconstruct(np.full(R, 0.2), np.full(R, 0.1), CONFIG).frames.copy()
    c, s_ = math.cos(0.3), math.sin(0.3)
    frames[5:] = frames[5:] @ np.array([[c, 0, s_], [0, 1, 0], [-s_, 0, c]])
    with pytest.raises(KinematicsError, match="not a tape"):
        tape_angles(frames)


@settings(max_examples=20, deadline=None)
@given(q=st.tuples(*[st.floats(-1.0, 1.0)] * 7).map(np.array))
def test_a_tape_that_starts_at_the_shoulder_has_no_back_path(q):
    # shoulder_region = 0 is allowed: the tape starts on the shoulder, at its base.
    arm = HumanArm()
    q = np.clip(q, arm.lower, arm.upper)
    config = TapeConfig(shoulder_region=0, wrist_region=5, base=np.eye(4))
    bend, twist = tape_from_arm(arm, q, config)
    shape = reconstruct(bend, twist, config)
    np.testing.assert_allclose(shape.positions[0], 0.0)
    d = arm.points(q)[1] / arm.upper_arm_length
    np.testing.assert_allclose(shape.positions[2], 2 * config.region_length * d, atol=1e-12)


def test_tape_from_arm_rejects_bad_noise():
    arm = HumanArm()
    rng = np.random.default_rng(0)
    for noise in (-0.01, math.nan, math.inf, "loud"):
        with pytest.raises(KinematicsError, match="noise"):
            tape_from_arm(arm, np.zeros(7), CONFIG, rng=rng, noise=noise)  # type: ignore[arg-type]
    with pytest.raises(KinematicsError, match="default_rng"):
        tape_from_arm(arm, np.zeros(7), CONFIG, rng=7, noise=0.01)  # type: ignore[arg-type]


def test_configs_compare_by_value_including_the_base():
    assert TapeConfig() == TapeConfig()
    assert hash(TapeConfig()) == hash(TapeConfig())
    moved = CONFIG.base.copy()
    moved[2, 3] += 0.01
    assert TapeConfig(base=moved) != TapeConfig()
    assert TapeConfig(side="left") != TapeConfig()
