"""The camera teacher's speed in a real browser, each figure against a baseline in the same run.

Chromium's fake camera plays a clip made here (``tests/e2e/camera_clips.py``: a drawn figure
raising and lowering its arm, so that every frame's pose differs), every frame stamped with its
index, at 30 frames/s (``--clip-fps``). Both loops wait for a new picture after each inference,
so a frame rate comes in steps of the picture interval: at 10 frames/s an inference of 400-500
ms reads as 2.0 frames/s on either side, which hides differences of up to a fifth.

1. Inference frame rate: the bare package (a minimal page that loads only the vendored
   ``@mediapipe/tasks-vision`` from the studio and runs the same camera loop with the same
   PoseLandmarker on the CPU: each frame copied into a canvas, its stamp read, the copy given to
   the model) against the studio page with the camera as its
   source (drawing, sending landmarks, the 3D scene), in alternating windows of the same run,
   for the lite and the full model. Both sides run beside the same studio server with the same
   API probe, and each opens the camera only for its own windows: they differ by the studio page
   alone. Goal: the studio slows inference by at most 10%.

   Beside the frame rates, the CPU seconds each process spends per inferred frame, from /proc
   (``process_cpu.py``): the renderer of each page (bare, studio, the scene's iframe), the GPU
   process (where SwiftShader draws every page's WebGL: the scene's, and the pose model's before
   it ran on the CPU; split by thread), the browser, its utilities and the studio server. On a shared machine this moves
   far less with other work than frames/s do.
2. Camera-to-scene latency while the studio page runs: from the picture's capture time (the
   video frame's ``captureTime``, else when the page took it) to the landmarks (the model's
   result), to the scene, and to the page hearing the answer of ``POST /api/source/landmarks``;
   p50 and p99. "Scene" is when the frame's robot pose reaches a viser client: the benchmark
   listens to the scene's websocket like the page's 3D view does, and matches each frame's
   ``q_robot`` (in the answer) to the robot pose the scene sends. Frames whose pose the scene
   never sent (superseded by a newer one before its push, or unchanged) are counted apart. The
   page hears the answer only when its main thread is free (the next inference starts right
   after a result), so without a GPU the answer comes later than the scene.
3. The API while it runs: ``GET /api/source`` and ``GET /api/runs`` latencies, p50 and p99 (goal:
   p99 < 250 ms).
4. The scene's pushes for a camera at the rate the older WebGL pose solution reached on an idle
   machine without a GPU (3.5 frames/s, lite), landmarks of a known arm motion posted straight to the studio (no
   browser, so the figure does not depend on the machine's load): how many robot poses a second
   reach a viser client. Beside it, from the studio windows: the frames the page's scene drew
   for each robot pose (the studio limits its frames while a slow stream drives it, and each is
   drawn in the browser's software-GL process).

On a 2-core machine without a GPU figures swing with other work on the machine: read the ratios
of neighbouring windows, and rerun.

Run: ``python benchmarks/bench_camera.py`` (two to five minutes on an idle machine, far longer on
a busy one; ``--models lite`` for half; needs /usr/bin/chromium).
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import sys
import tempfile
import threading
import time
import urllib.request
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from bench_web import CHROMIUM, FLAGS, http, start_studio
from process_cpu import ROLE_ORDER, ProcessCpu, frame_id, machine_busy_s, renderer_roles

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.e2e.camera_clips import COLLECT_FRAMES_JS, READ_STAMP_JS, figure_clip  # noqa: E402
from tests.page_hooks import hook  # noqa: E402

BARE_PATH = "/bench-bare-blazepose"
"""Where the browser is handed the bare page, on the studio's own origin (so the vendored files
come from the same server, as for the studio page); the studio itself never serves it."""

API_GOAL_P99_MS = 250.0
SLOWDOWN_GOAL = 0.10
IDLE_SOURCE = {"kind": "hand", "side": "right"}
"""The studio's source between its windows: the hand guide, untouched, moves nothing in the scene,
so the bare package's windows run beside a still studio page."""
WARMUP_FRAMES = 3
"""Frames dropped after each (re)start: the first inferences compile shaders and warm caches."""
ROBOT_NODE = "/robot/link6"
"""The scene node of the robot's last link: its position tells which robot pose the scene shows."""
SAME_POSITION_M = 1e-7
"""A scene position this near a frame's (the same arithmetic on the same joints) is that frame's."""

