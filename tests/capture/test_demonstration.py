"""Demonstrations: a simulated reach becomes a grid path to the goal; bad segments are refused."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from studio.capture import (
    DemonstrationError,
    RecordingWriter,
    TapeFrame,
    extract_demonstration,
    load_demonstration,
    read_recording,
    simulate,
)
from studio.capture._demonstration import erase_loops
from studio.learning import ArmGrid

SECONDS = 5.0


def _goal_q(grid: ArmGrid) -> np.ndarray:
    from studio.capture import goal_configuration

    return goal_configuration(grid)


@pytest.fixture(scope="module")
def reach(tmp_path_factory):
    grid = ArmGrid()
    sim = simulate(SECONDS, seed=0, goal=_goal_q(grid))
    path = tmp_path_factory.mktemp("demo") / "reach.tape.csv"
    with RecordingWriter(path, config=sim.config, source="simulator") as writer:
        writer.write_many(sim.frames)
    return read_recording(path), sim, grid


def _one_action_apart(grid: ArmGrid, path: list[int]) -> bool:
    bins = np.array([grid.bins_of(s) for s in path])
    return bool(
        np.all(np.abs(np.diff(bins, axis=0)) <= 1) and np.all(np.any(np.diff(bins, axis=0), axis=1))
    )


def test_a_simulated_reach_becomes_a_path_to_the_goal(reach):
    rec, sim, grid = reach
    t0 = sim.reach_start / 110
    demo = extract_demonstration(rec, t0, rec.duration, grid=grid)
    assert demo.grid_path[-1] == grid.goal_state and len(demo.grid_path) >= 2
    assert _one_action_apart(grid, demo.grid_path)
    assert len(set(demo.grid_path)) == len(demo.grid_path)  # no pauses, no loops
    assert demo.grid_path[0] == grid.state_of_angles(demo.q_robot[0, :3])
    assert demo.q_robot.shape == (len(demo.times), 6)
    from studio.kinematics import Retargeter

    retarget = Retargeter("joint", mirror=True)
    reachable = retarget.robot_from_human(retarget.human_from_robot(_goal_q(grid)))
    assert np.abs(demo.q_robot[-1, :3] - reachable[:3]).max() < np.radians(3)
    assert demo.residual_max < 0.03
    assert t0 <= demo.reached_at <= sim.reach_end / 110 + 0.5


def test_saved_demonstration_round_trips(reach, tmp_path):
    rec, sim, grid = reach
    demo = extract_demonstration(rec, sim.reach_start / 110, rec.duration, grid=grid, name="r")
    path = demo.save()
    assert path.name.startswith("reach.") and path.name.endswith(".demo.json")
    back = load_demonstration(path)
    assert (
        back.grid_path == demo.grid_path and back.goal == demo.goal and back.recording == rec.path
    )
    assert np.allclose(back.q_robot, demo.q_robot, atol=1e-6)
    assert back.arm_grid() == grid
    assert path.stat().st_size < 100_000


def test_a_segment_that_misses_the_goal_is_refused_or_sets_the_goal(reach):
    rec, sim, grid = reach
    t1 = sim.reach_start / 110 - 0.1
    with pytest.raises(DemonstrationError, match="never reaches the goal") as err:
        extract_demonstration(rec, 0.0, t1, grid=grid)
    assert err.value.reason == "never_reaches_goal"
    demo = extract_demonstration(rec, 0.0, t1, grid=grid, goal_from_end=True)
    assert demo.grid_path[-1] == demo.arm_grid().goal_state != grid.goal_state
    assert _one_action_apart(grid, demo.grid_path)


def test_bad_fit_is_refused(reach, tmp_path):
    rec, _, grid = reach
    rng = np.random.default_rng(0)
    path = tmp_path / "noise.tape.csv"
    with RecordingWriter(path, config=rec.config) as writer:
        writer.write_many(
            [
                TapeFrame(i / 110, i, rng.normal(0, 0.6, 16), rng.normal(0, 0.6, 16))
                for i in range(30)
            ]
        )
    with pytest.raises(DemonstrationError, match="fits the tape badly") as err:
        extract_demonstration(path, 0.0, 1.0, grid=grid)
    assert err.value.reason == "bad_fit"


def test_leaving_the_robot_range_is_refused(reach, tmp_path):
    from studio.kinematics import HumanArm, tape_from_arm

    rec, _, grid = reach
    arm = HumanArm()
    q = np.zeros((60, 7))
    q[:, 0] = np.linspace(0.5, -1.2, 60)  # shoulder flexion -> Puma J2 = q - 90 deg, past -110 deg
    q[:, 3] = 0.5
    bend, twist = tape_from_arm(arm, q, rec.config)
    path = tmp_path / "limit.tape.csv"
    with RecordingWriter(path, config=rec.config) as writer:
        writer.write_many([TapeFrame(i / 110, i, bend[i], twist[i]) for i in range(60)])
    with pytest.raises(DemonstrationError, match="joint 2 to its limit") as err:
        extract_demonstration(path, 0.0, 1.0, grid=grid)
    assert err.value.reason == "leaves_joint_range"


def test_too_short_segment(reach):
    rec, _, grid = reach
    with pytest.raises(DemonstrationError) as err:
        extract_demonstration(rec, 1.0, 1.001, grid=grid)
    assert err.value.reason == "too_short"


@given(st.lists(st.integers(0, 6), min_size=1, max_size=40))
def test_erase_loops_keeps_a_loop_free_subpath(path):
    out = erase_loops(path)
    assert len(set(out)) == len(out)
    assert out[0] == path[0] and out[-1] == path[-1]
    steps = set(zip(path, path[1:], strict=False))
    assert all(step in steps for step in zip(out, out[1:], strict=False))


def test_trigger_marks_the_reach_as_a_segment(reach):
    from studio.capture import trigger_segments

    rec, sim, grid = reach
    [(t0, t1)] = trigger_segments(rec)
    assert t0 == pytest.approx(sim.reach_start / 110) and t1 == pytest.approx(rec.duration)
    assert extract_demonstration(rec, t0, t1, grid=grid).grid_path[-1] == grid.goal_state
