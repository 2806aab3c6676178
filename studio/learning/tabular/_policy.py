"""Policy files: a learned arm policy on disk, and its greedy rollout as a joint trajectory.

Format ``teach-studio-policy``, version 1: a ``.npz`` archive (``numpy.savez_compressed``) holding

- ``header``: a 0-d unicode array with a JSON object::

      {"format": "teach-studio-policy", "version": 1,
       "grid": {"joints": 3, "bins": 11, "low_deg": -180.0, "high_deg": 180.0, "goal": [5, 6, 2]},
       "goal_state": 678, "n_states": 1331, "n_actions": 27,
       "config": {... DynaQConfig fields ...},
       "curve": {"mean_steps": [...], "experiments": 20},
       "created": "2026-11-22T21:40:00+00:00", "notes": ""}

- ``q``: float64 ``(n_states, n_actions)``, the Q table;
- ``greedy``: int64 ``(n_states,)``, the greedy action per state (ties: lowest action index).

numpy alone reads it without pickles::

    f = np.load("arm.policy.npz")
    header = json.loads(str(f["header"]))
    q, greedy = f["q"], f["greedy"]

States and actions are numbered as in :class:`ArmGrid` (joint 1 the most significant digit; action
digit ``d`` moves its joint by ``d - 1`` bins). Readers refuse a file whose version is newer than
the one they know.
"""

from __future__ import annotations

import io
import json
import math
import zipfile
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import IO, TypedDict

import numpy as np
from numpy.lib import format as npy_format

from studio import JSONFileError, loads_json

from .._config import MAX_EPISODES, DynaQConfig
from .._config import ROLLOUT_MAX_STEPS as ROLLOUT_MAX_STEPS
from .._config import ROLLOUT_RATE_HZ as ROLLOUT_RATE_HZ
from .._config import ROLLOUT_SECONDS_PER_STEP as ROLLOUT_SECONDS_PER_STEP
from .._errors import LearningError, PolicyFileError
from ..tasks._arm import ArmGrid
from ..tasks._robot import default_goal, task_arm

FORMAT_NAME = "teach-studio-policy"
FORMAT_VERSION = 1
ROBOT_JOINTS = 6
"""Columns of a rollout trajectory: the Puma560's six joints."""
MAX_NPY_HEADER_BYTES = 10_000
"""Longest ``.npy`` member header read (numpy's own safe limit)."""
MAX_NPZ_BYTES = 256 * 1024 * 1024
"""Most bytes decompressed from one ``.npz`` file, all members together (the largest arm grid's
Q table is 96 MB)."""
MAX_HEADER_CHARS = 64 * (MAX_EPISODES + 10_000)
"""Longest policy JSON header: a curve of :data:`MAX_EPISODES` values and the settings."""
NPZ_READ_BYTES = 1024 * 1024
"""Bytes decompressed at a time."""


@dataclass(frozen=True)
class NpyHeader:
    """What a ``.npy`` member's header says its data is (read before any data is)."""

    shape: tuple[int, ...]
    dtype: np.dtype
    fortran_order: bool

    @property
    def nbytes(self) -> int:
        """Bytes of data the header promises."""
        return math.prod(self.shape) * self.dtype.itemsize