BARE_HTML = (
    """<!doctype html><html><head><meta charset="utf-8"><title>bare BlazePose</title></head>
<body><video id="v" playsinline muted style="position:absolute;width:1px;height:1px;opacity:0"></video>
<script type="module">
// The vendored package alone, with the studio page's loop: one frame at a time, a yield between,
// each frame copied into a canvas (camera.js's grab) whose stamp is read before the model sees it.
import { FilesetResolver, PoseLandmarker } from "/static/vendor/mediapipe-tasks-vision/vision_bundle.mjs";
const MODELS = { lite: "/static/vendor/pose-landmarker/pose_landmarker_lite.task",
                 full: "/static/vendor/pose-landmarker/pose_landmarker_full.task" };
const readStamp = """
    + READ_STAMP_JS
    + """;
const grabbed = document.createElement("canvas");
function grab() {
  if (grabbed.width !== video.videoWidth) grabbed.width = video.videoWidth;
  if (grabbed.height !== video.videoHeight) grabbed.height = video.videoHeight;
  grabbed.getContext("2d").drawImage(video, 0, 0);
  return grabbed;
}
window.bench = { times: [], running: false, model: null, ready: false };
const video = document.getElementById("v");
const fileset = await FilesetResolver.forVisionTasks("/static/vendor/mediapipe-tasks-vision");
let pose = null, poseTime = 0;
function nextFrame() {
  return new Promise((resolve) => {
    let done = false;
    const go = () => { if (!done) { done = true; setTimeout(resolve, 0); } };
    video.requestVideoFrameCallback(go);
    setTimeout(go, 100);
  });
}
window.setModel = async (model) => {
  if (pose) pose.close();
  pose = await PoseLandmarker.createFromOptions(fileset, {
    baseOptions: { modelAssetPath: MODELS[model], delegate: "CPU" }, runningMode: "VIDEO", numPoses: 1,
    minPoseDetectionConfidence: 0.5, minPosePresenceConfidence: 0.5, minTrackingConfidence: 0.5,
    outputSegmentationMasks: false });
  window.bench.model = model;
};
async function loop() {
  while (window.bench.running) {
    await nextFrame();
    if (!window.bench.running) break;
    if (video.readyState < 2 || !video.videoWidth) continue;
    const frame = grab();
    window.bench.tag = readStamp(frame);
    poseTime = Math.max(poseTime + 1, performance.now());
    pose.detectForVideo(frame, poseTime);
    window.bench.times.push(performance.now() / 1000);
  }
}
// The camera is open only while the page measures, as in the studio page (which opens it when
// the camera becomes the source and closes it after): neither page decodes frames while the
// other one runs.
window.benchStart = async () => {
  window.bench.times = [];
  video.srcObject = await navigator.mediaDevices.getUserMedia({ video: { width: 640, height: 480 } });
  await video.play();
  window.bench.running = true;
  loop();
};
window.benchStop = () => {
  window.bench.running = false;
  for (const track of video.srcObject ? video.srcObject.getTracks() : []) track.stop();
  video.srcObject = null;
};
await setModel("lite");
window.bench.ready = true;
</script></body></html>"""
)


def rate(times: list[float]) -> float:
    """Frames per second from result times (s), the warm-up frames left out."""
    times = times[WARMUP_FRAMES:]
    if len(times) < 2:
        return float("nan")
    return (len(times) - 1) / (times[-1] - times[0])


def pct(values: list[float], q: float) -> float:
    return float(np.percentile(values, q)) if values else float("nan")


class ApiProbe:
    """Times GET /api/source and GET /api/runs a few times a second, in a thread."""

    def __init__(self, base: str, period_s: float = 0.2) -> None:
        self.base, self.period_s = base, period_s
        self.latencies: list[float] = []  # while the studio page's camera runs
        self.side = "bare"  # which side runs now; the API's figure is the studio's
        self.on = threading.Event()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        paths = ("/api/source", "/api/runs")
        i = 0
        while not self.stop.is_set():
            if self.on.is_set():
                t0 = time.perf_counter()
                with urllib.request.urlopen(self.base + paths[i % 2], timeout=30) as r:
                    r.read()
                if self.side == "studio":
                    self.latencies.append(time.perf_counter() - t0)
                i += 1
            time.sleep(self.period_s)


