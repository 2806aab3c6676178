"""The LeRobotDataset v3.0 layout, field by field, as lerobot's ``datasets/utils.py`` documents
it (``INFO_PATH``, ``STATS_PATH``, ``DEFAULT_TASKS_PATH``, ``DEFAULT_EPISODES_PATH``,
``DEFAULT_DATA_PATH``, ``DEFAULT_FEATURES``, ``create_empty_dataset_info``), read with pyarrow
and json alone."""

from __future__ import annotations

import json

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from studio.export import CODEBASE_VERSION, demonstration_motion, export_motion
from studio.samples import SAMPLES_DIR

# lerobot's DEFAULT_FEATURES
DEFAULT_FEATURES = {
    "timestamp": ("float32", [1]),
    "frame_index": ("int64", [1]),
    "episode_index": ("int64", [1]),
    "index": ("int64", [1]),
    "task_index": ("int64", [1]),
}
# create_empty_dataset_info (v3.0) and what a finished dataset fills in
INFO_KEYS = {
    "codebase_version", "robot_type", "total_episodes", "total_frames", "total_tasks",
    "chunks_size", "data_files_size_in_mb", "video_files_size_in_mb", "fps", "splits",
    "data_path", "video_path", "features",
}  # fmt: skip
EPISODE_COLUMNS = {
    "episode_index", "tasks", "length", "data/chunk_index", "data/file_index",
    "dataset_from_index", "dataset_to_index", "meta/episodes/chunk_index",
    "meta/episodes/file_index",
}  # fmt: skip
STATS = {"min", "max", "mean", "std", "count", "q01", "q10", "q50", "q90", "q99"}


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    motion = demonstration_motion(SAMPLES_DIR / "sample-reach-3.demo.json", "puma560", 30.0)
    out = tmp_path_factory.mktemp("lerobot") / "reach"
    export_motion(motion, "lerobot", out, task="Reach the goal")
    return out, motion


def test_the_files_are_where_lerobot_looks(dataset):
    out, _ = dataset
    files = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert files == [
        "data/chunk-000/file-000.parquet",
        "meta/episodes/chunk-000/file-000.parquet",
        "meta/info.json",
        "meta/stats.json",
        "meta/tasks.parquet",
    ]


def test_info_json_field_by_field(dataset):
    out, motion = dataset
    info = json.loads((out / "meta/info.json").read_text())
    assert set(info) >= INFO_KEYS and set(info) - INFO_KEYS == {"teach_studio"}
    assert info["codebase_version"] == CODEBASE_VERSION == "v3.0"
    assert info["robot_type"] == "puma560"
    assert info["data_path"] == "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
    assert info["video_path"] is None  # no cameras
    assert info["chunks_size"] == 1000
    assert info["data_files_size_in_mb"] == 100 and info["video_files_size_in_mb"] == 500
    assert info["fps"] == 30 and isinstance(info["fps"], int)
    rows = pq.read_metadata(out / "data/chunk-000/file-000.parquet").num_rows
    assert info["total_frames"] == rows and info["total_episodes"] == 1
    assert info["total_tasks"] == 1 and info["splits"] == {"train": "0:1"}
    features = info["features"]
    for name, (dtype, shape) in DEFAULT_FEATURES.items():
        assert features[name] == {"dtype": dtype, "shape": shape, "names": None}
    joints = list(motion.robot.joint_names)
    for name in ("observation.state", "action"):
        assert features[name] == {"dtype": "float32", "shape": [len(joints)], "names": joints}


def test_the_data_file_has_one_column_per_feature_with_its_dtype(dataset):
    out, motion = dataset
    info = json.loads((out / "meta/info.json").read_text())
    table = pq.read_table(out / "data/chunk-000/file-000.parquet")
    assert set(table.column_names) == set(info["features"])
    for name, feature in info["features"].items():
        field = table.schema.field(name)
        if feature["shape"] == [1]:
            assert field.type == pa.from_numpy_dtype(np.dtype(feature["dtype"])), name
        else:
            assert field.type == pa.list_(pa.float32(), feature["shape"][0]), name
    timestamps = np.array(table.column("timestamp"))
    np.testing.assert_allclose(timestamps, np.arange(len(timestamps)) / info["fps"], atol=1e-4)


def test_tasks_and_episodes_tables(dataset):
    out, _ = dataset
    tasks = pq.read_table(out / "meta/tasks.parquet")
    assert tasks.to_pydict() == {"task_index": [0], "task": ["Reach the goal"]}
    assert tasks.schema.pandas_metadata["index_columns"] == ["task"]  # lerobot's tasks.loc[task]
    episodes = pq.read_table(out / "meta/episodes/chunk-000/file-000.parquet").to_pylist()
    assert len(episodes) == 1
    episode = episodes[0]
    assert set(episode) >= EPISODE_COLUMNS
    frames = pq.read_metadata(out / "data/chunk-000/file-000.parquet").num_rows
    assert episode["episode_index"] == 0 and episode["tasks"] == ["Reach the goal"]
    assert episode["length"] == frames
    assert (episode["dataset_from_index"], episode["dataset_to_index"]) == (0, frames)
    for key in ("data/chunk_index", "data/file_index", "meta/episodes/chunk_index",
                "meta/episodes/file_index"):  # fmt: skip
        assert episode[key] == 0
    stats = json.loads((out / "meta/stats.json").read_text())
    for feature, values in stats.items():
        assert set(values) == STATS, feature
        for stat, value in values.items():
            assert episode[f"stats/{feature}/{stat}"] == value


