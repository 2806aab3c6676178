"""A LeRobotDataset v3.0 folder, written with pyarrow alone (no ``lerobot``, no torch).

The layout and fields follow lerobot's ``datasets/utils.py`` (``CODEBASE_VERSION = "v3.0"``)::

    meta/info.json                                   codebase_version, fps, features, paths ...
    meta/stats.json                                  min/max/mean/std/count and quantiles per feature
    meta/tasks.parquet                               task (the pandas index) -> task_index
    meta/episodes/chunk-000/file-000.parquet         one row per episode: length, tasks, offsets, stats
    data/chunk-000/file-000.parquet                  one row per frame

A frame holds ``timestamp`` (s from the episode's start), ``frame_index``, ``episode_index``,
``index`` (across the dataset), ``task_index``, ``observation.state`` (the robot's joints) and
``action`` (the next frame's joints; the last frame holds its own). The joints are named and
scaled as the robot's own LeRobot driver does (:func:`lerobot_conventions`): the SO-100 and
SO-101 as ``so100_follower`` / ``so101_follower`` record them, every other arm by its URDF joint
names in radians, with the units stated in ``info.json``. One export is one
episode of one task. The folder is built next to ``out`` and renamed into place, so a failed
export leaves nothing half-written, and an existing non-empty folder is never replaced.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from studio._files import make_temp_dir
from studio.kinematics import robot_names, robot_spec

from ._errors import ExportError

CODEBASE_VERSION = "v3.0"
CHUNKS_SIZE = 1000
"""lerobot's DEFAULT_CHUNK_SIZE: files per chunk folder."""
DATA_FILES_SIZE_IN_MB = 100
VIDEO_FILES_SIZE_IN_MB = 500
DATA_PATH = "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
EPISODES_PATH = "meta/episodes/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
VIDEO_PATH = "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
TASKS_PATH = "meta/tasks.parquet"
INFO_PATH = "meta/info.json"
STATS_PATH = "meta/stats.json"
QUANTILES = (0.01, 0.10, 0.50, 0.90, 0.99)
"""The quantiles lerobot's stats carry (``q01`` ... ``q99``)."""


GRIPPER_OPEN = 100.0
"""The SO followers' ``gripper.pos`` while the studio teaches no gripper: open. LeRobot's
calibration maps the gripper's range onto 0 (closed) .. 100 (open) (``MotorNormMode.RANGE_0_100``)."""


@dataclass(frozen=True)
class LeRobotConventions:
    """How one robot's joints are written in a LeRobot dataset.

    Attributes:
        robot_type: ``info.json``'s ``robot_type`` (the LeRobot driver's name, or the studio's).
        names: the ``observation.state`` and ``action`` names.
        units: each name's unit, in the same order.
        offset, scale: a value is ``(q - offset) * scale`` per joint.
        extra: constant columns after the joints (the SO followers' open gripper).
    """

    robot_type: str
    names: tuple[str, ...]
    units: tuple[str, ...]
    offset: np.ndarray
    scale: float
    extra: tuple[float, ...] = ()

    def values(self, q: np.ndarray) -> np.ndarray:
        """The dataset's columns for joint angles ``q`` (N, joints), radians."""
        joints = (np.asarray(q, dtype=float) - self.offset) * self.scale
        constant = np.broadcast_to(
            np.array(self.extra, dtype=float), (len(joints), len(self.extra))
        )
        return np.hstack([joints, constant])


def lerobot_conventions(
    robot: str, joint_names: Sequence[str], lower: np.ndarray, upper: np.ndarray
) -> LeRobotConventions:
    """How ``robot``'s joints are written so that LeRobot's own driver can replay them.

    The SO-100 and SO-101 follow LeRobot's ``so100_follower`` / ``so101_follower``: motors
    ``<joint>.pos`` in degrees (its ``use_degrees``, on by default), which its calibration counts
    from the middle of each joint's range (``(position - mid) * 360 / 4095``), so the middle of the
    URDF's limits is 0 degrees; then ``gripper.pos`` held open. Any other arm: the URDF's joint
    names in radians.
    """
    names = tuple(joint_names)
    # the driver LeRobot drives the arm with (the registry's ``lerobot_driver``), if any
    driver = robot_spec(robot).lerobot_driver if robot in robot_names() else ""
    if driver:
        middle = (np.asarray(lower, dtype=float) + np.asarray(upper, dtype=float)) / 2.0
        return LeRobotConventions(
            driver,
            (*(f"{name}.pos" for name in names), "gripper.pos"),
            (*("deg" for _ in names), "percent open"),
            middle,
            180.0 / np.pi,
            (GRIPPER_OPEN,),
        )
    return LeRobotConventions(robot, names, tuple("rad" for _ in names), np.zeros(len(names)), 1.0)


def features(names: Sequence[str]) -> dict[str, dict[str, object]]:
    """The ``features`` of ``info.json``: lerobot's five default features and the joints."""
    joints = {"dtype": "float32", "shape": [len(names)], "names": list(names)}
    scalar = {"shape": [1], "names": None}
    return {
        "observation.state": joints,
        "action": dict(joints),
        "timestamp": {"dtype": "float32", **scalar},
        "frame_index": {"dtype": "int64", **scalar},
        "episode_index": {"dtype": "int64", **scalar},
        "index": {"dtype": "int64", **scalar},
        "task_index": {"dtype": "int64", **scalar},
    }


def _stats(values: np.ndarray) -> dict[str, list[float] | list[int]]:
    """lerobot's per-feature statistics of ``values`` (N, D)."""
    out: dict[str, list[float] | list[int]] = {
        "min": values.min(axis=0).tolist(),
        "max": values.max(axis=0).tolist(),
        "mean": values.mean(axis=0).tolist(),
        "std": values.std(axis=0).tolist(),
        "count": [int(values.shape[0])],
    }
    for q in QUANTILES:
        out[f"q{round(q * 100):02d}"] = np.quantile(values, q, axis=0).tolist()
    return out