class SceneWatch:
    """A viser client of the studio's scene, in a thread: when each robot pose reaches it.

    It connects to the scene's websocket as the page's 3D view does and decodes viser's wire
    format (two little-endian sizes, zstd-compressed msgpack, then binary buffers), keeping the
    arrival time (``time.time()``) of every position sent for :data:`ROBOT_NODE`.
    """

    def __init__(self, url: str) -> None:
        self.url = url.replace("http://", "ws://", 1).split("?")[0].split("#")[0]
        self.arrivals: list[tuple[float, np.ndarray]] = []
        self.batches: list[float] = []  # arrival time of every message batch
        self.connected = threading.Event()
        self.thread = threading.Thread(target=lambda: asyncio.run(self._run()), daemon=True)
        self.thread.start()
        if not self.connected.wait(60):
            raise SystemExit(f"could not connect to the scene at {self.url}")

    async def _run(self) -> None:
        import msgspec
        import viser
        import websockets
        import zstandard

        unzip = zstandard.ZstdDecompressor()
        async with websockets.connect(
            self.url, subprotocols=[f"viser-v{viser.__version__}"], max_size=None
        ) as ws:
            self.connected.set()
            try:
                async for raw in ws:
                    now = time.time()
                    self.batches.append(now)
                    size, packed = (int.from_bytes(raw[k : k + 8], "little") for k in (0, 8))
                    inner = unzip.decompress(raw[16 : 16 + packed], max_output_size=size)
                    for m in msgspec.msgpack.decode(inner)["messages"]:
                        if m.get("type") == "SetPositionMessage" and m.get("name") == ROBOT_NODE:
                            self.arrivals.append((now, np.asarray(m["position"], float)))
            except websockets.ConnectionClosed:
                pass  # the studio stopped at the end of the run

    def arrival(self, position: np.ndarray, after: float) -> float | None:
        """When ``position`` first reached the scene at or after ``after`` (None: never)."""
        for t, p in list(self.arrivals):
            if t >= after and np.max(np.abs(p - position)) <= SAME_POSITION_M:
                return t
        return None


def total(cpu: dict[str, float]) -> float:
    """The CPU seconds of every process (the GPU process's threads are already in it)."""
    return sum(cpu.get(role, 0.0) for role in ROLE_ORDER)


@dataclass
class Window:
    """One measuring window: its frame rate, and the CPU spent over its measured frames."""

    fps: float
    frames: int  # results between the two CPU snapshots (after the warm-up)
    cpu: dict[str, float]  # CPU seconds by role (process_cpu.ROLE_ORDER)
    seconds: float
    others: float  # cores the rest of the machine kept busy meanwhile


def window(
    page: Any,
    start_js: str,
    stop_js: str,
    times_js: str,
    frames: int,
    timeout_s: float,
    cpu: ProcessCpu,
) -> Window:
    """Run one measuring window of ``frames`` results after the warm-up.

    CPU is counted from the warm-up's last result to the window's last, and divided by the
    results in between.
    """
    page.evaluate(start_js)
    count = f"() => ({times_js}).length"
    page.wait_for_function(f"{count} >= {WARMUP_FRAMES}", timeout=timeout_s * 1000)
    n0, c0, b0, t0 = page.evaluate(count), cpu.snapshot(), machine_busy_s(), time.perf_counter()
    page.wait_for_function(f"{count} >= {n0 + frames}", timeout=timeout_s * 1000)
    n1, c1, b1, t1 = page.evaluate(count), cpu.snapshot(), machine_busy_s(), time.perf_counter()
    times = page.evaluate(f"() => ({times_js}).slice()")
    page.evaluate(stop_js)
    spent = ProcessCpu.spent(c0, c1)
    others = max(0.0, (b1 - b0) - total(spent)) / (t1 - t0)
    return Window(rate(times), n1 - n0, spent, t1 - t0, others)


def scene_latencies(
    frames: list[dict[str, Any]], origin_s: float, scene: SceneWatch
) -> tuple[list[float], int]:
    """Capture-to-scene latencies (ms) of the answered frames, and how many never reached it."""
    from studio.kinematics import Puma560

    robot = Puma560()
    out, missed = [], 0
    for f in frames:
        q = (f.get("answer") or {}).get("q_robot")
        if q is None:
            continue
        position = robot.joint_frames(np.asarray(q, float))[6][:3, 3]
        arrived = scene.arrival(position, after=origin_s + f["tResult"])
        if arrived is None:
            missed += 1
        else:
            out.append((arrived - origin_s - f["body"]["t"]) * 1000)
    return out, missed


