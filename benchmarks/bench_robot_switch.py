"""What a robot switch in the page waits for, and whether the API keeps answering meanwhile.

1. For each robot (or those named), in one process as the studio would meet them: the time to
   load its model with collision and visual geometry (``load_robot``, once per process, here in
   this process), then to build the drawn view from its URDF meshes (read with trimesh and
   simplified: the baseline), and from the mesh cache the studio keeps under its data folder
   (``studio/web/scene/_mesh_cache.py``), with the ratio. The longest the process's other threads were
   held up meanwhile is printed too: Pinocchio keeps Python's lock while it loads.
2. The visual geometry alone, built with Coal's default mesh loader (the baseline) and with the
   one ``load_robot`` uses (axis-aligned boxes: the visual meshes are never queried).
3. The API during a switch: a real studio (API, scene, the simulator at 110 Hz) in a child
   process, a client polling ``GET /api/config`` while ``PUT /api/robot`` switches to each robot
   in turn, its first load in that studio, with the drawn meshes already in the data folder's
   cache. Twice in the same run: the robot's geometry built in the studio's own process (the
   baseline, as before ``isolate_robot_loading``) and in a child process (what ``studio serve``
   does), and then in a second studio on the same data folder, which reads the geometry the
   first kept in its cache (``cache/robots/``); for each, the switch's duration and the polls'
   median, p99 and longest latency, the ratio of the longest, and how much faster a switch is
   from the cache than in the studio's own process.

Run: ``python benchmarks/bench_robot_switch.py [panda ur5 ...]`` (about two minutes for all;
``--api-only`` runs part 3 alone, on kinova, z1 and panda unless robots are named).
"""

from __future__ import annotations

import http.client
import shutil
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).parent))

from bench_api_load import Studio  # noqa: E402

from studio.kinematics import MeshConfig, load_robot, robot_names  # noqa: E402
from studio.kinematics._robot_load import _visual_mesh_loader  # noqa: E402
from studio.kinematics._robots import robot_spec, robots_folder  # noqa: E402
from studio.web import Settings  # noqa: E402
from studio.web.scene._robot_view import arm_view  # noqa: E402

SWITCH_SERVER = """
import json, sys
from pathlib import Path
a = json.loads(sys.argv[1])
if not a["isolate"]:  # the baseline: every robot's geometry built in the studio's own process
    import studio.kinematics
    studio.kinematics.isolate_robot_loading = lambda cache=None: None
import studio.web._serve as served
served.prepare_in_background = lambda: None
from studio.web import Settings, serve
serve(Settings(data_dir=Path(a["data"]), port=a["port"], viser_port=a["viser_port"],
               source="simulator"), open_browser=False)
"""
QUIET_S = 0.5
"""The client polls this long before each switch and after it returns."""


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


def poll_during(studio: Studio, switch_to: str) -> tuple[float, np.ndarray]:
    """Switch the studio to ``switch_to`` while a client polls ``GET /api/config``; the switch's
    seconds and every poll's latency (s) from :data:`QUIET_S` before it to as long after."""
    latencies: list[float] = []
    stop = threading.Event()

    def client() -> None:
        conn = http.client.HTTPConnection("127.0.0.1", studio.port, timeout=60)
        while not stop.is_set():
            t0 = time.perf_counter()
            conn.request("GET", "/api/config")
            conn.getresponse().read()
            latencies.append(time.perf_counter() - t0)
        conn.close()

    thread = threading.Thread(target=client)
    thread.start()
    time.sleep(QUIET_S)
    t0 = time.perf_counter()
    studio.call("PUT", "/api/robot", {"name": switch_to})
    switch = time.perf_counter() - t0
    time.sleep(QUIET_S)
    stop.set()
    thread.join()
    return switch, np.array(latencies)


def api_latency(names: list[str]) -> None:
    print("\nThe API while the page switches robots (first load of each in the studio):")
    print(f"{'robot':8s} {'geometry built in':18s} {'switch (s)':>10s} {'p50 (ms)':>9s} "
          f"{'p99 (ms)':>9s} {'longest (ms)':>13s}")  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="bench-switch-") as folder:
        warm = Path(folder) / "warm"
        cache = Settings(data_dir=warm).mesh_cache_dir
        cache.mkdir(parents=True)
        for name in names:  # the drawn meshes cached, as after a first switch ever
            arm_view(load_robot(name), MeshConfig(), cache)
        longest: dict[tuple[str, str], float] = {}
        switches: dict[tuple[str, str], float] = {}
        # the studio's own process (the baseline); a child process, the first time on this
        # machine; and a later studio on the same data folder, the geometry kept in its cache
        for where, isolate, fresh in (
            ("the studio (before)", False, True),
            ("a child process", True, True),
            ("the cache (later)", True, False),
        ):
            data = Path(folder) / f"isolate-{isolate}"
            if fresh:
                shutil.copytree(warm, data)
            studio = Studio(0, data, background_prepare=False, code=SWITCH_SERVER, isolate=isolate)
            try:
                for name in names:
                    switch, lat = poll_during(studio, name)
                    longest[name, where] = float(lat.max())
                    switches[name, where] = switch
                    print(f"{name:8s} {where:18s} {switch:10.2f} "
                          f"{np.percentile(lat, 50) * 1e3:9.1f} {np.percentile(lat, 99) * 1e3:9.1f} "
                          f"{lat.max() * 1e3:13.1f}")  # fmt: skip
            finally:
                studio.stop()
    for name in names:
        ratio = longest[name, "the studio (before)"] / longest[name, "a child process"]
        faster = switches[name, "the studio (before)"] / switches[name, "the cache (later)"]
        print(f"{name:8s} longest API latency, before / child: {ratio:.1f}x; "
              f"switch, before / from the cache: {faster:.1f}x")  # fmt: skip


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--api-only"]
    if "--api-only" in sys.argv:
        api_latency(args or ["kinova", "z1", "panda"])
    else:
        chosen = args or [n for n in robot_names() if n != "puma560"]
        main(chosen)
        visual_loaders(chosen)
        api_latency(chosen)
