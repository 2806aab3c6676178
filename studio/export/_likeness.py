"""Which demonstrations an exported policy is scored against, for its likeness card.

``studio export POLICY`` prints the policy's likeness card against each of them on the policy's
robot (a demonstration retargeted onto it as a training run replays it), rolled out from
that demonstration's own start (:func:`studio.learning.likeness_cards`): the one ``--demo``
names, else the run's own (kept in its ``config.json``; by name for a run recorded before the
motions were kept), else a movement primitive's own demonstration.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from studio import StudioError, read_json
from studio.capture import DEMO_SUFFIX
from studio.kinematics import DEFAULT_ROBOT
from studio.learning import AnyPolicy, DemonstrationMotion, LearningError, RunRecord, learner_of
from studio.motion import MotionError, training_demonstration

from ._errors import ExportError
from ._sources import find_source, source_kind

RUN_CONFIG = "config.json"
"""A run folder's record, beside its policy."""


def demonstration_of(
    given: str | Path, data_dir: str | Path = ".", robot: str = DEFAULT_ROBOT
) -> DemonstrationMotion:
    """The motion on ``robot`` of the demonstration ``given`` names (a path, or a name as
    :func:`find_source` looks it up): its stored Puma560 path, or for another robot its
    recording's segment retargeted onto it (:func:`studio.motion.training_demonstration`).

    Raises:
        ExportError: nothing of that name, not a demonstration, its recording missing for
            another robot, or a motion learning refuses.
    """
    path = find_source(given, data_dir)
    if source_kind(path) != "demonstration":
        raise ExportError(f"--demo names {path.name}, which is not a demonstration (*.demo.json).")
    name = path.name.removesuffix(DEMO_SUFFIX)
    label = f"The demonstration {path}"
    try:
        demo = training_demonstration(path, robot, label, name)
        times = demo.times if demo.times is not None else np.zeros(0)
        return DemonstrationMotion.checked(name, times, demo.q_robot, label)
    except (MotionError, LearningError) as err:
        raise ExportError(str(err)) from None


def likeness_motions(
    policy_path: Path,
    policy: AnyPolicy,
    demo: str | Path | None = None,
    data_dir: str | Path = ".",
) -> list[DemonstrationMotion]:
    """The demonstrations to score ``policy`` (read from ``policy_path``) against (module doc)."""
    robot = policy.robot or DEFAULT_ROBOT
    if demo is not None:
        return [demonstration_of(demo, data_dir, robot)]
    config = Path(policy_path).parent / RUN_CONFIG
    if config.is_file():
        try:
            record = RunRecord.from_dict(read_json(config))
        except (StudioError, LearningError):
            record = None  # not a run folder this studio reads: no run demonstrations
        if record is not None and record.demonstration_motions:
            return list(record.demonstration_motions)
        if record is not None and record.demonstration_names:
            return [demonstration_of(n, data_dir, robot) for n in record.demonstration_names]
    own = learner_of(policy).own_demonstration(policy)  # a movement primitive's
    return [] if own is None else [own]