FED_RATE_HZ = 3.5
"""The lite model's rate in a bare page on an idle 2-core machine with software WebGL, when it ran
there (``@mediapipe/pose``; on the CPU it keeps up with the camera)."""


def fed_scene_rate(base: str, scene: SceneWatch, seconds: float) -> tuple[float, float]:
    """Post landmarks at :data:`FED_RATE_HZ` for ``seconds``; (frames, scene pushes) per second."""
    from studio.kinematics import HumanArm, arm_motion, landmarks_from_arm

    arm = HumanArm("right")
    http("PUT", base + "/api/source", {"kind": "camera", "side": "right"})
    time.sleep(1.0)  # the previous source's last pushes (the simulator streams at start)
    before, sent = len(scene.arrivals), 0
    t0 = due = time.perf_counter()
    while (elapsed := time.perf_counter() - t0) < seconds:
        world, image = landmarks_from_arm(arm_motion(elapsed, arm), arm)
        body = {"t": elapsed, "world": world.tolist(), "image": image.tolist()}
        http("POST", base + "/api/source/landmarks", {**body, "width": 640, "height": 480})
        sent += 1
        # The next frame a period later, never sooner: a late one is not caught up in a burst
        # (the page sends the newest frame only).
        due = max(due + 1 / FED_RATE_HZ, time.perf_counter())
        time.sleep(max(0.0, due - time.perf_counter()))
    took = time.perf_counter() - t0
    time.sleep(1.5)  # the last pose's push
    http("PUT", base + "/api/source", IDLE_SOURCE)
    return sent / took, (len(scene.arrivals) - before) / took


def bare_window(bare: Any, frames: int, timeout_s: float, cpu: ProcessCpu) -> Window:
    return window(
        bare,
        "() => window.benchStart()",
        "() => window.benchStop()",
        "window.bench.times",
        frames,
        timeout_s,
        cpu,
    )


def scene_frame(page: Any) -> Any:
    """The studio page's scene iframe (viser's page)."""
    return page.frame(url=lambda url: url.startswith(page.get_attribute("#scene", "src")))


def scene_frames_drawn(page: Any) -> int:
    """Frames the studio page's scene iframe has drawn so far (the studio's frame pacing counts
    them, ``studio/web/scene/_frames.py``; 0 before any pacing)."""
    return int(scene_frame(page).evaluate("() => window.__studioFramePacing?.frames ?? 0"))


def page_frames(bare: Any, page: Any) -> dict[str, str]:
    """``{DevTools frame id: role}`` of the bare page, the studio page and its scene iframe."""
    return {
        frame_id(bare.context, bare): "renderer: bare page",
        frame_id(page.context, page): "renderer: studio page",
        frame_id(page.context, scene_frame(page)): "renderer: scene",
    }


def print_rates(results: dict[str, dict[str, list[Window]]]) -> None:
    print("\nInference frame rate (alternating windows of the same run; a busy machine swings):")
    for model, sides in results.items():
        bare = [w.fps for w in sides["bare"]]
        studio = [w.fps for w in sides["studio"]]
        b, s = statistics.median(bare), statistics.median(studio)
        slowdown = 1 - s / b
        verdict = "meets" if slowdown <= SLOWDOWN_GOAL else "misses"
        ratios = [st / ba for ba, st in zip(bare, studio, strict=True)]
        print(
            f"  {model}: bare package {b:.2f} frames/s, studio page {s:.2f} frames/s: "
            f"the studio slows inference by {slowdown:+.0%} ({verdict} the goal <= {SLOWDOWN_GOAL:.0%}); "
            f"studio/bare per pair {', '.join(f'{r:.2f}' for r in ratios)}"
        )
    if "lite" in results and "full" in results:
        lite = statistics.median(w.fps for w in results["lite"]["studio"])
        full = statistics.median(w.fps for w in results["full"]["studio"])
        print(f"  lite / full in the studio page: {lite / full:.2f}x")