class BoundedNpz:
    """A ``.npz`` archive read member by member, each checked by its header before it is inflated.

    ``np.load`` decompresses a member whole before its shape can be judged, so a small zip bomb
    inflates to gigabytes. Here each member's ``.npy`` header (shape, dtype) is read first, from
    the start of the compressed stream; the data is decompressed only when the caller's expected
    shape and dtype kinds match, never more than the header promises, and never more than
    ``max_bytes`` for the whole archive. No pickles are ever loaded.

    Args:
        path: the ``.npz`` file.
        name: the file as error sentences name it.
        max_bytes: cap on decompressed bytes over all members.

    Raises:
        PolicyFileError: the file is not a readable zip archive.

    Example::

        with BoundedNpz(path, path.name) as npz:
            header = npz.read_text("header", MAX_HEADER_CHARS)
            q = npz.read("q", (n_states, n_actions), kinds="f")
    """

    def __init__(self, path: str | Path, name: str, max_bytes: int = MAX_NPZ_BYTES) -> None:
        self.name, self.budget = name, int(max_bytes)
        try:
            self._zip = zipfile.ZipFile(path)
        except (OSError, zipfile.BadZipFile, ValueError, EOFError) as err:
            raise PolicyFileError(
                f"{name} is corrupt or not a policy file ({type(err).__name__}); export the policy again."
            ) from None
        self.files = [n.removesuffix(".npy") for n in self._zip.namelist() if n.endswith(".npy")]

    def __enter__(self) -> BoundedNpz:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Release the file."""
        self._zip.close()

    def _refuse(self, what: str) -> PolicyFileError:
        return PolicyFileError(f"{self.name} {what}; export the policy again.")

    def _open(self, key: str) -> tuple[IO[bytes], NpyHeader]:
        if key not in self.files:
            raise self._refuse(f"has no {key!r} array")
        try:
            stream = self._zip.open(key + ".npy")
            try:
                version = npy_format.read_magic(stream)
                if version not in ((1, 0), (2, 0)):
                    raise ValueError(f"npy version {version}")
                length_field = stream.read(2 if version == (1, 0) else 4)
                length = int.from_bytes(length_field, "little")
                if length > MAX_NPY_HEADER_BYTES:  # numpy would read it all before checking
                    raise ValueError(f"a {length}-byte array header")
                header_bytes = length_field + stream.read(length)
                reader = (
                    npy_format.read_array_header_1_0
                    if version == (1, 0)
                    else npy_format.read_array_header_2_0
                )
                shape, fortran_order, dtype = reader(
                    io.BytesIO(header_bytes), max_header_size=MAX_NPY_HEADER_BYTES
                )
            except BaseException:
                stream.close()
                raise
        except PolicyFileError:
            raise
        except (
            OSError,
            ValueError,
            EOFError,
            RuntimeError,
            RecursionError,
            zipfile.BadZipFile,
        ) as err:
            raise self._refuse(f"has a damaged {key!r} array ({err})") from None
        if dtype.hasobject:
            stream.close()
            raise self._refuse(f"holds Python objects in {key!r}, which are never loaded")
        return stream, NpyHeader(tuple(int(n) for n in shape), dtype, bool(fortran_order))

    def header(self, key: str) -> NpyHeader:
        """Member ``key``'s shape and dtype, from its header alone (no data is decompressed)."""
        stream, header = self._open(key)
        stream.close()
        return header

    def read(
        self, key: str, shape: tuple[int, ...] | None, kinds: str, max_bytes: int | None = None
    ) -> np.ndarray:
        """Member ``key``, decompressed only if its header matches what the caller expects.

        Args:
            key: the member's name (without ``.npy``).
            shape: the exact shape required (``None``: any shape within ``max_bytes``).
            kinds: accepted ``dtype.kind`` letters (``"f"``, ``"iu"``, ``"U"``...).
            max_bytes: cap on this member's data (the archive's remaining budget applies too).

        Raises:
            PolicyFileError: the header does not match, the data is larger than allowed, is
                truncated, holds more than its header says, or fails its CRC.
        """
        stream, header = self._open(key)
        with stream:
            if header.dtype.kind not in kinds:
                raise self._refuse(f"stores {key!r} as {header.dtype}, not the expected kind")
            if shape is not None and header.shape != tuple(shape):
                raise self._refuse(
                    f"says its {key!r} array has shape {header.shape} where {tuple(shape)} was expected"
                )
            limit = self.budget if max_bytes is None else min(self.budget, max_bytes)
            if header.nbytes > limit:
                raise self._refuse(
                    f"says its {key!r} array holds {header.nbytes:,} bytes, more than the "
                    f"{limit:,} allowed"
                )
            count = math.prod(header.shape)
            flat = np.empty(count, dtype=header.dtype)  # justified by the checks above
            raw = flat.view(np.uint8)
            done = 0
            try:
                while done < header.nbytes:
                    chunk = stream.read(min(NPZ_READ_BYTES, header.nbytes - done))
                    if not chunk:
                        raise self._refuse(f"has a truncated {key!r} array")
                    raw[done : done + len(chunk)] = np.frombuffer(chunk, dtype=np.uint8)
                    done += len(chunk)
                if stream.read(1):  # reading to the end also checks the CRC
                    raise self._refuse(f"holds more {key!r} data than its header says")
            except (OSError, EOFError, zipfile.BadZipFile, RuntimeError) as err:
                raise self._refuse(f"has a damaged {key!r} array ({err})") from None
            self.budget -= header.nbytes
        order = "F" if header.fortran_order else "C"
        return flat.reshape(header.shape, order=order)

    def read_text(self, key: str, max_chars: int) -> str:
        """A 0-d unicode member (as ``np.savez`` stores a ``str``) of at most ``max_chars``."""
        array = self.read(key, (), "U", max_bytes=4 * max_chars)
        return str(array[()])


