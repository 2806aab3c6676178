"""A continuous-joint run from the settings a user types: one check for the page and the CLI.

The page's ``RunCreate`` and ``studio train --task arm-reach`` both describe a run of the
continuous task by the same settings (joints, step, tilings, tiles, a goal for joints 1-3 or the
first demonstration's end), with the defaults of :data:`REACH_DEFAULTS`; :func:`arm_reach_record`
checks them all and reports every bad one at once, keyed by the field the user typed.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ._config import DynaQConfig
from ._errors import ConfigError, LearningError
from ._goal import goal_problems
from ._reach import ROBOT_JOINTS, ArmReach
from ._runs import RunRecord, raise_problems, run_problems

_FEATURES = ArmReach().features()
REACH_DEFAULTS: dict[str, Any] = {
    "joints": ArmReach.joints,
    "step_deg": ArmReach.step_deg,
    "tilings": _FEATURES.tilings,
    "tiles": _FEATURES.tiles,
}
"""The continuous task's settings a user can type, and their defaults (:class:`ArmReach` and its
default :meth:`ArmReach.features`)."""


def arm_reach_record(
    config: DynaQConfig | None,
    *,
    joints: object,
    step_deg: object,
    tilings: object,
    tiles: object,
    goal_deg: Sequence[float],
    experiments: object,
    episodes: object,
    seed: object,
    demonstrations: Sequence[np.ndarray] = (),
    name: str = "",
    origin: str = "cli",
    request: dict[str, Any] | None = None,
    problems: Sequence[tuple[str, str]] = (),
) -> RunRecord:
    """A checked record of the continuous task from the user's settings.

    The goal is the first demonstration's final pose, else ``goal_deg`` for joints 1-3 with the
    wrist at zero.

    Args:
        config: the Dyna-Q settings, or None when they were bad (their ``problems`` given).
        demonstrations: Puma560 joint paths ``(N, 6)`` in radians, replayed first.
        problems: ``(field, sentence)`` found already (bad Dyna-Q settings), reported with these.

    Raises:
        ConfigError: one sentence per bad field, keyed by field (``joints``, ``step_deg``,
            ``tilings``, ``tiles``, ``goal_deg``, ``demonstrations``, the budget's).
    """
    problems = list(problems)
    paths = [np.asarray(p, dtype=np.float64) for p in demonstrations]
    goal: tuple[float, ...] | None = None
    if paths:
        goal = tuple(paths[0][-1, :ROBOT_JOINTS])
    else:
        wrong = goal_problems(goal_deg)
        problems += [("goal_deg", text) for text in wrong]
        if not wrong:
            padded = [*goal_deg, *([0.0] * (ROBOT_JOINTS - len(goal_deg)))]
            goal = tuple(np.radians(padded))
    task = coding = None
    try:
        task = ArmReach(joints=joints, step_deg=step_deg, goal=goal)  # type: ignore[arg-type]
    except LearningError as err:
        field = str(err).split(" ", 1)[0]
        problems.append((field if field in ("joints", "step_deg") else "goal_deg", str(err)))
    if task is not None:
        try:
            coding = task.features(tilings=tilings, tiles=tiles)  # type: ignore[arg-type]
        except LearningError as err:
            problems.append(("tiles" if str(err).startswith("tiles") else "tilings", str(err)))
    if task is None or coding is None or config is None:
        raise_problems(problems + run_problems(experiments, episodes, seed, name))
    assert task is not None and coding is not None and config is not None
    try:
        record = RunRecord.for_arm_reach(
            task,
            coding,
            config,
            experiments,  # type: ignore[arg-type]
            episodes,  # type: ignore[arg-type]
            seed,  # type: ignore[arg-type]
            [p[:, : task.joints] for p in paths],
            name=name,
            origin=origin,
            request=request,
        )
    except ConfigError as err:
        raise_problems(problems + list(err.by_field.items()))
        raise
    raise_problems(problems)
    return record