def test_stats_describe_the_data(dataset):
    out, _ = dataset
    stats = json.loads((out / "meta/stats.json").read_text())
    info = json.loads((out / "meta/info.json").read_text())
    assert set(stats) == set(info["features"])
    state = np.array(
        pq.read_table(out / "data/chunk-000/file-000.parquet")["observation.state"].to_pylist()
    )
    np.testing.assert_allclose(stats["observation.state"]["min"], state.min(axis=0), rtol=1e-6)
    np.testing.assert_allclose(stats["observation.state"]["mean"], state.mean(axis=0), rtol=1e-5)
    assert stats["observation.state"]["count"] == [len(state)]


@pytest.mark.parametrize("robot", ["so100", "so101"])
def test_an_so_arm_is_written_as_lerobots_own_follower_records_it(robot, tmp_path):
    """``robot_type`` ``so10x_follower``, ``<motor>.pos`` in degrees from the middle of each
    joint's range (LeRobot's ``use_degrees``), and ``gripper.pos`` held open, so that LeRobot's
    own driver can replay the dataset on the arm."""
    from studio.kinematics import load_robot

    motion = demonstration_motion(SAMPLES_DIR / "sample-reach-1.demo.json", robot, 30.0)
    out = tmp_path / "reach"
    done = export_motion(motion, "lerobot", out, unchecked=True)
    info = json.loads((out / "meta/info.json").read_text())
    assert info["robot_type"] == f"{robot}_follower"
    motors = ["shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll"]
    names = [f"{m}.pos" for m in motors] + ["gripper.pos"]
    assert info["features"]["observation.state"]["names"] == names
    assert info["features"]["action"]["names"] == names
    assert info["teach_studio"]["units"]["shoulder_pan.pos"] == "deg"
    data = pq.read_table(out / "data/chunk-000/file-000.parquet").to_pydict()
    state = np.array(data["observation.state"], dtype=float)
    arm = load_robot(robot)
    middle = (arm.lower + arm.upper) / 2
    np.testing.assert_allclose(state[:, :5], np.degrees(done.q - middle), atol=1e-3)
    assert np.all(state[:, 5] == 100.0)  # the gripper, open
    assert info["teach_studio"]["units"]["gripper.pos"] == "percent open"


def test_the_so101s_wrist_joints_move_in_its_file(tmp_path):
    """Every joint that moves in the source moves in the file: the SO-101 follows the hand's
    position with all five joints, its wrist's two included (they stayed at 0 once)."""
    motion = demonstration_motion(SAMPLES_DIR / "sample-reach-2.demo.json", "so101", 30.0)
    out = tmp_path / "reach"
    export_motion(motion, "lerobot", out, unchecked=True)
    names = json.loads((out / "meta/info.json").read_text())["features"]["action"]["names"]
    data = pq.read_table(out / "data/chunk-000/file-000.parquet").to_pydict()
    state = np.array(data["observation.state"], dtype=float)
    for motor in ("wrist_flex.pos", "wrist_roll.pos"):
        assert np.ptp(state[:, names.index(motor)]) > 10.0  # degrees


def test_another_arm_keeps_its_urdf_names_in_radians_and_says_so(tmp_path):
    motion = demonstration_motion(SAMPLES_DIR / "sample-reach-1.demo.json", "panda", 30.0)
    out = tmp_path / "reach"
    done = export_motion(motion, "lerobot", out, unchecked=True)
    info = json.loads((out / "meta/info.json").read_text())
    assert info["robot_type"] == "panda"
    assert info["features"]["observation.state"]["names"] == list(motion.robot.joint_names)
    assert set(info["teach_studio"]["units"].values()) == {"rad"}
    data = pq.read_table(out / "data/chunk-000/file-000.parquet").to_pydict()
    np.testing.assert_allclose(np.array(data["observation.state"]), done.q, atol=1e-5)


def test_the_task_is_a_sentence_a_person_would_write(dataset):
    out, _ = dataset
    tasks = pq.read_table(out / "meta/tasks.parquet").to_pydict()["task"]
    assert tasks == ["Reach the goal"]  # given
    motion = demonstration_motion(SAMPLES_DIR / "sample-reach-3.demo.json", "puma560", 30.0)
    other = out.parent / "default-task"
    export_motion(motion, "lerobot", other)
    (task,) = pq.read_table(other / "meta/tasks.parquet").to_pydict()["task"]
    assert task == "Reach the goal the way the person showed it."
    assert ".json" not in task