@dataclass(frozen=True, eq=False)
class PolicyFile:
    """A learned policy with everything needed to use and judge it.

    Attributes:
        grid: the arm grid the policy acts on.
        q: float ``(n_states, n_actions)``, the Q table.
        greedy: int ``(n_states,)``, the greedy action per state.
        config: the training settings.
        mean_steps: the learning curve, mean steps per episode.
        experiments: how many experiments the curve averages.
        created: ISO 8601 time of writing.
        notes: free text.
    """

    grid: ArmGrid
    q: np.ndarray
    greedy: np.ndarray
    config: DynaQConfig
    mean_steps: np.ndarray = field(default_factory=lambda: np.zeros(0))
    experiments: int = 1
    created: str = ""
    notes: str = ""

    @property
    def robot(self) -> str:
        """The robot it was learnt on (the grid's; a file written before grids named one: the
        Puma560)."""
        return self.grid.robot

    def header(self) -> dict[str, object]:
        """The JSON header written to the file."""
        return {
            "format": FORMAT_NAME,
            "version": FORMAT_VERSION,
            "grid": self.grid.to_dict(),
            "goal_state": self.grid.goal_state,
            "n_states": self.grid.n_states,
            "n_actions": self.grid.n_actions,
            "config": self.config.to_dict(),
            "curve": curve_header(self.mean_steps, self.experiments),
            "created": self.created,
            "notes": self.notes,
        }


def read_header(archive: BoundedNpz, name: str) -> object:
    """The JSON header of a policy archive (every policy kind has one), bounded like every JSON
    the studio reads; a damaged one is a :class:`PolicyFileError` naming the file."""
    try:
        return loads_json(
            archive.read_text("header", MAX_HEADER_CHARS),
            f"{name}'s header",
            max_bytes=MAX_HEADER_CHARS,
        )
    except JSONFileError as err:
        raise PolicyFileError(str(err)) from None


class CurveHeader(TypedDict):
    """A policy header's ``curve``: mean steps per episode (``None`` where no experiment ran
    that episode) and how many experiments they average."""

    mean_steps: list[float | None]
    experiments: int


def curve_header(mean_steps: np.ndarray, experiments: int) -> CurveHeader:
    """A policy header's ``curve``: the learning curve it came from, JSON-ready (NaN as null).

    Shared by the tabular and the tile-coded policy formats.
    """
    return {
        "mean_steps": [None if not np.isfinite(x) else float(x) for x in mean_steps],
        "experiments": int(experiments),
    }


def read_curve_header(curve: object) -> tuple[np.ndarray, int]:
    """The ``(mean_steps, experiments)`` of a policy header's ``curve`` (:func:`curve_header`).

    Raises:
        ValueError: not a list of numbers (null for none) and a whole number of experiments.
    """
    if not isinstance(curve, dict):
        raise ValueError("its curve is not a table")
    values = curve.get("mean_steps", [])
    if not isinstance(values, list) or any(
        x is not None and (isinstance(x, bool) or not isinstance(x, int | float)) for x in values
    ):
        raise ValueError("its curve is not a list of numbers")
    mean_steps = np.array([np.nan if x is None else x for x in values], dtype=np.float64)
    if np.isinf(mean_steps).any():
        raise ValueError("its curve holds an infinite value")
    experiments = curve.get("experiments", 1)
    if not isinstance(experiments, int) or isinstance(experiments, bool) or experiments < 1:
        raise ValueError(f"experiments is {experiments!r}, not a whole number of at least 1")
    return mean_steps, experiments


def greedy_actions(q: np.ndarray) -> np.ndarray:
    """Greedy action per state, ties going to the lowest action index (deterministic)."""
    return np.argmax(q, axis=1).astype(np.int64)


