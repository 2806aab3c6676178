"""Read back a trajectory ``studio export`` wrote: its CSV or its MCAP (:func:`read_trajectory`).

The formats are :mod:`._formats`': a CSV is ``#`` comment lines, a ``time,<joint names>`` header
and one row per sample; an MCAP holds one ``JointTrajectory`` on ``/joint_trajectory`` (its
points' ``time_from_start``, read first) or one ``JointState`` per sample on ``/joint_states``
(their stamps, real times, read from the first), and the ``teach_studio`` metadata record. A LeRobot dataset is read by ``lerobot`` itself.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from studio._files import open_regular, read_bytes_bounded

from ._errors import ExportError
from ._formats import METADATA_NAME, STATE_TOPIC, TRAJECTORY_TOPIC

MAX_TRAJECTORY_BYTES = 512 * 1024 * 1024
"""The largest trajectory file read (an hour at 1 kHz of a 7-joint arm is ~300 MB of CSV)."""


@dataclass(frozen=True)
class Trajectory:
    """A trajectory read from a file.

    Attributes:
        path: the file.
        names: the joint names, in column order.
        times: seconds from the start, one per sample.
        q: radians, one row per sample.
        notes: what the file says about itself (the CSV's ``#`` lines, the MCAP's metadata).
    """

    path: Path
    names: tuple[str, ...]
    times: np.ndarray
    q: np.ndarray
    notes: tuple[str, ...]


def read_trajectory(path: Path) -> Trajectory:
    """The trajectory in ``path``, a ``.csv`` or ``.mcap`` file as ``studio export`` writes them.

    Raises:
        ExportError: the file is missing, of another kind, or not a trajectory (one sentence).
        FileLimitError: not a regular file, or too large.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".csv":
        return _read_csv(path)
    if suffix == ".mcap":
        return _read_mcap(path)
    raise ExportError(
        f"{path} is neither a .csv nor a .mcap file; give a trajectory `studio export "
        "--format csv` or `--format mcap` wrote."
    )


def _malformed(path: Path, problem: str) -> ExportError:
    return ExportError(
        f"{path} is not a trajectory as `studio export` writes it ({problem}); export it again."
    )


def _read_csv(path: Path) -> Trajectory:
    data = read_bytes_bounded(path, MAX_TRAJECTORY_BYTES, str(path))
    try:
        lines = data.decode("utf-8").splitlines()
    except UnicodeDecodeError:
        raise _malformed(path, "it is not text") from None
    notes = tuple(line[1:].strip() for line in lines if line.startswith("#"))
    body = [line for line in lines if line.strip() and not line.startswith("#")]
    if not body or not body[0].startswith("time,"):
        raise _malformed(path, "no `time,<joint names>` header line")
    names = tuple(name.strip() for name in body[0].split(",")[1:])
    if not names or not all(names):
        raise _malformed(path, "its header names no joints")
    try:
        rows = np.loadtxt(io.StringIO("\n".join(body[1:])), delimiter=",", ndmin=2)
    except ValueError as err:
        raise _malformed(path, f"a row is not numbers: {err}") from None
    if rows.shape[0] == 0:
        raise _malformed(path, "it has no samples")
    if rows.shape[1] != len(names) + 1:
        raise _malformed(
            path, f"its rows have {rows.shape[1]} columns, its header {len(names) + 1}"
        )
    return Trajectory(path, names, rows[:, 0], rows[:, 1:], notes)


def _seconds(stamp: object) -> float:
    return float(stamp.sec) + 1e-9 * float(stamp.nanosec)  # type: ignore[attr-defined]


def _nanoseconds(stamp: object) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)  # type: ignore[attr-defined]


def _read_mcap(path: Path) -> Trajectory:
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open_regular(path, str(path)) as stream:
        try:
            reader = make_reader(stream, decoder_factories=[DecoderFactory()])
            metadata = {m.name: m.metadata for m in reader.iter_metadata()}
            messages = [
                (channel.topic, message)
                for _, channel, _, message in reader.iter_decoded_messages(
                    topics=[TRAJECTORY_TOPIC, STATE_TOPIC]
                )
            ]
        except (McapError, ValueError, KeyError, EOFError) as err:
            raise _malformed(path, f"it cannot be read as MCAP: {err}") from None
    meta = metadata.get(METADATA_NAME, {})
    notes = tuple(f"{key}: {value}" for key, value in meta.items() if value)
    trajectories = [m for topic, m in messages if topic == TRAJECTORY_TOPIC]
    states = [m for topic, m in messages if topic == STATE_TOPIC]
    if trajectories:
        message = trajectories[0]
        names = tuple(message.joint_names)
        times = np.array([_seconds(p.time_from_start) for p in message.points])
        q = np.array([list(p.positions) for p in message.points], dtype=float)
    elif states:
        names = tuple(states[0].name)
        stamps = np.array([_nanoseconds(s.header.stamp) for s in states], dtype=np.int64)
        times = (stamps - stamps[0]) / 1e9  # stamps are real times: from the first sample
        q = np.array([list(s.position) for s in states], dtype=float)
    else:
        raise _malformed(path, f"no {TRAJECTORY_TOPIC} or {STATE_TOPIC} messages")
    if q.ndim != 2 or q.shape[0] == 0 or q.shape[1] != len(names):
        raise _malformed(path, f"its samples do not each give the {len(names)} joints it names")
    return Trajectory(path, names, times, q, notes)