def print_cpu(results: dict[str, dict[str, list[Window]]]) -> None:
    """CPU seconds per measured frame by process, bare against studio (sums over the windows)."""
    print("\nCPU seconds per inferred frame, by process (all windows' CPU / all their frames):")
    for model, sides in results.items():
        per = {}
        for side, windows in sides.items():
            frames = sum(w.frames for w in windows)
            per[side] = {r: sum(w.cpu.get(r, 0.0) for w in windows) / frames for r in ROLE_ORDER}
        print(f"  {model:26s} {'bare':>7s} {'studio':>7s} {'studio-bare':>11s}")
        for role in ROLE_ORDER:
            b, s = per["bare"][role], per["studio"][role]
            print(f"    {role:24s} {b:7.3f} {s:7.3f} {s - b:+11.3f}")
        b, s = sum(per["bare"].values()), sum(per["studio"].values())
        print(f"    {'total':24s} {b:7.3f} {s:7.3f} {s - b:+11.3f}   studio/bare {s / b:.2f}")
        gpu = {
            role
            for ws in sides.values()
            for w in ws
            for role, t in w.cpu.items()
            if role.startswith("GPU: ") and t > 0.01 * w.frames
        }
        for role in sorted(gpu):
            b, s = (
                sum(w.cpu.get(role, 0.0) for w in ws) / sum(w.frames for w in ws)
                for ws in (sides["bare"], sides["studio"])
            )
            print(f"      {role:22s} {b:7.3f} {s:7.3f} {s - b:+11.3f}")
        pairs = [
            (total(st.cpu) / st.frames) / (total(ba.cpu) / ba.frames)
            for ba, st in zip(sides["bare"], sides["studio"], strict=True)
        ]
        others = [w.others for ws in sides.values() for w in ws]
        print(
            f"    total CPU per frame, studio/bare per pair: {', '.join(f'{r:.2f}' for r in pairs)}"
            f"; other work on the machine {min(others):.1f}-{max(others):.1f} cores"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=15, help="frames per measuring window")
    parser.add_argument("--pairs", type=int, default=2, help="bare/studio window pairs per model")
    parser.add_argument("--models", default="lite,full", help="models to time, comma-separated")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds a window may take")
    parser.add_argument("--fed", type=float, default=20.0, help="seconds of posted landmarks")
    parser.add_argument("--clip-fps", type=int, default=30, help="the fake camera's frame rate")
    args = parser.parse_args()

    from playwright.sync_api import sync_playwright

    tmp = Path(tempfile.mkdtemp(prefix="bench-camera-"))
    # a camera at --clip-fps: the loop waits for a new picture after each inference, so the
    # frame rates come in steps of the picture interval (at 10 frames/s, 2.0 then 2.5 frames/s)
    clip = figure_clip(tmp / "figure.y4m", frames=12 * args.clip_fps, fps=args.clip_fps)
    (tmp / "data").mkdir()
    studio, base = start_studio(tmp / "data")
    probe = ApiProbe(base)
    scene = SceneWatch(http("GET", base + "/api/config")["viser_url"])
    cpu = ProcessCpu(studio.pid)
    flags = [
        *FLAGS,
        "--use-fake-ui-for-media-stream",
        "--use-fake-device-for-media-stream",
        f"--use-file-for-fake-video-capture={clip}",
    ]
    fed = fed_scene_rate(base, scene, args.fed)
    results: dict[str, dict[str, list[Window]]] = {}
    latency: dict[str, list[float]] = {"landmarks": [], "scene": [], "answer": []}
    missed = 0
    scene_drawn = [0, 0]  # the scene's frames drawn and its poses, over the studio windows
    idle: list[tuple[float, float]] = []  # (start, end) of the bare windows: the studio is still
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=flags, headless=True)
            bare = browser.new_page()
            bare.route(
                base + BARE_PATH,
                lambda route: route.fulfill(body=BARE_HTML, content_type="text/html"),
            )
            bare.goto(base + BARE_PATH)
            bare.wait_for_function(
                "() => window.bench && window.bench.ready", timeout=args.timeout * 1000
            )
            page = browser.new_page(viewport={"width": 1440, "height": 900})
            page.goto(base + "/")
            page.wait_for_selector("body[data-ready='1']", timeout=120_000)
            page.evaluate(COLLECT_FRAMES_JS)
            # the bare page idles with its camera closed: a timer shows whose renderer it is
            bare.evaluate("() => { window.tick = setInterval(() => {}, 50); }")
            cpu.renderers = renderer_roles(browser, page_frames(bare, page))
            bare.evaluate("() => clearInterval(window.tick)")
            origin_s = page.evaluate("() => performance.timeOrigin") / 1000
            page.select_option("[data-testid='source-kind']", "camera")  # shows its controls
            http("PUT", base + "/api/source", IDLE_SOURCE)
            probe.on.set()  # the API is probed beside both sides alike
            for model in [m for m in args.models.split(",") if m]:
                results[model] = {"bare": [], "studio": []}
                bare.evaluate(f"() => setModel('{model}')")
                page.select_option("[data-testid='camera-model']", model)
                for pair in range(args.pairs):
                    order = ("bare", "studio") if pair % 2 == 0 else ("studio", "bare")
                    for side in order:
                        probe.side = side
                        if side == "bare":
                            t0 = time.time()
                            w = bare_window(bare, args.frames, args.timeout, cpu)
                            idle.append((t0, time.time()))
                        else:
                            page.evaluate("() => { window.__frames = []; }")
                            drawn, poses = scene_frames_drawn(page), len(scene.arrivals)
                            http("PUT", base + "/api/source", {"kind": "camera", "side": "right"})
                            w = window(
                                page,
                                "() => {}",
                                "() => {}",
                                "window.__frames.map((f) => f.tResult)",
                                args.frames,
                                args.timeout,
                                cpu,
                            )
                            http("PUT", base + "/api/source", IDLE_SOURCE)
                            scene_drawn[0] += scene_frames_drawn(page) - drawn
                            scene_drawn[1] += len(scene.arrivals) - poses
                            frames = page.evaluate("() => window.__frames")[WARMUP_FRAMES:]
                            latency["landmarks"] += [
                                (f["tResult"] - f["body"]["t"]) * 1000 for f in frames
                            ]
                            latency["answer"] += [
                                (f["tAnswered"] - f["body"]["t"]) * 1000
                                for f in frames
                                if f["answer"]
                            ]
                            to_scene, lost = scene_latencies(frames, origin_s, scene)
                            latency["scene"] += to_scene
                            missed += lost
                            page.wait_for_function("p => !p.S.camera.running", arg=hook(page))
                        results[model][side].append(w)
                        print(
                            f"{model:4s} {side:6s} {w.fps:5.2f} frames/s, "
                            f"{total(w.cpu) / w.frames:.2f} CPU s/frame "
                            f"(others on the machine: {w.others:.1f} cores)",
                            flush=True,
                        )
            browser.close()
    finally:
        probe.stop.set()
        studio.terminate()
        studio.wait(timeout=10)

    print_rates(results)
    print_cpu(results)
    print("\nCamera-to-scene latency while the studio page runs (ms, from the picture's capture):")
    names = {
        "landmarks": "landmarks (the model's result)",
        "scene": "scene (the robot pose reaches a viser client)",
        "answer": "the page hears the studio's answer (late when inference runs)",
    }
    for name, values in latency.items():
        print(
            f"  p50 {pct(values, 50):7.0f}   p99 {pct(values, 99):7.0f}   (n={len(values):3d})  {names[name]}"
        )
    print(f"  frames whose pose the scene never sent (superseded or unchanged): {missed}")
    idle_s = sum(b - a for a, b in idle)
    idle_n = sum(a <= t <= b for t in scene.batches for a, b in idle)
    print(
        f"  the still studio sent its scene {idle_n} message batches in {idle_s:.0f} s "
        "(the bare windows; viser's page itself redraws once a second when idle)"
    )
    print(
        f"\nScene pushes for a camera at {fed[0]:.1f} frames/s (landmarks posted, no browser): "
        f"{fed[1]:.1f} robot poses/s reach the scene"
    )
    frames, poses = scene_drawn
    print(
        f"The scene in the studio windows: {frames} frames drawn for {poses} robot poses, "
        f"{frames / max(poses, 1):.2f} a pose"
    )
    api_ms = [v * 1000 for v in probe.latencies]
    p99 = pct(api_ms, 99)
    print(
        f"\nAPI while the camera runs: p50 {pct(api_ms, 50):.0f} ms, p99 {p99:.0f} ms over "
        f"{len(api_ms)} requests ({'meets' if p99 < API_GOAL_P99_MS else 'misses'} p99 < {API_GOAL_P99_MS:.0f} ms)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