def save_policy(
    path: str | Path,
    grid: ArmGrid,
    q: np.ndarray,
    config: DynaQConfig,
    mean_steps: np.ndarray | None = None,
    *,
    experiments: int = 1,
    notes: str = "",
    compress: bool = True,
) -> PolicyFile:
    """Write a policy file (format above) and return what was written.

    Args:
        path: where to write; ``.policy.npz`` is the convention.
        grid: the arm grid the Q table belongs to.
        q: float ``(n_states, n_actions)``, for example ``result.q[result.best_experiment()]``.
        config: the training settings.
        mean_steps: the learning curve, for example ``result.mean_steps()``.
        experiments: how many experiments the curve averages.
        notes: free text kept in the header.
        compress: deflate the members (a training checkpoint does not: a large table is written
            in a fraction of the time, and the file reads the same).
    """
    q = np.ascontiguousarray(q, dtype=np.float64)
    if q.shape != (grid.n_states, grid.n_actions):
        raise LearningError(
            f"The Q table has shape {q.shape} but the grid needs ({grid.n_states}, {grid.n_actions}); save the Q table of this grid."
        )
    if not np.all(np.isfinite(q)):
        raise LearningError(
            "The Q table holds NaN or infinite values; save a table from a finished run."
        )
    policy = PolicyFile(
        grid=grid,
        q=q,
        greedy=greedy_actions(q),
        config=config,
        mean_steps=np.asarray([] if mean_steps is None else mean_steps, dtype=np.float64),
        experiments=experiments,
        created=datetime.now(UTC).isoformat(timespec="seconds"),
        notes=notes,
    )
    path = Path(path)
    with path.open("wb") as stream:
        (np.savez_compressed if compress else np.savez)(
            stream,
            header=np.array(json.dumps(policy.header())),
            q=policy.q,
            greedy=policy.greedy,
        )
    return policy


def load_policy(path: str | Path) -> PolicyFile:
    """Read a policy file, checking its format, version and shapes.

    Raises:
        PolicyFileError: the file is missing, corrupt, not a policy, or from a newer version.
    """
    path = Path(path)
    name = path.name
    if not path.is_file():
        raise PolicyFileError(
            f"Policy file {name} does not exist; give the path of a .policy.npz file."
        )
    # Bounded: the JSON header is read (size and depth limited) and checked first; the tables
    # are decompressed only when their .npy headers have exactly the shapes its grid implies.
    with BoundedNpz(path, name) as archive:
        missing = {"header", "q", "greedy"} - set(archive.files)
        if missing:
            raise PolicyFileError(
                f"{name} lacks {', '.join(sorted(missing))}; it is not a Teach Studio policy file, export one again."
            )
        header = read_header(archive, name)
        header, grid, config, mean_steps, experiments = _check_header(name, header)
        q = archive.read("q", (grid.n_states, grid.n_actions), "fiu").astype(np.float64, copy=False)
        greedy = archive.read("greedy", (grid.n_states,), "iu").astype(np.int64, copy=False)
    if not np.all(np.isfinite(q)) or greedy.min() < 0 or greedy.max() >= grid.n_actions:
        raise PolicyFileError(f"{name} holds invalid Q values or actions; export the policy again.")
    return PolicyFile(
        grid=grid,
        q=q,
        greedy=greedy,
        config=config,
        mean_steps=mean_steps,
        experiments=experiments,
        created=str(header.get("created", "")),
        notes=str(header.get("notes", "")),
    )


def _check_header(
    name: str, header: object
) -> tuple[dict[str, object], ArmGrid, DynaQConfig, np.ndarray, int]:
    """The header as a table, and its grid, settings, curve and experiment count, all validated.

    Raises:
        PolicyFileError: not a policy header, a newer version, or a damaged field.
    """
    if not isinstance(header, dict) or header.get("format") != FORMAT_NAME:
        raise PolicyFileError(f"{name} is not a Teach Studio policy file; export the policy again.")
    version = header.get("version")
    if not isinstance(version, int) or version < 1:
        raise PolicyFileError(
            f"{name} has an invalid format version {version!r}; export the policy again."
        )
    if version > FORMAT_VERSION:
        raise PolicyFileError(
            f"{name} uses policy format version {version}, newer than this studio's {FORMAT_VERSION}; upgrade Teach Studio to read it."
        )
    try:
        grid = ArmGrid(**{**header["grid"], "goal": tuple(header["grid"]["goal"])})
        config = DynaQConfig.from_dict(header["config"])
        mean_steps, experiments = read_curve_header(header.get("curve", {}))
    except (KeyError, TypeError, ValueError, AttributeError, OverflowError, LearningError) as err:
        raise PolicyFileError(
            f"{name} has a damaged header ({err}); export the policy again."
        ) from None
    return header, grid, config, mean_steps, experiments


