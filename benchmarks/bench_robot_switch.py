"""What a robot switch in the page waits for: the robot's model, then the meshes the scene draws.

For each robot (or those named), in one process as the studio would meet them: the time to load
its model with collision and visual geometry (``load_robot``, once per process), then to build
the drawn view from its URDF meshes (read with trimesh and simplified: the baseline), and from
the mesh cache the studio keeps under its data folder (``studio/web/_mesh_cache.py``), with the
ratio. The longest the process's other threads were held up meanwhile is printed too: Pinocchio
keeps Python's lock while it loads, so the page and the scene wait for it as well. Then the
visual geometry alone, built with Coal's default mesh loader (the baseline) and with the one
``load_robot`` uses (axis-aligned boxes: the visual meshes are never queried for distances).

Run: ``python benchmarks/bench_robot_switch.py [panda ur5 ...]`` (under a minute for all).
"""

from __future__ import annotations

import sys
import tempfile
import threading
import time
from pathlib import Path

import pinocchio as pin

from studio.kinematics import MeshConfig, load_robot, robot_names
from studio.kinematics._robots import _visual_mesh_loader, robot_spec, robots_folder
from studio.web._robot_view import arm_view


class Stall:
    """The longest gap between the ticks of a thread that sleeps 5 ms at a time."""

    def __init__(self) -> None:
        self.longest = 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._tick, daemon=True)

    def _tick(self) -> None:
        last = time.perf_counter()
        while not self._stop.is_set():
            time.sleep(0.005)
            now = time.perf_counter()
            self.longest = max(self.longest, now - last)
            last = now

    def __enter__(self) -> Stall:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()


def main(names: list[str]) -> None:
    config = MeshConfig()
    print(
        f"{'robot':8s} {'model (s)':>10s} {'held (s)':>9s} {'meshes read (s)':>16s} "
        f"{'from cache (s)':>15s} {'ratio':>7s}"
    )
    with tempfile.TemporaryDirectory() as folder:
        cache = Path(folder)
        for name in names:
            with Stall() as stall:
                t = time.perf_counter()
                arm = load_robot(name)
                model = time.perf_counter() - t
            t = time.perf_counter()
            arm_view(arm, config)  # the baseline: read and simplified
            read = time.perf_counter() - t
            arm_view(arm, config, cache)  # written to the cache
            t = time.perf_counter()
            arm_view(arm, config, cache)
            cached = time.perf_counter() - t
            print(
                f"{name:8s} {model:10.2f} {stall.longest:9.2f} {read:16.3f} {cached:15.3f} "
                f"{read / cached:6.0f}x"
            )


def visual_loaders(names: list[str]) -> None:
    print(f"\n{'robot':8s} {'visual, default (s)':>20s} {'visual, boxes (s)':>18s} {'ratio':>6s}")
    root = robots_folder()
    for name in names:
        text = (root / robot_spec(name).urdf).read_text()
        model = pin.buildModelFromXML(text)
        times = []
        for loader in (None, _visual_mesh_loader()):
            t = time.perf_counter()
            pin.buildGeomFromUrdfString(
                model, text, pin.GeometryType.VISUAL, None, [str(root.parent.parent)], loader
            )
            times.append(time.perf_counter() - t)
        print(f"{name:8s} {times[0]:20.2f} {times[1]:18.2f} {times[0] / times[1]:5.1f}x")


if __name__ == "__main__":
    chosen = sys.argv[1:] or [n for n in robot_names() if n != "puma560"]
    main(chosen)
    visual_loaders(chosen)
