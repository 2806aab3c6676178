"""Tile-coded policy files: linear Dyna-Q's weights on disk, and their greedy arm rollout.

Format ``teach-studio-tile-policy``, version 1: a ``.policy.npz`` archive
(``numpy.savez_compressed``, no pickles) beside the tabular format of :mod:`._policy`, holding

- ``header``: a 0-d unicode array with a JSON object::

      {"format": "teach-studio-tile-policy", "version": 1,
       "env_id": "TeachStudio/ArmReach-v0",
       "task": {"joints": 6, "step_deg": 2.0, "goal": [...rad, 6...], "position_tolerance": 0.02,
                "angle_tolerance_deg": 10.0, "shaping": 5.0},      (null for other environments)
       "tile_coding": {"tilings": 8, "tiles": 32, "size": null, "low": null, "high": null,
                       "groups": [[0], [1], ...]},                (the settings as given)
       "features": {"low": [...], "high": [...], "groups": [[0], [1], ...], "size": 1584,
                    "hashed": false, "n_active": 48},             (as bound to the observations)
       "n_actions": 12, "config": {... DynaQConfig fields ...},
       "curve": {"mean_steps": [...], "experiments": 2}, "created": "...", "notes": "",
       "seconds_per_step": 0.104}                    (optional: 0.04 when absent)

- ``weights``: float64 ``(features.size, n_actions)``.

Q(s, a) is ``weights[active(s), a].sum()``, where ``active(s)`` follows the formula of
:mod:`._tiles` from the ``features`` fields alone, so numpy reads and uses a policy without
Teach Studio (``s`` is the observation, :meth:`._reach.ArmReach.observe`: the joints, and the
follow cost last for a task that follows paths)::

    f = np.load("reach.policy.npz")
    header = json.loads(str(f["header"]))
    w = f["weights"]

Readers refuse versions newer than theirs, and read through :class:`._policy.BoundedNpz` (every
member's size checked by its header before it is decompressed).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from ..._numbers import is_number
from .._config import TILE_ROLLOUT_MAX_STEPS as DEFAULT_MAX_STEPS
from .._config import TILE_ROLLOUT_SECONDS_PER_STEP as DEFAULT_SECONDS_PER_STEP
from .._config import DynaQConfig
from .._errors import LearningError, PolicyFileError
from .._tiles import TileCoder, TileCoding
from ..likeness._likeness import moving_span
from ..tabular._policy import (
    MAX_NPZ_BYTES,
    BoundedNpz,
    curve_header,
    read_curve_header,
    read_header,
)
from ..tasks._reach import ArmReach
from ._linear import LinearResult, greedy_rollout

FORMAT_NAME = "teach-studio-tile-policy"
FORMAT_VERSION = 1


@dataclass(frozen=True, eq=False)
class TilePolicyFile:
    """A tile-coded linear policy with what is needed to use and judge it.

    Attributes:
        coder: the tile coder bound to the observation box.
        weights: float ``(size, n_actions)``.
        config: the training settings.
        task: the arm task (None for another environment).
        env_id: the Gymnasium id trained on, when known.
        mean_steps: the learning curve.
        experiments: how many experiments the curve averages.
        created: ISO 8601 time of writing.
        notes: free text.
        seconds_per_step: the time one step of its rollouts takes (s): the pace of the
            demonstrations it was taught from (:func:`demonstrated_pace`), else
            :data:`DEFAULT_SECONDS_PER_STEP`.
    """

    coder: TileCoder
    weights: np.ndarray
    config: DynaQConfig
    task: ArmReach | None = None
    env_id: str | None = None
    mean_steps: np.ndarray = field(default_factory=lambda: np.zeros(0))
    experiments: int = 1
    created: str = ""
    notes: str = ""
    seconds_per_step: float = DEFAULT_SECONDS_PER_STEP

    def __post_init__(self) -> None:
        _check_pace(self.seconds_per_step, LearningError)

    @property
    def n_actions(self) -> int:
        """Actions of the environment."""
        return int(self.weights.shape[1])

    @property
    def robot(self) -> str | None:
        """The robot it was learnt on (the task's; a file written before tasks named one: the
        Puma560), or None for another environment's policy."""
        return None if self.task is None else self.task.robot

    def header(self) -> dict[str, object]:
        """The JSON header written to the file."""
        coder = self.coder
        return {
            "format": FORMAT_NAME,
            "version": FORMAT_VERSION,
            "env_id": self.env_id,
            "task": None if self.task is None else self.task.to_dict(),
            "tile_coding": coder.coding.to_dict(),
            "features": {
                "low": coder.low.tolist(),
                "high": coder.high.tolist(),
                "groups": [list(g) for g in coder.groups],
                "size": int(coder.size),
                "hashed": bool(coder.hashed),
                "n_active": int(coder.n_active),
            },
            "n_actions": self.n_actions,
            "config": self.config.to_dict(),
            "curve": curve_header(self.mean_steps, self.experiments),
            "created": self.created,
            "notes": self.notes,
            "seconds_per_step": self.seconds_per_step,
        }

    def q_values(self, obs: np.ndarray) -> np.ndarray:
        """Q(obs, .) for observations ``(..., D)``: ``(..., n_actions)``."""
        return self.weights[self.coder.active(obs)].sum(axis=-2)


