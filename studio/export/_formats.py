"""The trajectory file formats: CSV with the URDF's joint names, and MCAP with ROS 2 messages.

CSV: ``#`` comment lines first, on every export (the robot, the joint order, the units, the
source, the checks and any finding, the physics report; ``numpy.loadtxt`` and pandas'
``comment="#"`` skip them, :func:`~._read.read_trajectory` reads them back), then
``time,<joint names>`` and one row per sample, seconds (to the nanosecond) and radians.

MCAP (``mcap`` + ``mcap-ros2-support``, no ROS installation needed; Foxglove and Lichtblick draw
the robot moving from it alone):

- ``/robot_description``: the URDF as ``std_msgs/msg/String``, latched, at the start;
- ``/joint_trajectory``: a policy's or a demonstration's one ``trajectory_msgs/msg/JointTrajectory``
  whose points carry positions, velocities and ``time_from_start`` (a recording at its capture
  times has none: it is what the arm did, not a trajectory to follow);
- ``/joint_states``: one ``sensor_msgs/msg/JointState`` per sample;
- ``/tf``: one ``tf2_msgs/msg/TFMessage`` per sample, every link's transform from its parent.

Log times and stamps are real times, nanoseconds since the Unix epoch: a recording's own, or the
export's. Frame ids are the URDF's link names. The file's metadata record ``teach_studio``
states the source, the robot and whether the checks passed, with the findings of an unchecked
export.
"""

from __future__ import annotations

import io
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, BinaryIO

import numpy as np

from studio._files import atomic_write

from ._errors import ExportError

if TYPE_CHECKING:
    from ._tf import LinkTransforms

JOINT_TRAJECTORY = "trajectory_msgs/msg/JointTrajectory"
JOINT_STATE = "sensor_msgs/msg/JointState"
STRING = "std_msgs/msg/String"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
TRAJECTORY_TOPIC = "/joint_trajectory"
STATE_TOPIC = "/joint_states"
DESCRIPTION_TOPIC = "/robot_description"
TF_TOPIC = "/tf"
METADATA_NAME = "teach_studio"
"""The MCAP metadata record that describes the export."""

_SEPARATOR = "=" * 80
_TIME = "int32 sec\nuint32 nanosec\n"
_HEADER = "builtin_interfaces/Time stamp\nstring frame_id\n"
_MSGDEFS = {
    STRING: ("string data\n", []),
    TF_MESSAGE: (
        "geometry_msgs/TransformStamped[] transforms\n",
        [
            (
                "geometry_msgs/TransformStamped",
                "std_msgs/Header header\nstring child_frame_id\nTransform transform\n",
            ),
            ("std_msgs/Header", _HEADER),
            ("builtin_interfaces/Time", _TIME),
            ("geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation\n"),
            ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"),
            ("geometry_msgs/Quaternion", "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n"),
        ],
    ),
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
        notes: lines written first as ``# `` comments (what the file is, its checks and
            findings).
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
    return _stamp_ns(int(round(t * 1e9)))


def _stamp_ns(ns: int) -> dict[str, int]:
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


LATCHED = (
    "- history: keep_last\n  depth: 1\n  reliability: reliable\n  durability: transient_local\n"
    "  deadline:\n    sec: 2147483647\n    nsec: 4294967295\n  lifespan:\n    sec: 2147483647\n"
    "    nsec: 4294967295\n  liveliness: automatic\n  liveliness_lease_duration:\n"
    "    sec: 2147483647\n    nsec: 4294967295\n  avoid_ros_namespace_conventions: false\n"
)
"""The QoS a ROS 2 bag records for a latched topic (``offered_qos_profiles``): a subscriber that
joins late (``robot_state_publisher``, Foxglove) still gets ``/robot_description``."""


