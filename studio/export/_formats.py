"""The trajectory file formats: CSV with the URDF's joint names, and MCAP with ROS 2 messages.

CSV: ``time,<joint names>``, one row per sample, seconds (to the nanosecond) and radians. Findings of an unchecked
export come first as ``#`` comment lines (``numpy.loadtxt`` and pandas' ``comment="#"`` skip them).

MCAP (``mcap`` + ``mcap-ros2-support``, no ROS installation needed; opens in Foxglove and
Lichtblick): a policy or a demonstration is one ``trajectory_msgs/msg/JointTrajectory`` on
``/joint_trajectory`` whose points carry positions, velocities and ``time_from_start``; a
recording is one ``sensor_msgs/msg/JointState`` per captured frame on ``/joint_states``, stamped
at its capture time. The file's metadata record ``teach_studio`` states the source, the robot and
whether the checks passed, with the findings of an unchecked export.
"""

from __future__ import annotations

import io
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import BinaryIO

import numpy as np

from studio._files import atomic_write

from ._errors import ExportError

JOINT_TRAJECTORY = "trajectory_msgs/msg/JointTrajectory"
JOINT_STATE = "sensor_msgs/msg/JointState"
TRAJECTORY_TOPIC = "/joint_trajectory"
STATE_TOPIC = "/joint_states"
METADATA_NAME = "teach_studio"
"""The MCAP metadata record that describes the export."""

_SEPARATOR = "=" * 80
_TIME = "int32 sec\nuint32 nanosec\n"
_HEADER = "builtin_interfaces/Time stamp\nstring frame_id\n"
_MSGDEFS = {
    JOINT_STATE: (
        "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n"
        "float64[] effort\n",
        [("std_msgs/Header", _HEADER), ("builtin_interfaces/Time", _TIME)],
    ),
    JOINT_TRAJECTORY: (
        "std_msgs/Header header\nstring[] joint_names\nJointTrajectoryPoint[] points\n",
        [
            ("std_msgs/Header", _HEADER),
            ("builtin_interfaces/Time", _TIME),
            (
                "trajectory_msgs/JointTrajectoryPoint",
                "float64[] positions\nfloat64[] velocities\nfloat64[] accelerations\n"
                "float64[] effort\nbuiltin_interfaces/Duration time_from_start\n",
            ),
            ("builtin_interfaces/Duration", _TIME),
        ],
    ),
}


def msgdef(datatype: str) -> str:
    """The ROS 2 message definition of ``datatype`` with its dependencies, as ``ros2 bag`` and
    Foxglove expect in an MCAP schema (each dependency after a ``MSG:`` separator)."""
    text, deps = _MSGDEFS[datatype]
    return text + "".join(f"{_SEPARATOR}\nMSG: {name}\n{body}" for name, body in deps)


def _write_or_refuse(path: Path, write: Callable[[BinaryIO], None], what: str) -> None:
    try:
        atomic_write(path, write)
    except OSError as err:
        raise ExportError(
            f"Cannot write the {what} {path} ({err.strerror or err}); choose a writable --out."
        ) from None


def write_csv(
    path: Path,
    names: Sequence[str],
    times: np.ndarray,
    q: np.ndarray,
    notes: Sequence[str] = (),
) -> None:
    """Write ``time,<names>`` and one row per sample (atomically: no half file is ever seen).

    Args:
        path: the CSV file.
        names: the joint names (the URDF's).
        times: seconds from the start.
        q: radians, one row per sample.
        notes: lines written first as ``# `` comments (an unchecked export's findings).
    """
    buffer = io.StringIO()
    for note in notes:
        buffer.write(f"# {note}\n")
    np.savetxt(
        buffer,
        np.column_stack([times, q]),
        delimiter=",",
        header=",".join(["time", *names]),
        comments="",
        fmt=["%.9f"] + ["%.9g"] * q.shape[1],  # time to the nanosecond, as MCAP stamps it
    )
    data = buffer.getvalue().encode("utf-8")
    _write_or_refuse(path, lambda f: f.write(data), "CSV file")


def _stamp(t: float) -> dict[str, int]:
    ns = int(round(t * 1e9))
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def write_mcap(
    path: Path,
    names: Sequence[str],
    times: np.ndarray,
    q: np.ndarray,
    *,
    states: bool,
    metadata: dict[str, str],
) -> None:
    """Write an MCAP file of ROS 2 messages (atomically).

    Args:
        path: the ``.mcap`` file.
        names: the joint names.
        times: seconds from the start.
        q: radians, one row per sample.
        states: one ``JointState`` per sample (a recording) instead of one ``JointTrajectory``.
        metadata: the ``teach_studio`` metadata record's key-value pairs.
    """
    from mcap_ros2.writer import Writer

    names = list(names)
    velocity = np.gradient(q, times, axis=0) if len(times) > 1 else np.zeros_like(q)

    def write(stream: BinaryIO) -> None:
        writer = Writer(stream)
        if states:
            schema = writer.register_msgdef(JOINT_STATE, msgdef(JOINT_STATE))
            for i, t in enumerate(times):
                ns = int(round(float(t) * 1e9))
                message = {
                    "header": {"stamp": _stamp(float(t)), "frame_id": ""},
                    "name": names,
                    "position": q[i].tolist(),
                    "velocity": velocity[i].tolist(),
                    "effort": [],
                }
                writer.write_message(STATE_TOPIC, schema, message, log_time=ns, publish_time=ns)
        else:
            schema = writer.register_msgdef(JOINT_TRAJECTORY, msgdef(JOINT_TRAJECTORY))
            points = [
                {
                    "positions": q[i].tolist(),
                    "velocities": velocity[i].tolist(),
                    "accelerations": [],
                    "effort": [],
                    "time_from_start": _stamp(float(t)),
                }
                for i, t in enumerate(times)
            ]
            message = {
                "header": {"stamp": _stamp(0.0), "frame_id": ""},
                "joint_names": names,
                "points": points,
            }
            writer.write_message(TRAJECTORY_TOPIC, schema, message, log_time=0, publish_time=0)
        writer.add_metadata(METADATA_NAME, metadata)
        writer.finish()

    _write_or_refuse(path, write, "MCAP file")