def save_tile_policy(
    path: str | Path,
    result: LinearResult,
    experiment: int | None = None,
    *,
    notes: str = "",
    compress: bool = True,
    seconds_per_step: float = DEFAULT_SECONDS_PER_STEP,
) -> TilePolicyFile:
    """Write one experiment's weights of a linear run as a policy file (format above).

    Args:
        path: where to write; ``.policy.npz`` is the convention.
        result: what :func:`run_experiments` returned for a Gymnasium environment.
        experiment: which experiment's weights (default: ``result.best_experiment()``).
        notes: free text kept in the header.
        seconds_per_step: its rollouts' pace (:func:`demonstrated_pace` of the demonstrations
            it was taught from, when their times are known).
        compress: deflate the members (a training checkpoint does not: a large table is written
            in a fraction of the time, and the file reads the same).
    """
    if not isinstance(result, LinearResult):
        raise LearningError(
            f"result is a {type(result).__name__}; give the result of a tile-coded run (save tabular ones with save_policy)."
        )
    e = result.best_experiment() if experiment is None else int(experiment)
    if not 0 <= e < result.weights.shape[0]:
        raise LearningError(f"experiment is {experiment}; give 0 to {result.weights.shape[0] - 1}.")
    weights = np.ascontiguousarray(result.weights[e], dtype=np.float64)
    if not np.all(np.isfinite(weights)):
        raise LearningError(
            "The weights hold NaN or infinite values (the learning diverged); lower alpha and train again."
        )
    policy = TilePolicyFile(
        coder=result.coder,
        weights=weights,
        config=result.config,
        task=result.task,
        env_id=result.env_id,
        mean_steps=result.mean_steps(),
        experiments=int(result.steps.shape[0]),
        created=datetime.now(UTC).isoformat(timespec="seconds"),
        notes=notes,
        seconds_per_step=seconds_per_step,
    )
    with Path(path).open("wb") as stream:
        (np.savez_compressed if compress else np.savez)(
            stream, header=np.array(json.dumps(policy.header())), weights=policy.weights
        )
    return policy


def load_tile_policy(path: str | Path) -> TilePolicyFile:
    """Read a tile-coded policy file, checking its format, version, header and shapes.

    Raises:
        PolicyFileError: missing, corrupt, not a tile-coded policy, or from a newer version.
    """
    path = Path(path)
    name = path.name
    if not path.is_file():
        raise PolicyFileError(
            f"Policy file {name} does not exist; give the path of a .policy.npz file."
        )
    with BoundedNpz(path, name, MAX_NPZ_BYTES) as archive:
        header = read_policy_header(archive, name)
        coder, config, task, n_actions = _check_header(name, header)
        pace = header.get("seconds_per_step", DEFAULT_SECONDS_PER_STEP)
        _check_pace(pace, PolicyFileError, f"{name}'s seconds_per_step")
        weights = archive.read("weights", (coder.size, n_actions), "f").astype(np.float64)
    if not np.all(np.isfinite(weights)):
        raise PolicyFileError(f"{name} holds invalid weights; export the policy again.")
    try:
        mean_steps, experiments = read_curve_header(header.get("curve") or {})
    except ValueError as err:
        raise PolicyFileError(
            f"{name} has a damaged curve ({err}); export the policy again."
        ) from None
    return TilePolicyFile(
        coder=coder,
        weights=weights,
        config=config,
        task=task,
        env_id=header.get("env_id") if isinstance(header.get("env_id"), str) else None,
        mean_steps=mean_steps,
        experiments=experiments,
        created=str(header.get("created", "")),
        notes=str(header.get("notes", "")),
        seconds_per_step=float(pace),
    )


