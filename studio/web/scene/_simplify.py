"""A robot's meshes read and simplified in a child process (:func:`simplified_elsewhere`).

Reading and simplifying a robot's meshes holds the interpreter for seconds at a time, so the
studio does it in a child process. The child is started by ``spawn`` and imports only this module
(and what reading meshes needs), not the studio's app: the function and the values it is handed
live here, apart from the scene.
"""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np

from studio.kinematics import MeshConfig, MeshPart, robot_meshes


@dataclass(frozen=True)
class Geometry:
    """What :func:`~studio.kinematics.robot_meshes` reads of one of a URDF's visual objects,
    as plain values a child process is handed (a Pinocchio model does not cross)."""

    name: str
    meshPath: str  # noqa: N815  (Pinocchio's GeometryObject names)
    meshScale: tuple[float, ...]  # noqa: N815
    meshColor: tuple[float, ...]  # noqa: N815


@dataclass(frozen=True)
class Visuals:
    """A robot's visual objects, as :func:`~studio.kinematics.robot_meshes` reads a
    ``pinocchio.GeometryModel``."""

    geometryObjects: tuple[Geometry, ...]  # noqa: N815


def simplified(visuals: Visuals, config: MeshConfig, scale: float) -> list[MeshPart]:
    """The robot's meshes read and simplified at the size drawn."""
    return [
        MeshPart(p.name, p.frame, p.vertices * np.float32(scale), p.faces, p.rgb)
        for p in robot_meshes(visuals, config)  # type: ignore[arg-type]
    ]


def simplified_elsewhere(visuals: Visuals, config: MeshConfig, scale: float) -> list[MeshPart]:
    """:func:`simplified` in a child process: reading and simplifying a robot's meshes holds
    the interpreter for seconds at a time (a Panda: 14 s, with pauses of up to a second in the
    other threads on a busy machine), and the live scene, the fit and the page's requests must
    go on meanwhile. Only the simplified parts come back."""
    spawn = multiprocessing.get_context("spawn")  # a fork would copy the server's threads
    with ProcessPoolExecutor(max_workers=1, mp_context=spawn) as child:
        return child.submit(simplified, visuals, config, scale).result()
