"""What an export starts from: a policy file, a demonstration or a recording, found by path or
name.

A recording and a demonstration become a :class:`studio.motion.Motion` of one robot's joints
through :mod:`studio.motion` (the one home of a recorded arm motion on a robot). A policy drives
the robot it was learnt on only (its file names it; one written before policies named a robot is
the Puma560's).
"""

from __future__ import annotations

from pathlib import Path

from studio._layout import POLICIES_DIR, RECORDINGS_DIR, RUNS_DIR
from studio.capture import DEMO_SUFFIX, RECORDING_SUFFIXES
from studio.kinematics import RobotArm, load_robot
from studio.learning import POLICY_SUFFIX, LearningError
from studio.learning import check_policy_robot as check_policy_robot_named
from studio.motion import SourceKind
from studio.samples import SAMPLES_DIR

from ._errors import ExportError


def source_kind(path: Path) -> SourceKind:
    """What the file at ``path`` is, by its name's ending."""
    name = path.name
    if name.endswith(POLICY_SUFFIX) or name.endswith(".npz"):
        return "policy"
    if name.endswith(DEMO_SUFFIX):
        return "demonstration"
    if any(name.endswith(suffix) for suffix in RECORDING_SUFFIXES):
        return "recording"
    raise ExportError(
        f"{path} is neither a policy ({POLICY_SUFFIX}), a demonstration ({DEMO_SUFFIX}) nor a "
        f"recording ({', '.join(RECORDING_SUFFIXES)}); give one of those."
    )


def find_source(given: str | Path, data_dir: str | Path = ".") -> Path:
    """The file ``given`` names: a path, else a name in the data folder or among the samples.

    A name is looked for as a demonstration or a recording in ``<data_dir>/recordings/``, a
    policy in ``<data_dir>/policies/`` or a run ``<data_dir>/runs/<name>/``, then as a shipped
    sample (``sample-reach-1`` is the demonstration; ``sample-reach-1.tape.csv`` the recording).

    Raises:
        ExportError: nothing of that name.
    """
    given = Path(given)
    if given.exists() or len(given.parts) != 1:
        if not given.is_file():
            what = "is a folder, not a file" if given.is_dir() else "does not exist"
            raise ExportError(
                f"{given} {what}; give the path of a policy, demonstration or recording file."
            )
        return given
    root = Path(data_dir)
    endings = (DEMO_SUFFIX, *RECORDING_SUFFIXES)
    candidates = [root / RECORDINGS_DIR / given.name, SAMPLES_DIR / given.name]
    for folder in (root / RECORDINGS_DIR, SAMPLES_DIR):
        candidates += [folder / f"{given.name}{ending}" for ending in endings]
    candidates += [
        root / POLICIES_DIR / f"{given.name}{POLICY_SUFFIX}",
        root / RUNS_DIR / given.name / f"policy{POLICY_SUFFIX}",
    ]
    for candidate in candidates:
        if candidate.is_file() and candidate.name != "__init__.py":
            return candidate
    samples = sorted(p.name.removesuffix(DEMO_SUFFIX) for p in SAMPLES_DIR.glob(f"*{DEMO_SUFFIX}"))
    raise ExportError(
        f"There is no file {given}, nor a recording, demonstration, policy or run named "
        f"{given.name!r} in {root.resolve()} or among the samples ({', '.join(samples)}); check "
        "the name or give a path."
    )


def check_policy_robot(path: Path, policy_robot: str | None, robot_name: str) -> RobotArm:
    """The robot a policy file drives, or an ExportError when another one is asked for.

    Args:
        path: the policy file (for the sentence).
        policy_robot: the robot its file names (None: not an arm's policy, refused when rolled
            out).
        robot_name: the robot asked for.
    """
    robot = load_robot(robot_name).scratch_copy()  # its own scratch data: any thread
    if policy_robot is not None:
        try:
            check_policy_robot_named(
                policy_robot,
                robot.name,
                f"The policy {path.name}",
                f"export it with --robot {policy_robot}, or export a recording or demonstration "
                f"for the {robot.spec.title}",
            )
        except LearningError as err:
            raise ExportError(str(err)) from None
    return robot