def _check_pace(value: object, error: type[Exception], label: str = "seconds_per_step") -> None:
    """Refuse a pace that is not a positive number of seconds (with ``error``)."""
    if not is_number(value) or value <= 0:
        raise error(f"{label} is {value!r}; give a positive number of seconds.")


def demonstrated_pace(task: ArmReach, motions: Sequence[tuple[np.ndarray, np.ndarray]]) -> float:
    """The time one step of ``task`` takes at the pace of the demonstrations ``motions``.

    The paper's robot learns the demonstration's execution time as well as its path. Each
    demonstration, walked in ``task`` from its first sample (:meth:`ArmReach.demonstration_actions`:
    the follow action along it, or the single steps that trace it), takes some number of steps;
    the pace is the demonstrations' total moving time over their total steps, so a rollout along
    a demonstration's route takes as long as the person moved. The moving time is the task's
    joints' :func:`._likeness.moving_span`: a cut that holds still before or after the motion
    does not slow the robot. Demonstrations that do not move or start at the goal (no step) are
    left out; with none left, :data:`DEFAULT_SECONDS_PER_STEP`.

    Args:
        task: the task the policy learns (with its followed paths, if any).
        motions: each demonstration's sample times ``(N,)`` (s) and joints ``(N, >= joints)``.

    Raises:
        LearningError: a demonstration the task cannot walk (as
            :meth:`ArmReach.demonstration_actions` says), or times that do not increase.
    """
    seconds = steps = 0.0
    for index, (times, q) in enumerate(motions):
        t = np.asarray(times, dtype=np.float64).reshape(-1)
        if t.shape[0] < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise LearningError(
                f"Demonstration {index}'s times do not increase; cut it again from its recording."
            )
        _, actions = task.demonstration_actions(q, index)
        moving = moving_span(t, np.asarray(q, dtype=np.float64)[:, : task.joints])
        if actions.size and moving > 0:
            seconds += moving
            steps += actions.size
    return seconds / steps if steps else DEFAULT_SECONDS_PER_STEP


def read_policy_header(archive: BoundedNpz, name: str) -> object:
    """The JSON header of a policy archive of any kind (:func:`._policy.read_header`), refused in
    one sentence when the archive has none."""
    if "header" not in archive.files:
        raise PolicyFileError(
            f"{name} lacks its header; it is not a Teach Studio policy file, export one again."
        )
    return read_header(archive, name)


def _check_header(name: str, header: object) -> tuple[TileCoder, DynaQConfig, ArmReach | None, int]:
    if not isinstance(header, dict) or header.get("format") != FORMAT_NAME:
        raise PolicyFileError(
            f"{name} is not a tile-coded Teach Studio policy file; export the policy again."
        )
    version = header.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise PolicyFileError(
            f"{name} has an invalid format version {version!r}; export the policy again."
        )
    if version > FORMAT_VERSION:
        raise PolicyFileError(
            f"{name} uses tile policy format version {version}, newer than this studio's {FORMAT_VERSION}; upgrade Teach Studio to read it."
        )
    try:
        coding = TileCoding.from_dict(header["tile_coding"])
        bound = header["features"]
        coder = coding.bind(bound["low"], bound["high"])
        config = DynaQConfig.from_dict(header["config"])
        task = None if header.get("task") is None else ArmReach.from_dict(header["task"])
        n_actions = header["n_actions"]
        if not isinstance(n_actions, int) or isinstance(n_actions, bool) or n_actions < 1:
            raise ValueError(f"n_actions is {n_actions!r}")
        if task is not None and n_actions != task.n_actions:
            raise ValueError(f"{n_actions} actions where the arm task has {task.n_actions}")
        if int(bound["size"]) != coder.size or bool(bound["hashed"]) != coder.hashed:
            raise ValueError("its feature table does not match its tile coding")
    except (KeyError, TypeError, ValueError, AttributeError, OverflowError, LearningError) as err:
        raise PolicyFileError(
            f"{name} has a damaged header ({err}); export the policy again."
        ) from None
    return coder, config, task, n_actions


