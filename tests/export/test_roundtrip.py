"""The exports read back: MCAP (with mcap_ros2) against the CSV, LeRobot (with pyarrow alone)
against the recording, frame by frame."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from mcap_ros2.reader import read_ros2_messages

from studio.cli import main
from studio.export import (
    JOINT_STATE,
    JOINT_TRAJECTORY,
    STATE_TOPIC,
    TRAJECTORY_TOPIC,
    check_trajectory,
    demonstration_motion,
    export_motion,
    recording_motion,
)
from studio.kinematics import load_robot
from studio.samples import SAMPLES_DIR


def read_csv(path: Path) -> tuple[list[str], np.ndarray]:
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    return lines[0].split(","), np.loadtxt(lines[1:], delimiter=",", ndmin=2)


def read_mcap(path: Path) -> tuple[str, list[str], np.ndarray, np.ndarray]:
    """The schema name, joint names, times (from the first sample) and positions an MCAP file
    holds: its trajectory where it has one, else its joint states."""
    trajectory, states = None, []
    for message in read_ros2_messages(str(path), topics=[TRAJECTORY_TOPIC, STATE_TOPIC]):
        if message.schema.name == JOINT_TRAJECTORY:
            trajectory = message.ros_msg
        else:
            msg = message.ros_msg
            stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
            assert message.log_time_ns == stamp
            states.append((stamp, list(msg.name), list(msg.position)))
    if trajectory is not None:
        times = [
            p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in trajectory.points
        ]
        rows = [list(p.positions) for p in trajectory.points]
        return JOINT_TRAJECTORY, list(trajectory.joint_names), np.array(times), np.array(rows)
    stamps = np.array([s[0] for s in states], dtype=np.int64)
    times = (stamps - stamps[0]) * 1e-9
    return JOINT_STATE, states[0][1], times, np.array([s[2] for s in states])


def test_a_demonstrations_mcap_is_its_csv_as_a_ros2_joint_trajectory(tmp_path):
    motion = demonstration_motion(SAMPLES_DIR / "sample-reach-2.demo.json", "puma560", 50.0)
    export_motion(motion, "csv", tmp_path / "demo.csv")
    export_motion(motion, "mcap", tmp_path / "demo.mcap")
    header, rows = read_csv(tmp_path / "demo.csv")
    schema, names, times, q = read_mcap(tmp_path / "demo.mcap")
    assert schema == "trajectory_msgs/msg/JointTrajectory"
    assert header == ["time", *names] and names == list(load_robot("puma560").joint_names)
    np.testing.assert_allclose(times, rows[:, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(q, rows[:, 1:], rtol=0, atol=1e-8)  # %.9g in the CSV


def test_a_recordings_mcap_is_joint_states_at_the_capture_rate(slow_recording, tmp_path):
    motion = recording_motion(slow_recording, "puma560")
    export_motion(motion, "csv", tmp_path / "rec.csv")
    export_motion(motion, "mcap", tmp_path / "rec.mcap")
    header, rows = read_csv(tmp_path / "rec.csv")
    schema, names, times, q = read_mcap(tmp_path / "rec.mcap")
    assert schema == JOINT_STATE == "sensor_msgs/msg/JointState"
    assert header == ["time", *names]
    assert len(times) == 165 and np.allclose(np.diff(times), 1 / 110)
    np.testing.assert_allclose(times, rows[:, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(q, rows[:, 1:], rtol=0, atol=1e-8)


def test_the_lerobot_dataset_matches_the_recording_frame_by_frame(slow_recording, tmp_path):
    motion = recording_motion(slow_recording, "puma560")
    out = tmp_path / "slow.lerobot"
    export_motion(motion, "lerobot", out)
    table = pq.read_table(out / "data/chunk-000/file-000.parquet").to_pydict()
    state = np.array(table["observation.state"])
    assert state.shape == motion.q.shape == (165, 6)
    np.testing.assert_allclose(state, motion.q.astype(np.float32), rtol=0, atol=0)
    np.testing.assert_array_equal(np.array(table["action"])[:-1], state[1:])
    np.testing.assert_array_equal(np.array(table["action"])[-1], state[-1])
    np.testing.assert_allclose(table["timestamp"], motion.times.astype(np.float32), atol=0)
    assert table["frame_index"] == list(range(165)) == table["index"]
    assert set(table["episode_index"]) == {0} == set(table["task_index"])
    info = json.loads((out / "meta/info.json").read_text())
    assert info["fps"] == 110 and info["total_frames"] == 165
    assert info["features"]["observation.state"]["names"] == list(motion.robot.joint_names)
    assert info["teach_studio"]["checked"] is True


def test_the_cli_exports_a_sample_by_name_in_each_format(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    for fmt in ("csv", "mcap", "lerobot"):
        argv = ["export", "sample-reach-1", "--robot", "puma560", "--format", fmt]
        assert main(argv) == 0, capsys.readouterr().err
        assert "passed the safety checks" in capsys.readouterr().out
    made = sorted(p.name for p in tmp_path.iterdir() if p.name != "cache")  # the data folder's
    assert made == [f"sample-reach-1.puma560.{end}" for end in ("csv", "lerobot", "mcap")]
    header, rows = read_csv(tmp_path / "sample-reach-1.puma560.csv")
    assert header == ["time", *load_robot("puma560").joint_names]
    assert rows[0, 0] == 0 and np.allclose(np.diff(rows[:, 0]), 1 / 50)  # --rate's default


@pytest.mark.parametrize("fmt", ["csv", "mcap", "lerobot"])
def test_an_unchecked_export_states_its_findings_in_the_file(fmt, tmp_path, capsys):
    out = tmp_path / f"rec.{fmt}"
    sample = str(SAMPLES_DIR / "sample-reach-1.tape.csv")
    assert main(["export", sample, "--format", fmt, "--out", str(out)]) == 2
    refusal = capsys.readouterr().err.strip()
    assert refusal.startswith("studio export: Refused: recording sample-reach-1.tape.csv")
    assert "\n" not in refusal and not out.exists()
    assert main(["export", sample, "--format", fmt, "--out", str(out), "--unchecked"]) == 0
    first = refusal.split(": ", 4)[-1].split(" (and")[0]  # the first finding's sentence
    if fmt == "csv":
        assert first in out.read_text().split("\ntime,")[0]
    elif fmt == "mcap":
        from mcap.reader import make_reader

        with out.open("rb") as f:
            meta = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
        assert meta["teach_studio"]["checked"] == "no (--unchecked)"
        assert first in meta["teach_studio"]["findings"]
    else:
        info = json.loads((out / "meta/info.json").read_text())
        assert info["teach_studio"]["checked"] is False
        assert any(first in finding for finding in info["teach_studio"]["findings"])


@pytest.mark.parametrize("fmt", ["csv", "mcap", "lerobot"])
def test_a_refused_recording_exports_timed_within_the_limits_with_retime(fmt, tmp_path, capsys):
    """At its capture times a recording breaks the robot's limits, and the refusal says how to
    send it to a robot: --retime times its path within them, at the person's pace where the
    limits allow (issue 39), and it passes."""
    out = tmp_path / f"rec.{fmt}"
    sample = str(SAMPLES_DIR / "sample-reach-1.tape.csv")
    argv = ["export", sample, "--robot", "ur5", "--format", fmt, "--out", str(out)]
    assert main(argv) == 2
    assert "pass --retime to time its path within the limits" in capsys.readouterr().err
    assert main([*argv, "--retime", "--rate", "100"]) == 0, capsys.readouterr().err
    said = capsys.readouterr().out
    assert "at the person's pace where the limits allow, passed the safety checks" in said
    ur5 = load_robot("ur5")
    if fmt == "csv":
        header, rows = read_csv(out)
        times, q = rows[:, 0], rows[:, 1:]
    elif fmt == "mcap":
        schema, names, times, q = read_mcap(out)
        # timed, a recording is a trajectory to send, no longer the arm's joint states
        assert schema == JOINT_TRAJECTORY and names == list(ur5.joint_names)
    else:
        info = json.loads((out / "meta/info.json").read_text())
        assert info["fps"] == 100 and info["teach_studio"]["timed_by"] == "pace"
        table = pq.read_table(out / "data/chunk-000/file-000.parquet")
        times = np.array(table.column("timestamp").to_pylist())
        q = np.array(table.column("observation.state").to_pylist())
    assert np.allclose(np.diff(times), 0.01, atol=1e-6)  # --rate
    assert check_trajectory(ur5, times, q) == []
    # the retargeted path, start to end: the hand's first and last poses
    path = recording_motion(SAMPLES_DIR / "sample-reach-1.tape.csv", "ur5").q
    assert np.allclose(q[0], path[0], atol=1e-6) and np.allclose(q[-1], path[-1], atol=1e-6)


def test_retime_and_a_fixed_pace_for_a_policy_is_one_sentence(tmp_path, capsys):
    policy = str(tmp_path / "p.policy.npz")
    argv = ["export", policy, "--format", "csv", "--retime", "--seconds-per-step", "0.5"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "--retime" in err and "--seconds-per-step" in err and "\n" not in err


def _topics(path: Path) -> dict[str, list]:
    found: dict[str, list] = {}
    for message in read_ros2_messages(str(path)):
        found.setdefault(message.channel.topic, []).append(message)
    return found


def test_an_mcap_carries_what_foxglove_needs_to_draw_the_robot_moving(tmp_path):
    """``/robot_description`` (the URDF, latched, first), ``/tf`` (every link from its parent,
    per sample, matching Pinocchio's forward kinematics), joint states with frame ids, and real
    log times."""
    import time

    from studio.export import DESCRIPTION_TOPIC, TF_TOPIC

    robot = load_robot("panda")
    motion = demonstration_motion(SAMPLES_DIR / "sample-reach-1.demo.json", "panda", 30.0)
    before = time.time_ns()
    export_motion(motion, "mcap", tmp_path / "demo.mcap", unchecked=True)
    topics = _topics(tmp_path / "demo.mcap")
    assert set(topics) == {DESCRIPTION_TOPIC, TRAJECTORY_TOPIC, STATE_TOPIC, TF_TOPIC}
    (description,) = topics[DESCRIPTION_TOPIC]
    assert description.ros_msg.data == robot.urdf_text
    assert "transient_local" in description.channel.metadata["offered_qos_profiles"]
    first = min(m.log_time_ns for ms in topics.values() for m in ms)
    assert description.log_time_ns == first >= before  # a real time, not 1970
    states, tfs = topics[STATE_TOPIC], topics[TF_TOPIC]
    assert len(states) == len(tfs) > 10
    assert {m.ros_msg.header.frame_id for m in states} == {"panda_link0"}
    # chain the transforms from the root to the hand: Pinocchio's tool pose at that sample
    _, _, times, q = read_mcap(tmp_path / "demo.mcap")
    i = len(tfs) // 2
    edges = {t.child_frame_id: t for t in tfs[i].ros_msg.transforms}
    assert tfs[i].log_time_ns == first + round(times[i] * 1e9)

    def pose(link: str) -> np.ndarray:
        if link not in edges:
            return np.eye(4)
        t = edges[link]
        r, p = t.transform.rotation, t.transform.translation
        x, y, z, w = r.x, r.y, r.z, r.w
        m = np.eye(4)
        m[:3, :3] = [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
        m[:3, 3] = [p.x, p.y, p.z]
        return pose(t.header.frame_id) @ m

    import pinocchio as pin

    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q[i])
    hand = robot.model.getFrameId("panda_hand")
    np.testing.assert_allclose(pose("panda_hand"), data.oMf[hand].homogeneous, atol=1e-9)


def test_a_recordings_mcap_is_stamped_at_its_own_capture_time(slow_recording, tmp_path):
    from datetime import datetime

    from studio.capture import read_any_recording

    created = read_any_recording(slow_recording).meta["created"]
    export_motion(recording_motion(slow_recording, "puma560"), "mcap", tmp_path / "rec.mcap")
    topics = _topics(tmp_path / "rec.mcap")
    assert TRAJECTORY_TOPIC not in topics  # what the arm did, not a trajectory to follow
    first = topics[STATE_TOPIC][0].log_time_ns
    assert first == round(datetime.fromisoformat(created).timestamp() * 1e9)


def test_every_csv_names_its_robot_joint_order_units_and_source(tmp_path):
    motion = demonstration_motion(SAMPLES_DIR / "sample-reach-2.demo.json", "puma560", 50.0)
    done = export_motion(motion, "csv", tmp_path / "demo.csv")
    assert not done.findings  # a checked file has them too
    comments = [line for line in (tmp_path / "demo.csv").read_text().splitlines() if line[0] == "#"]
    text = "\n".join(comments)
    robot = load_robot("puma560")
    assert f"robot: puma560; joints in order: {', '.join(robot.joint_names)}" in text
    assert "seconds" in text and "radians" in text
    assert "source: the demonstration sample-reach-2.demo.json" in text
    assert "safety checks: passed" in text
    rows = np.loadtxt(
        tmp_path / "demo.csv", delimiter=",", comments="#", skiprows=len(comments) + 1
    )
    assert rows.shape[1] == 1 + robot.nq
