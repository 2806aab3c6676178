"""Camera presets of the scene (front, top, side) and following the robot's tool.

Pure geometry from the scene's layout (:class:`~._scene_model.SceneLayout`): each preset looks at
the layout's target (between the robot and the operator) from the default camera's distance, so
both bodies stay in the picture. The scene (:mod:`._scene`) applies a view to every connected
browser; following the tool moves the target onto the tool and keeps the camera's offset from it,
so an orbit the user made is kept while the camera follows.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import viser

from ._model import SceneLayout

VIEW_NAMES = ("front", "top", "side")
"""The camera presets, in the order the page offers them."""
TOP_TILT = 1e-3
"""A top view looks down almost straight: exactly along the up axis, a Z-up orbit has no
heading, so the camera stands this far (m per m of height) towards the front."""


@dataclass(frozen=True)
class CameraView:
    """Where a camera stands and what it looks at (world frame, m, Z up)."""

    position: tuple[float, float, float]
    look_at: tuple[float, float, float]


def camera_view(name: str, layout: SceneLayout) -> CameraView:
    """The preset ``name`` of :data:`VIEW_NAMES` for ``layout``.

    - ``front``: the audience's view of the pair, from -Y (the robot on the left, the operator
      on the right, both in profile), level with the target.
    - ``top``: from straight above, the robot's forward axis (+X) to the right.
    - ``side``: along the robot's forward axis (+X), from behind the robot towards the operator.

    Raises:
        KeyError: ``name`` is not a preset (the API checks the name first).
    """
    target = np.asarray(layout.camera_look_at, dtype=float)
    distance = float(np.linalg.norm(np.asarray(layout.camera_position, dtype=float) - target))
    direction = {
        "front": np.array([0.0, -1.0, 0.0]),
        "top": np.array([0.0, -TOP_TILT, 1.0]),
        "side": np.array([-1.0, 0.0, 0.0]),
    }[name]
    position = target + distance * direction / np.linalg.norm(direction)
    return CameraView(_triple(position), _triple(target))


def following(position: np.ndarray, look_at: np.ndarray, tool: np.ndarray) -> CameraView:
    """A camera at ``position`` looking at ``look_at``, moved so that it looks at ``tool`` from
    the same offset."""
    offset = np.asarray(position, dtype=float) - np.asarray(look_at, dtype=float)
    tool = np.asarray(tool, dtype=float)
    return CameraView(_triple(tool + offset), _triple(tool))


def _triple(v: np.ndarray) -> tuple[float, float, float]:
    return float(v[0]), float(v[1]), float(v[2])


def apply_view(clients: Iterable[viser.ClientHandle], view: CameraView) -> None:
    """Put each browser's camera at ``view`` (Z up), each in one message."""
    for c in clients:
        with c.atomic():
            c.camera.up_direction = (0.0, 0.0, 1.0)
            c.camera.position = view.position
            c.camera.look_at = view.look_at


def follow_tool(clients: Iterable[viser.ClientHandle], tool: np.ndarray) -> None:
    """Turn each browser's camera onto ``tool`` (world, m), keeping its offset (:func:`following`)."""
    for c in clients:
        apply_view([c], following(c.camera.position, c.camera.look_at, tool))


def shown_views(clients: Iterable[viser.ClientHandle]) -> list[CameraView]:
    """Where each browser's camera stands and looks, as it last reported."""
    return [
        CameraView(_triple(np.asarray(c.camera.position)), _triple(np.asarray(c.camera.look_at)))
        for c in clients
    ]


class SceneCamera:
    """The cameras of every browser connected to a viser server: presets and following the tool.

    Args:
        server: the scene's viser server.
        layout: gives the presets' target and distance.
    """

    def __init__(self, server: viser.ViserServer, layout: SceneLayout) -> None:
        self.server = server
        self.layout = layout
        self.following = False

    def show(self, name: str) -> None:
        """Put every browser's camera on the preset ``name`` (:data:`VIEW_NAMES`)."""
        apply_view(self.server.get_clients().values(), camera_view(name, self.layout))

    def follow(self, tool: np.ndarray) -> None:
        """Turn every browser's camera onto the tool at ``tool`` (world, m)."""
        follow_tool(self.server.get_clients().values(), tool)

    def views(self) -> list[CameraView]:
        """Each connected browser's camera, as it last reported it."""
        return shown_views(self.server.get_clients().values())