def greedy_path(
    policy: PolicyFile, start_state: int, max_steps: int = ROLLOUT_MAX_STEPS
) -> list[int]:
    """States visited by following the greedy actions from ``start_state``.

    Stops at the goal, after ``max_steps`` steps, or when a state repeats (the policy loops, so
    going on would only repeat the loop).
    """
    grid = policy.grid
    grid._check_state(start_state)
    mdp_next = grid.mdp().next_state
    path = [int(start_state)]
    seen = {int(start_state)}
    goal = grid.goal_state
    while path[-1] != goal and len(path) <= max_steps:
        s = mdp_next[path[-1], policy.greedy[path[-1]]]
        if int(s) in seen:
            break
        seen.add(int(s))
        path.append(int(s))
    return path


def _min_jerk(u: np.ndarray) -> np.ndarray:
    """0 -> 1 with zero velocity and acceleration at both ends."""
    return u**3 * (10.0 - 15.0 * u + 6.0 * u**2)


def rollout(
    policy: PolicyFile,
    start_state: int,
    rate_hz: float = ROLLOUT_RATE_HZ,
    max_steps: int = ROLLOUT_MAX_STEPS,
    *,
    seconds_per_step: float = ROLLOUT_SECONDS_PER_STEP,
    hold: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The greedy policy from ``start_state`` as a joint trajectory of its robot.

    Consecutive bin centres are joined by minimum-jerk segments of ``seconds_per_step`` each
    (the arm starts and stops smoothly at every grid state) sampled at ``rate_hz``.

    Args:
        policy: a loaded or saved policy.
        start_state: grid state to start from.
        rate_hz: control rate of the samples.
        max_steps: cap on greedy steps (see :func:`greedy_path`).
        seconds_per_step: duration of one grid step.
        hold: angles (rad, one per robot joint) for the joints the grid does not cover;
            default: the robot's default goal's (0 for the Puma560's wrist).

    Returns:
        ``(times (N,), q (N, nq))`` in seconds and radians, from t = 0 to the end (the
        Puma560's ``nq`` is 6).
    """
    for name, value in (("rate_hz", rate_hz), ("seconds_per_step", seconds_per_step)):
        if not isinstance(value, int | float) or not np.isfinite(value) or value <= 0:
            raise LearningError(f"{name} is {value!r}; give a positive number.")
    if not isinstance(max_steps, int) or max_steps < 0:
        raise LearningError(f"max_steps is {max_steps!r}; give a whole number >= 0.")
    grid = policy.grid
    width = task_arm(grid.robot).nq
    hold = default_goal(grid.robot) if hold is None else np.asarray(hold, dtype=np.float64)
    if hold.shape != (width,) or not np.all(np.isfinite(hold)):
        raise LearningError(
            f"hold has shape {hold.shape}; give {width} finite joint angles in radians."
        )
    path = greedy_path(policy, start_state, max_steps)
    centres = np.array([grid.angles_of(s) for s in path])  # (K, joints)
    samples_per_step = max(1, round(seconds_per_step * rate_hz))
    n = (len(path) - 1) * samples_per_step + 1
    times = np.arange(n) / rate_hz
    q = np.tile(hold, (n, 1))
    if len(path) == 1:
        q[0, : grid.joints] = centres[0]
        return times, q
    u = np.arange(samples_per_step) / samples_per_step
    blend = _min_jerk(u)[:, None]
    segments = centres[:-1, None, :] + blend[None] * (centres[1:] - centres[:-1])[:, None, :]
    q[:-1, : grid.joints] = segments.reshape(-1, grid.joints)
    q[-1, : grid.joints] = centres[-1]
    return times, q


def save_trajectory_csv(path: str | Path, times: np.ndarray, q: np.ndarray) -> None:
    """Write a joint trajectory as CSV with columns ``time, q1..q6`` (seconds, radians)."""
    times = np.asarray(times, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    if q.ndim != 2 or q.shape[0] != times.shape[0]:
        raise LearningError(
            f"times {times.shape} and q {q.shape} do not match; give one row of q per time."
        )
    header = ",".join(["time", *(f"q{j + 1}" for j in range(q.shape[1]))])
    np.savetxt(
        Path(path),
        np.column_stack([times, q]),
        delimiter=",",
        header=header,
        comments="",
        fmt="%.9g",
    )
