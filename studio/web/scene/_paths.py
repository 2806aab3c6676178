"""Tool paths drawn in the studio's scene: the part of :class:`StudioScene` that draws, lists and
removes named paths (a demonstration's, a rollout's), kept apart so the scene module stays small."""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np
import viser

from ._model import SceneLayout


class ScenePaths:
    """Named tool paths in the scene: a start ball, an end ball and a line each.

    The scene sets ``server``, ``layout``, ``_paths`` and ``_paths_lock`` and provides
    ``tool_positions``.
    """

    server: viser.ViserServer
    layout: SceneLayout
    _paths: dict[str, list[viser.SceneNodeHandle]]
    _paths_lock: threading.Lock
    tool_positions: Callable[[np.ndarray, str | None], np.ndarray]

    def show_path(self, name: str, q_robot_path: np.ndarray, robot: str | None = None) -> None:
        """Draw the tool path of ``robot``'s joint path ``(N, nq)`` (the Puma560's when None),
        replacing a path of that name."""
        tool = self.tool_positions(q_robot_path, robot)
        node = f"/paths/{name}"
        c = self.layout.colors
        s = self.server.scene
        with self._paths_lock, self.server.atomic():
            for h in self._paths.pop(name, []):
                h.remove()
            handles: list[viser.SceneNodeHandle] = [
                s.add_icosphere(
                    f"{node}/start", radius=0.02, color=c["path_start"], position=tool[0]
                ),
                s.add_icosphere(f"{node}/end", radius=0.02, color=c["path"], position=tool[-1]),
            ]
            if len(tool) >= 2:
                handles.append(
                    s.add_spline_catmull_rom(
                        f"{node}/line",
                        points=tool.astype(np.float32),
                        thickness=0.01,
                        color=c["path"],
                    )
                )
            self._paths[name] = handles

    def clear_path(self, name: str | None = None) -> None:
        """Remove the path called ``name`` (every path when None); unknown names are ignored."""
        with self._paths_lock, self.server.atomic():
            names = list(self._paths) if name is None else [name]
            for n in names:
                for h in self._paths.pop(n, []):
                    h.remove()

    def path_names(self) -> list[str]:
        """Names of the paths drawn now."""
        with self._paths_lock:
            return list(self._paths)

    def path_points(self, name: str) -> np.ndarray:
        """World points of the path line called ``name`` ((N, 3); for tests)."""
        with self._paths_lock:
            return np.asarray(self._paths[name][-1].points)