def write_mcap(
    path: Path,
    names: Sequence[str],
    times: np.ndarray,
    q: np.ndarray,
    *,
    states: bool,
    metadata: dict[str, str],
    start_ns: int | None = None,
    urdf: str = "",
    links: LinkTransforms | None = None,
) -> None:
    """Write an MCAP file of ROS 2 messages (atomically) that robot tools read whole.

    Args:
        path: the ``.mcap`` file.
        names: the joint names.
        times: seconds from the start.
        q: radians, one row per sample.
        states: a recording at its capture times: joint states only, no trajectory to follow.
        metadata: the ``teach_studio`` metadata record's key-value pairs.
        start_ns: the first sample's time, nanoseconds since the Unix epoch (the recording's own
            time; None: now): every log time and stamp counts from it.
        urdf: the robot's URDF, latched on ``/robot_description`` at the start.
        links: every link's transform per sample (:func:`link_transforms`), on ``/tf``; its
            root link is the frame id of the joint messages.
    """
    from mcap_ros2.writer import Writer

    names = list(names)
    velocity = np.gradient(q, times, axis=0) if len(times) > 1 else np.zeros_like(q)
    start_ns = time.time_ns() if start_ns is None else start_ns
    at = [start_ns + int(round(float(t) * 1e9)) for t in times]
    frame_id = links.root if links is not None else ""

    def write(stream: BinaryIO) -> None:
        writer = Writer(stream)
        if urdf:
            schema = writer.register_msgdef(STRING, msgdef(STRING))
            _latch(writer, DESCRIPTION_TOPIC, schema)
            writer.write_message(DESCRIPTION_TOPIC, schema, {"data": urdf}, log_time=at[0])
        if not states:
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
                "header": {"stamp": _stamp_ns(at[0]), "frame_id": frame_id},
                "joint_names": names,
                "points": points,
            }
            writer.write_message(TRAJECTORY_TOPIC, schema, message, log_time=at[0])
        state = writer.register_msgdef(JOINT_STATE, msgdef(JOINT_STATE))
        tf = writer.register_msgdef(TF_MESSAGE, msgdef(TF_MESSAGE)) if links else None
        for i, ns in enumerate(at):
            message = {
                "header": {"stamp": _stamp_ns(ns), "frame_id": frame_id},
                "name": names,
                "position": q[i].tolist(),
                "velocity": velocity[i].tolist(),
                "effort": [],
            }
            writer.write_message(STATE_TOPIC, state, message, log_time=ns, publish_time=ns)
            if tf is not None and links is not None:
                writer.write_message(TF_TOPIC, tf, _tf_message(links, i, ns), log_time=ns)
        writer.add_metadata(METADATA_NAME, metadata)
        writer.finish()

    _write_or_refuse(path, write, "MCAP file")


def _latch(writer: object, topic: str, schema: object) -> None:
    """Register ``topic`` with the latched QoS a ROS 2 bag gives it (mcap_ros2's writer
    registers its channels with no metadata, so the channel is registered here first)."""
    channel = writer._writer.register_channel(  # type: ignore[attr-defined]
        topic=topic,
        message_encoding="cdr",
        schema_id=schema.id,  # type: ignore[attr-defined]
        metadata={"offered_qos_profiles": LATCHED},
    )
    writer._channel_ids[topic] = channel  # type: ignore[attr-defined]


def _tf_message(links: LinkTransforms, i: int, ns: int) -> dict[str, object]:
    stamp = _stamp_ns(ns)
    transforms = []
    for e, (parent, child) in enumerate(links.edges):
        x, y, z = links.translation[i, e].tolist()
        qx, qy, qz, qw = links.rotation[i, e].tolist()
        transforms.append(
            {
                "header": {"stamp": stamp, "frame_id": parent},
                "child_frame_id": child,
                "transform": {
                    "translation": {"x": x, "y": y, "z": z},
                    "rotation": {"x": qx, "y": qy, "z": qz, "w": qw},
                },
            }
        )
    return {"transforms": transforms}
