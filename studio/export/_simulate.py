"""A robot's trajectory checked in physics: :func:`simulate_trajectory` replays it in MuJoCo.

The robot's MuJoCo model is built from the URDF folder ``studio export-urdf --robot NAME``
writes (:func:`~._urdf.export_urdf`: the studio's own URDF, meshes beside it), kept in the cache
folder under a name that changes with the URDF, so it is written and converted once per machine;
the compiled model is kept per robot for the process. :mod:`studio.physics` does the rest.
"""

from __future__ import annotations

import hashlib
import shutil
import tempfile
import threading
from pathlib import Path

import numpy as np

from studio.kinematics import Obstacle, RobotArm, load_robot
from studio.physics import PhysicsModel, SimulationReport, build_model, mujoco_urdf, simulate

from ._errors import ExportError
from ._urdf import export_urdf

_models: dict[tuple[str, tuple[Obstacle, ...]], PhysicsModel] = {}
_lock = threading.Lock()
_scratch: list[Path] = []


def _folder(arm: RobotArm, cache: Path | None) -> Path:
    """The robot's URDF folder in ``cache`` (a process-wide temporary folder when None)."""
    if cache is None:
        if not _scratch:
            _scratch.append(Path(tempfile.mkdtemp(prefix="studio-physics-")))
        cache = _scratch[0]
    digest = hashlib.sha256(arm.urdf_text.encode("utf-8")).hexdigest()[:12]
    folder = cache / f"{arm.name}-{digest}"
    urdf = folder / f"{arm.name}.urdf"
    if not urdf.is_file():
        if folder.exists():
            shutil.rmtree(folder, ignore_errors=True)  # not ours: export_urdf renames whole
        try:
            export_urdf(arm, folder)
        except ExportError:
            if not urdf.is_file():  # another process wrote the same folder meanwhile: fine
                raise
    return folder


def physics_model(
    robot: RobotArm | str, cache: Path | None = None, obstacles: tuple[Obstacle, ...] = ()
) -> PhysicsModel:
    """The robot's MuJoCo model with ``obstacles`` (built once per process and set of boxes;
    its files kept in ``cache``).

    Raises:
        ExportError: the URDF folder cannot be written.
        PhysicsError: MuJoCo cannot compile it.
    """
    # always the model with its collision geometry: the contacts are the studio's pairs
    arm = load_robot(robot if isinstance(robot, str) else robot.name)
    with _lock:
        key = (arm.name, tuple(obstacles))
        model = _models.get(key)
        if model is None:
            folder = _folder(arm, cache)
            urdf = mujoco_urdf(folder / f"{arm.name}.urdf", folder / "converted")
            model = build_model(arm, urdf, tuple(obstacles))
            _models[key] = model
    return model


def simulate_trajectory(
    robot: RobotArm | str,
    times: np.ndarray,
    q: np.ndarray,
    *,
    names: tuple[str, ...] | None = None,
    cache: Path | None = None,
    obstacles: tuple[Obstacle, ...] = (),
) -> SimulationReport:
    """Replay ``q`` at ``times`` in MuJoCo on ``robot`` (:func:`studio.physics.simulate`).

    Args:
        robot: the robot or its name.
        times: seconds, one per sample.
        q: radians, one row per sample.
        names: the joint names the trajectory gives, checked against the robot's (``q1`` ..
            ``qN``, a policy rollout's columns, stand for its joints in order).
        cache: the folder the robot's MuJoCo files are kept in (None: a temporary one).
        obstacles: boxes in the robot's base frame, added as fixed geoms: contacts with them are
            reported (``kind`` ``"obstacle"``).

    Raises:
        ExportError: ``names`` are not the robot's joints.
        PhysicsError: a malformed trajectory, or a model MuJoCo cannot compile.
    """
    # the joints are checked on the model without geometry: a wrong robot is refused at once
    light = load_robot(robot, geometry=False) if isinstance(robot, str) else robot
    # a policy's rollout as `studio export POLICY` alone writes it names its joints q1..qN
    positional = tuple(f"q{i + 1}" for i in range(light.nq))
    if names is not None and tuple(names) not in (light.joint_names, positional):
        raise ExportError(
            f"The trajectory's joints ({', '.join(names)}) are not the {light.spec.title}'s "
            f"({', '.join(light.joint_names)}); give the --robot it was exported for."
        )
    return simulate(physics_model(robot, cache, tuple(obstacles)), times, q)