def _columns(times: np.ndarray, q: np.ndarray) -> dict[str, np.ndarray]:
    n = len(times)
    action = np.vstack([q[1:], q[-1:]]) if n else q
    frames = np.arange(n, dtype=np.int64)
    return {
        "observation.state": q.astype(np.float32),
        "action": action.astype(np.float32),
        "timestamp": np.asarray(times, dtype=np.float32),
        "frame_index": frames,
        "episode_index": np.zeros(n, dtype=np.int64),
        "index": frames.copy(),
        "task_index": np.zeros(n, dtype=np.int64),
    }


def _tasks_table(task: str) -> object:
    """``meta/tasks.parquet``: lerobot writes a pandas frame indexed by the task text."""
    import pyarrow as pa

    table = pa.table({"task_index": pa.array([0], pa.int64()), "task": pa.array([task])})
    pandas = {
        "index_columns": ["task"],
        "column_indexes": [],
        "columns": [
            {"name": "task_index", "field_name": "task_index", "pandas_type": "int64",
             "numpy_type": "int64", "metadata": None},
            {"name": "task", "field_name": "task", "pandas_type": "unicode",
             "numpy_type": "object", "metadata": None},
        ],
        "creator": {"library": "pyarrow", "version": pa.__version__},
        "pandas_version": "2.2.0",
    }  # fmt: skip
    return table.replace_schema_metadata({b"pandas": json.dumps(pandas).encode()})


def _build(
    root: Path,
    names: Sequence[str],
    times: np.ndarray,
    q: np.ndarray,
    *,
    fps: int,
    robot_type: str,
    task: str,
    extra: dict[str, object],
) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    columns = _columns(times, q)
    n, dof = q.shape
    arrays = {}
    for key, values in columns.items():
        if values.ndim == 2:
            flat = pa.array(values.reshape(-1), pa.float32())
            arrays[key] = pa.FixedSizeListArray.from_arrays(flat, dof)
        else:
            arrays[key] = pa.array(values)
    data = root / DATA_PATH.format(chunk_index=0, file_index=0)
    data.parent.mkdir(parents=True)
    pq.write_table(pa.table(arrays), data)
    stats = {
        key: _stats(values.reshape(n, -1).astype(np.float64)) for key, values in columns.items()
    }
    episode: dict[str, object] = {
        "episode_index": [0],
        "tasks": [[task]],
        "length": [n],
        "data/chunk_index": [0],
        "data/file_index": [0],
        "dataset_from_index": [0],
        "dataset_to_index": [n],
        "meta/episodes/chunk_index": [0],
        "meta/episodes/file_index": [0],
    }
    for key, feature_stats in stats.items():
        for stat, value in feature_stats.items():
            episode[f"stats/{key}/{stat}"] = [value]
    episodes = root / EPISODES_PATH.format(chunk_index=0, file_index=0)
    episodes.parent.mkdir(parents=True)
    pq.write_table(pa.table(episode), episodes)
    pq.write_table(_tasks_table(task), root / TASKS_PATH)
    (root / STATS_PATH).write_text(json.dumps(stats, indent=4))
    info = {
        "codebase_version": CODEBASE_VERSION,
        "robot_type": robot_type,
        "total_episodes": 1,
        "total_frames": n,
        "total_tasks": 1,
        "chunks_size": CHUNKS_SIZE,
        "data_files_size_in_mb": DATA_FILES_SIZE_IN_MB,
        "video_files_size_in_mb": VIDEO_FILES_SIZE_IN_MB,
        "fps": fps,
        "splits": {"train": "0:1"},
        "data_path": DATA_PATH,
        "video_path": None,
        "features": features(names),
        **extra,
    }
    (root / INFO_PATH).write_text(json.dumps(info, indent=4))


def write_lerobot(
    out: Path,
    names: Sequence[str],
    times: np.ndarray,
    q: np.ndarray,
    *,
    fps: int,
    robot_type: str,
    task: str,
    extra: dict[str, object] | None = None,
) -> None:
    """Write a one-episode LeRobotDataset v3.0 folder at ``out``.

    Args:
        out: the dataset folder (must not exist, or be empty).
        names: the joint names (``observation.state`` and ``action`` names).
        times: seconds from the start, one per frame.
        q: the joints' values, one row per frame, in the units :func:`lerobot_conventions`
            gives the robot.
        fps: the frame rate ``info.json`` states.
        robot_type: ``info.json``'s ``robot_type``.
        task: the episode's task text.
        extra: more ``info.json`` keys (the export's source and checks).

    Raises:
        ExportError: ``out`` is a file or a non-empty folder, or cannot be written.
    """
    if out.is_file() or (out.is_dir() and any(out.iterdir())):
        raise ExportError(
            f"{out} already exists and is not an empty folder; give a new folder for the "
            "LeRobot dataset (nothing was written)."
        )
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = make_temp_dir(f".{out.name}.", out.parent)
    except OSError as err:
        raise ExportError(
            f"Cannot write the LeRobot dataset {out} ({err.strerror or err}); choose a writable "
            "--out."
        ) from None
    try:
        (tmp / "meta").mkdir()
        _build(tmp, names, times, q, fps=fps, robot_type=robot_type, task=task, extra=extra or {})
        if out.is_dir():
            out.rmdir()  # empty, checked above
        tmp.rename(out)
    except OSError as err:
        raise ExportError(
            f"Cannot write the LeRobot dataset {out} ({err.strerror or err}); choose a writable "
            "--out."
        ) from None
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
