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

import json
import zipfile
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from ._arm import ArmGrid
from ._config import DynaQConfig
from ._errors import LearningError, PolicyFileError

FORMAT_NAME = "teach-studio-policy"
FORMAT_VERSION = 1
ROBOT_JOINTS = 6
"""Columns of a rollout trajectory: the Puma560's six joints."""
DEFAULT_RATE_HZ = 50.0
"""Default control rate of a rollout trajectory."""
DEFAULT_SECONDS_PER_STEP = 0.5
"""Default time the arm takes to move one grid step."""
DEFAULT_MAX_STEPS = 1_000
"""Default cap on greedy steps in a rollout."""


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

    def header(self) -> dict[str, Any]:
        """The JSON header written to the file."""
        return {
            "format": FORMAT_NAME,
            "version": FORMAT_VERSION,
            "grid": self.grid.to_dict(),
            "goal_state": self.grid.goal_state,
            "n_states": self.grid.n_states,
            "n_actions": self.grid.n_actions,
            "config": self.config.to_dict(),
            "curve": {
                "mean_steps": [None if not np.isfinite(x) else float(x) for x in self.mean_steps],
                "experiments": int(self.experiments),
            },
            "created": self.created,
            "notes": self.notes,
        }


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
        np.savez_compressed(
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
    try:
        with np.load(path, allow_pickle=False) as archive:
            missing = {"header", "q", "greedy"} - set(archive.files)
            if missing:
                raise PolicyFileError(
                    f"{name} lacks {', '.join(sorted(missing))}; it is not a Teach Studio policy file, export one again."
                )
            header = json.loads(str(archive["header"]))
            q = np.asarray(archive["q"], dtype=np.float64)
            greedy = np.asarray(archive["greedy"], dtype=np.int64)
    except PolicyFileError:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError, TypeError) as err:
        raise PolicyFileError(
            f"{name} is corrupt or not a policy file ({type(err).__name__}); export the policy again."
        ) from None
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
        curve = header.get("curve", {})
        mean_steps = np.array(
            [np.nan if x is None else x for x in curve.get("mean_steps", [])], dtype=np.float64
        )
        experiments = int(curve.get("experiments", 1))
    except (KeyError, TypeError, ValueError, LearningError) as err:
        raise PolicyFileError(
            f"{name} has a damaged header ({err}); export the policy again."
        ) from None
    if q.shape != (grid.n_states, grid.n_actions) or greedy.shape != (grid.n_states,):
        raise PolicyFileError(
            f"{name} holds tables of shape {q.shape} and {greedy.shape}, which do not match its grid; export the policy again."
        )
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


def greedy_path(
    policy: PolicyFile, start_state: int, max_steps: int = DEFAULT_MAX_STEPS
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
    rate_hz: float = DEFAULT_RATE_HZ,
    max_steps: int = DEFAULT_MAX_STEPS,
    *,
    seconds_per_step: float = DEFAULT_SECONDS_PER_STEP,
    hold: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The greedy policy from ``start_state`` as a Puma560 joint trajectory.

    Consecutive bin centres are joined by minimum-jerk segments of ``seconds_per_step`` each
    (the arm starts and stops smoothly at every grid state) sampled at ``rate_hz``.

    Args:
        policy: a loaded or saved policy.
        start_state: grid state to start from.
        rate_hz: control rate of the samples.
        max_steps: cap on greedy steps (see :func:`greedy_path`).
        seconds_per_step: duration of one grid step.
        hold: angles (rad, ``(6,)``) for the joints the grid does not cover; default 0.

    Returns:
        ``(times (N,), q (N, 6))`` in seconds and radians, from t = 0 to the end.
    """
    for name, value in (("rate_hz", rate_hz), ("seconds_per_step", seconds_per_step)):
        if not isinstance(value, int | float) or not np.isfinite(value) or value <= 0:
            raise LearningError(f"{name} is {value!r}; give a positive number.")
    if not isinstance(max_steps, int) or max_steps < 0:
        raise LearningError(f"max_steps is {max_steps!r}; give a whole number >= 0.")
    if hold is None:
        hold = np.zeros(ROBOT_JOINTS)
    hold = np.asarray(hold, dtype=np.float64)
    if hold.shape != (ROBOT_JOINTS,) or not np.all(np.isfinite(hold)):
        raise LearningError(
            f"hold has shape {hold.shape}; give {ROBOT_JOINTS} finite joint angles in radians."
        )
    grid = policy.grid
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
