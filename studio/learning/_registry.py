"""The learners, registered by kind: the one dispatch from a kind, a policy or a task to the
:class:`._interface.Learner` that handles it.

Nothing outside this package asks which class a policy is: it asks :func:`learner_of` for the
policy's learner and calls that. A new learner (a baseline) registers itself here with
:func:`register_learner` and is then listed, rolled out, scored and exported like the others.
"""

from __future__ import annotations

from pathlib import Path

from ._config import OWN_LEARNER as OWN_LEARNER
from ._errors import LearningError, PolicyFileError
from ._interface import Learner
from .baselines._learner import CloningLearner, TeacherLearner
from .baselines._policy import CloningPolicyFile, TeacherPolicyFile
from .linear._learner import TileLearner
from .linear._policy import TilePolicyFile, read_policy_header
from .primitives._learner import DmpLearner
from .primitives._policy import DmpPolicyFile
from .tabular._learner import TabularLearner
from .tabular._policy import MAX_NPZ_BYTES, BoundedNpz, PolicyFile
from .tasks._arm import ArmGrid
from .tasks._reach import ArmReach

AnyPolicy = PolicyFile | TilePolicyFile | DmpPolicyFile | TeacherPolicyFile | CloningPolicyFile
"""A policy of any kind registered here, as :func:`load_any_policy` returns it."""

_LEARNERS: dict[str, Learner] = {}
_TASKS: dict[str, type] = {}


def register_learner(learner: Learner, task_type: type | None = None) -> None:
    """Register ``learner`` under its kind; with ``task_type``, as the learner of that task
    (a run's record holds such a task; :func:`learner_for_task`)."""
    if learner.kind in _LEARNERS:
        raise LearningError(f"A learner of kind {learner.kind!r} is registered already.")
    _LEARNERS[learner.kind] = learner
    if task_type is not None:
        _TASKS[learner.kind] = task_type


def learner(kind: str) -> Learner:
    """The learner registered as ``kind`` (``"arm-grid"``, ``"arm-reach"``, ``"dmp"``)."""
    try:
        return _LEARNERS[kind]
    except KeyError:
        raise LearningError(
            f"There is no learner of kind {kind!r}; give one of {', '.join(_LEARNERS)}."
        ) from None


def learner_kinds() -> tuple[str, ...]:
    """The kinds registered, in the order they were."""
    return tuple(_LEARNERS)


def learner_of(policy: object) -> Learner:
    """The learner whose policy ``policy`` is (as :func:`load_any_policy` returns them)."""
    for each in _LEARNERS.values():
        if isinstance(policy, each.policy_type):
            return each
    raise LearningError(
        f"A {type(policy).__name__} is no policy of a registered learner; load it with load_any_policy."
    )


def learner_for_task(task: object) -> Learner:
    """The learner of a run's task (an :class:`ArmGrid`: tabular; an :class:`ArmReach`: tile
    coding)."""
    for kind, task_type in _TASKS.items():
        if isinstance(task, task_type):
            return _LEARNERS[kind]
    raise LearningError(
        f"No learner learns a {type(task).__name__}; give an ArmGrid or an ArmReach."
    )


def run_learner(kind: str, task: object) -> Learner:
    """The learner a run of ``task`` trains with: its task's own (``kind`` "" or
    :data:`OWN_LEARNER`), or the registered learner ``kind`` that trains such a task (its
    ``trains``: the baselines train the continuous task)."""
    if kind in ("", OWN_LEARNER):
        return learner_for_task(task)
    chosen = _LEARNERS.get(kind)
    trains = getattr(chosen, "trains", None)
    if chosen is None or trains is None or not isinstance(task, trains):
        able = [OWN_LEARNER] + [
            k
            for k, each in _LEARNERS.items()
            if k not in _TASKS and each.trains and isinstance(task, each.trains)
        ]
        raise LearningError(
            f"learner is {kind!r}; give one of {', '.join(able)} for a run of the {type(task).__name__} task."
        )
    return chosen


def load_any_policy(path: str | Path) -> AnyPolicy:
    """Read a policy file of any registered kind: tabular (:func:`load_policy`), tile-coded, or a
    movement primitive (:func:`load_dmp_policy`), by the ``format`` of its header.

    Raises:
        PolicyFileError: missing, corrupt, of no registered format, or as its reader says.
    """
    path = Path(path)
    if not path.is_file():
        raise PolicyFileError(
            f"Policy file {path.name} does not exist; give the path of a .policy.npz file."
        )
    with BoundedNpz(path, path.name, MAX_NPZ_BYTES) as archive:
        header = read_policy_header(archive, path.name)
    kind = header.get("format") if isinstance(header, dict) else None
    for each in _LEARNERS.values():
        if kind == each.format:
            return each.load(path)  # type: ignore[return-value]
    raise PolicyFileError(
        f"{path.name} is not a Teach Studio policy file; export the policy again."
    )


register_learner(TabularLearner(), ArmGrid)
register_learner(TileLearner(), ArmReach)
register_learner(DmpLearner())
register_learner(TeacherLearner())
register_learner(CloningLearner())