def sample_times(duration: float, rate_hz: float) -> np.ndarray:
    """Sample times ``0, 1/rate_hz, ...`` up to ``duration``, ending exactly once at ``duration``.

    The end is appended only when it lies past the last tick by more than a rounding error
    (188 steps of 0.04 s end 1e-15 s after 376 ticks at 50 Hz: that is the same instant).
    """
    times = np.arange(int(np.floor(duration * rate_hz + 1e-9)) + 1) / rate_hz
    if duration - times[-1] > 1e-9:
        times = np.append(times, duration)
    return times


def rollout_tile_policy(
    policy: TilePolicyFile,
    start_q: np.ndarray,
    rate_hz: float,
    max_steps: int = DEFAULT_MAX_STEPS,
    *,
    seconds_per_step: float | None = None,
) -> tuple[np.ndarray, np.ndarray, bool]:
    """The greedy policy from ``start_q`` as a joint trajectory of its robot.

    Each action moves its joints by one step at constant speed over ``seconds_per_step``; the
    trajectory is sampled at ``rate_hz`` (joints beyond the task's held at the goal's values).

    Args:
        policy: a tile-coded arm policy.
        start_q: the learned joints' start angles, radians ``(joints,)``.
        rate_hz: control rate of the samples.
        max_steps: cap on greedy steps.
        seconds_per_step: duration of one step (default: the policy's own pace,
            :attr:`TilePolicyFile.seconds_per_step`).

    Returns:
        ``(times (N,), q (N, nq), reached)``: every joint of the robot (six for the Puma560).

    Raises:
        LearningError: a policy of another environment, or a bad start or rate.
    """
    times, q, reached, _ = tile_rollout(
        policy, start_q, rate_hz, max_steps, seconds_per_step=seconds_per_step
    )
    return times, q, reached


def tile_rollout(
    policy: TilePolicyFile,
    start_q: np.ndarray,
    rate_hz: float,
    max_steps: int = DEFAULT_MAX_STEPS,
    *,
    seconds_per_step: float | None = None,
) -> tuple[np.ndarray, np.ndarray, bool, np.ndarray]:
    """:func:`rollout_tile_policy`, and the greedy joint path ``(K + 1, joints)`` it samples."""
    task = policy.task
    if task is None:
        raise LearningError(
            f"This policy was trained on {policy.env_id or 'another environment'}, not the arm; only arm policies roll out to joint trajectories."
        )
    if seconds_per_step is None:
        seconds_per_step = policy.seconds_per_step
    for label, value in (("rate_hz", rate_hz), ("seconds_per_step", seconds_per_step)):
        if not isinstance(value, int | float) or not np.isfinite(value) or value <= 0:
            raise LearningError(f"{label} is {value!r}; give a positive number.")
    if not isinstance(max_steps, int) or max_steps < 0:
        raise LearningError(f"max_steps is {max_steps!r}; give a whole number >= 0.")
    start = np.asarray(start_q, dtype=np.float64).reshape(-1)
    if start.shape != (task.joints,) or not np.all(np.isfinite(start)):
        raise LearningError(
            f"The start has {start.size} angles; give {task.joints} finite joint angles in radians."
        )
    if np.any(start < task.lower) or np.any(start > task.upper):
        raise LearningError("The start lies outside the joint limits; give angles inside them.")
    path, reached = greedy_rollout(task, policy.coder, policy.weights, start, max_steps)
    times, q = path_trajectory(task, path, rate_hz, seconds_per_step)
    return times, q, reached, path


def path_trajectory(
    task: ArmReach, path: np.ndarray, rate_hz: float, seconds_per_step: float
) -> tuple[np.ndarray, np.ndarray]:
    """A greedy joint path ``(K + 1, joints)`` as the robot's trajectory: ``seconds_per_step`` a
    step, sampled at ``rate_hz``, the joints beyond the task's at its goal."""
    times = sample_times((path.shape[0] - 1) * seconds_per_step, rate_hz)
    knots = np.arange(path.shape[0]) * seconds_per_step
    q = np.tile(np.asarray(task.goal, dtype=np.float64), (times.shape[0], 1))
    for j in range(task.joints):
        q[:, j] = np.interp(times, knots, path[:, j])
    return times, q
