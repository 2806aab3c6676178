"""Does training starve the studio? The API under load, with and without a heavy training run.

A real studio (``studio.web.serve``: API, scene, the simulator at 110 Hz) runs in a child process
on loopback, with a capture recording every frame. Twenty client threads then poll the API
(the page's GETs: source, capture, runs, lists, config) for a fixed time, twice in the same
run: without training (the baseline), then while a heavy run trains (full planning, 20
experiments, on every core). For each window it prints requests per second, p50/p99/max
latency, and the frames the pipeline dropped or the capture missed; and the ratio of the p99s.

The studio's answer to "training must not starve the studio" is priority: the training threads
run at a lower CPU priority (``TRAINING_NICENESS``), so the API, the pipeline and the scene get
the cores first. ``--niceness 0`` starts the studio without it, to see the difference.

Run: ``python benchmarks/bench_api_load.py`` (about 50 s; ``--seconds`` per window, ``--rounds``).
``--heavy`` measures issue 18's load instead: 15 s windows while a 100 x 20,000-episode run with
full planning trains, a page's live stream open and the clients polling the run's curve too,
each round's baseline measured right after the run is stopped (its finished curve polled).
"""

from __future__ import annotations

import argparse
import http.client
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from studio.web.services._runs import TRAINING_NICENESS

CLIENTS = 20
PATHS = (
    "/api/source",
    "/api/capture",
    "/api/runs",
    "/api/recordings",
    "/api/config",
    "/api/demonstrations",
    "/api/policies",
)
HEAVY_RUN = {"planning": "full", "experiments": 20, "episodes": 3000, "seed": 1}
"""Far more work than a window lasts: it trains on every core until it is stopped."""
ISSUE_RUN = {
    "planning": "full",
    "planning_steps": 3000,
    "experiments": 100,
    "episodes": 20_000,
    "seed": 1,
}
"""``--heavy``: the largest run the studio accepts (100 x 20,000 episodes, full planning with
3,000 planning updates per step), the run issue 18 measured the API under. Its 2,000,000-cell
curve is what the page's live stream, the run list and the curve endpoint read while it trains."""
CURVE_PATH = "/api/runs/{run}/curve"
"""``--heavy`` adds the run's curve to what the clients poll (the page loads it for each shown run)."""
START_TIMEOUT_S = 120.0
GOAL_P99_MS = 250.0

SERVER = """
import json, sys
from pathlib import Path
import studio.web.services._runs as runs
from studio.web import Settings, serve
import studio.web._serve as served
a = json.loads(sys.argv[1])
runs.RunQueue.niceness = a["niceness"]
if not a["background_prepare"]:
    served.prepare_in_background = lambda: None
serve(Settings(data_dir=Path(a["data"]), port=a["port"], viser_port=a["viser_port"],
               source="simulator"), open_browser=False)
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Studio:
    """A studio in a child process on loopback, and a small JSON client for it."""

    def __init__(
        self,
        niceness: int,
        data: Path,
        background_prepare: bool = True,
        code: str = SERVER,
        **extra: object,
    ) -> None:
        """Start ``code`` (default :data:`SERVER`) with its arguments, and ``extra`` ones."""
        self.port = free_port()
        args = {"niceness": niceness, "data": str(data), "port": self.port, **extra}
        args["background_prepare"] = background_prepare
        args["viser_port"] = free_port()
        self.process = subprocess.Popen(
            [sys.executable, "-c", code, json.dumps(args)],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        deadline = time.monotonic() + START_TIMEOUT_S
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"the studio did not start: {self.process.stderr.read()}")
            try:
                self.call("GET", "/api/config")
                return
            except OSError:
                time.sleep(0.2)
        self.stop()
        raise RuntimeError("the studio did not answer within the start timeout")

    def call(self, method: str, path: str, body: dict | None = None) -> dict | list | None:
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=30)
        try:
            data = json.dumps(body).encode() if body is not None else None
            headers = {"Content-Type": "application/json"} if data else {}
            conn.request(method, path, body=data, headers=headers)
            response = conn.getresponse()
            text = response.read()
            if response.status >= 400:
                raise RuntimeError(f"{method} {path}: {response.status} {text[:200]!r}")
            return json.loads(text) if text else None
        finally:
            conn.close()

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


def load(
    port: int, seconds: float, paths_polled: tuple[str, ...] = PATHS
) -> tuple[np.ndarray, np.ndarray]:
    """``CLIENTS`` threads polling the API for ``seconds``; every request's latency (s) and
    the index of its path in ``paths_polled``."""
    latencies: list[list[float]] = [[] for _ in range(CLIENTS)]
    paths: list[list[int]] = [[] for _ in range(CLIENTS)]
    failures = [0]
    deadline = time.monotonic() + seconds
    start = threading.Barrier(CLIENTS)

    def client(k: int) -> None:
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
        start.wait()
        i = k
        while time.monotonic() < deadline:
            path = paths_polled[i % len(paths_polled)]
            i += 1
            t0 = time.perf_counter()
            try:
                conn.request("GET", path)
                response = conn.getresponse()
                response.read()
                ok = response.status == 200
            except OSError:
                ok = False
                conn.close()
                conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
            latencies[k].append(time.perf_counter() - t0)
            paths[k].append((i - 1) % len(paths_polled))
            failures[0] += not ok
        conn.close()

    threads = [threading.Thread(target=client, args=(k,)) for k in range(CLIENTS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    if failures[0]:
        print(f"  ({failures[0]} requests failed)")
    return (
        np.array([x for per_client in latencies for x in per_client]),
        np.array([x for per_client in paths for x in per_client]),
    )


def summary(latencies: np.ndarray, seconds: float) -> dict[str, float]:
    """Requests per second and latency percentiles (ms) of one condition."""
    return {
        "req_per_s": len(latencies) / seconds,
        "p50_ms": float(np.percentile(latencies, 50) * 1000),
        "p99_ms": float(np.percentile(latencies, 99) * 1000),
        "max_ms": float(latencies.max() * 1000),
    }


def window(
    studio: Studio, label: str, seconds: float, paths_polled: tuple[str, ...] = PATHS
) -> tuple[np.ndarray, int]:
    """Load the API for ``seconds``; the latencies and the frames the pipeline dropped."""
    source0 = studio.call("GET", "/api/source")
    latencies, paths = load(studio.port, seconds, paths_polled)
    source1 = studio.call("GET", "/api/source")
    dropped = source1["dropped"] - source0["dropped"]
    row = summary(latencies, seconds)
    p99 = {
        paths_polled[j]: float(np.percentile(latencies[paths == j], 99) * 1000)
        for j in range(len(paths_polled))
        if np.any(paths == j)
    }
    slowest = max(p99, key=p99.__getitem__)
    rate = (source1["frames"] - source0["frames"]) / seconds
    print(
        f"  {label:<22} {row['req_per_s']:6.0f} req/s   p50 {row['p50_ms']:6.1f} ms   "
        f"p99 {row['p99_ms']:6.1f} ms   max {row['max_ms']:6.0f} ms   source {rate:5.1f} Hz, "
        f"{dropped} frames dropped; slowest {slowest} (p99 {p99[slowest]:.0f} ms)"
    )
    return latencies, dropped


def page_stream(port: int, until: threading.Event) -> threading.Thread:
    """A page's live stream (``/api/events``), read until ``until`` is set, in a thread."""

    def read() -> None:
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
        conn.request("GET", "/api/events")
        response = conn.getresponse()
        while not until.is_set() and response.read1(65536):
            pass
        conn.close()

    thread = threading.Thread(target=read, daemon=True)
    thread.start()
    return thread


def measure(
    niceness: int, seconds: float, rounds: int, heavy: bool = False
) -> dict[str, dict[str, float]]:
    """Alternate windows without and with training on one studio (the machine's other load
    changes over time: alternating spreads it over both conditions).

    ``heavy``: the run is :data:`ISSUE_RUN`, a page's live stream is open throughout, the
    clients also poll the run's curve, and each round measures while training first, then with
    the run stopped (its finished curve polled as the baseline's)."""
    pooled: dict[str, list[np.ndarray]] = {"idle": [], "training": []}
    dropped = {"idle": 0, "training": 0}
    body = ISSUE_RUN if heavy else HEAVY_RUN
    with tempfile.TemporaryDirectory(prefix="bench-api-load-") as data:
        studio = Studio(niceness, Path(data))
        closing = threading.Event()
        try:
            studio.call("POST", "/api/capture/start", {"name": "bench"})
            if heavy:
                page_stream(studio.port, closing)
            time.sleep(1.0)  # the capture and the scene settle
            for _ in range(rounds):
                if not heavy:
                    latencies, lost = window(studio, "no training", seconds)
                    pooled["idle"].append(latencies)
                    dropped["idle"] += lost
                run = studio.call("POST", "/api/runs", body)
                polled = PATHS + (CURVE_PATH.format(run=run["id"]),) if heavy else PATHS
                deadline = time.monotonic() + START_TIMEOUT_S
                while studio.call("GET", f"/api/runs/{run['id']}")["episodes_done"] == 0:
                    if time.monotonic() > deadline:
                        raise RuntimeError("the heavy run did not start training")
                    time.sleep(0.2)
                latencies, lost = window(studio, f"training (nice {niceness})", seconds, polled)
                pooled["training"].append(latencies)
                dropped["training"] += lost
                studio.call("POST", f"/api/runs/{run['id']}/stop")
                while studio.call("GET", f"/api/runs/{run['id']}")["status"] == "running":
                    time.sleep(0.2)
                if heavy:
                    latencies, lost = window(studio, "no training", seconds, polled)
                    pooled["idle"].append(latencies)
                    dropped["idle"] += lost
            recording = studio.call("POST", "/api/capture/stop")
            print(
                f"  the capture kept {recording['frames']} frames of "
                f"{recording['duration']:.1f} s ({recording['frames'] / recording['duration']:.1f} Hz)"
            )
        finally:
            closing.set()
            studio.stop()
    return {
        name: {**summary(np.concatenate(parts), seconds * rounds), "dropped": dropped[name]}
        for name, parts in pooled.items()
    }


def long_recording(path: Path, megabytes: float) -> Path:
    """A valid recording of about ``megabytes`` MB: a shipped sample's frames, over and over."""
    from studio.capture import RecordingWriter, TapeFrame, read_recording
    from studio.samples import SAMPLES_DIR

    source = SAMPLES_DIR / "sample-reach-1.tape.csv"
    sample = read_recording(source)
    frames = int(megabytes * 1e6 / (source.stat().st_size / len(sample.t)))
    period = 1.0 / sample.rate_hz
    n = len(sample.t)
    with RecordingWriter(path, config=sample.config, name=path.name.split(".")[0]) as writer:
        for k in range(0, frames, n):
            writer.write_many(
                [
                    TapeFrame((k + i) * period, k + i, sample.bend[i], sample.twist[i])
                    for i in range(n)
                ]
            )
    return path


def upload_stall(megabytes: float) -> dict[str, float]:
    """The longest wait of a client polling the API while a long recording is uploaded and
    parsed, against the same client's longest wait with no upload."""
    with tempfile.TemporaryDirectory(prefix="bench-api-upload-") as data:
        recording = long_recording(Path(data) / "long.tape.csv", megabytes)
        size_mb = recording.stat().st_size / 1e6
        studio = Studio(TRAINING_NICENESS, Path(data) / "studio")
        try:

            def poll(until: threading.Event) -> float:
                conn = http.client.HTTPConnection("127.0.0.1", studio.port, timeout=60)
                worst = 0.0
                while not until.is_set():
                    t0 = time.perf_counter()
                    conn.request("GET", "/api/capture")
                    conn.getresponse().read()
                    worst = max(worst, time.perf_counter() - t0)
                    time.sleep(0.01)
                conn.close()
                return worst

            quiet = threading.Event()
            timer = threading.Timer(3.0, quiet.set)
            timer.start()
            idle_worst = poll(quiet)
            done = threading.Event()
            worst: list[float] = []
            poller = threading.Thread(target=lambda: worst.append(poll(done)))
            poller.start()
            body, boundary = multipart(recording)
            conn = http.client.HTTPConnection("127.0.0.1", studio.port, timeout=300)
            t0 = time.perf_counter()
            conn.request(
                "POST",
                "/api/recordings",
                body=body,
                headers={"Content-Type": f"multipart/form-data; boundary={boundary}"},
            )
            status = conn.getresponse().status
            upload_s = time.perf_counter() - t0
            done.set()
            poller.join()
            conn.close()
        finally:
            studio.stop()
    print(
        f"upload of a {size_mb:.0f} MB recording: {status} in {upload_s:.1f} s; "
        f"longest wait of another request {worst[0] * 1000:.0f} ms during it, "
        f"{idle_worst * 1000:.0f} ms without"
    )
    return {"upload_s": upload_s, "worst_ms": worst[0] * 1000, "idle_worst_ms": idle_worst * 1000}


def multipart(path: Path) -> tuple[bytes, str]:
    """A ``multipart/form-data`` body holding ``path`` as the field ``file``."""
    boundary = "bench-api-load-boundary"
    head = (
        f'--{boundary}\r\nContent-Disposition: form-data; name="file"; filename="{path.name}"'
        "\r\nContent-Type: text/csv\r\n\r\n"
    ).encode()
    return head + path.read_bytes() + f"\r\n--{boundary}--\r\n".encode(), boundary


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=6.0, help="length of each window")
    parser.add_argument("--rounds", type=int, default=2, help="idle/training window pairs")
    parser.add_argument(
        "--upload-mb", type=float, default=45.0, help="size of the uploaded recording (0: skip)"
    )
    parser.add_argument(
        "--niceness",
        type=int,
        default=None,
        help="training priority to measure (default: the studio's own, TRAINING_NICENESS)",
    )
    parser.add_argument(
        "--heavy",
        action="store_true",
        help="issue 18's load: a 100 x 20,000-episode run, 15 s windows, a page's live stream "
        "and the run's curve polled too (a few minutes)",
    )
    args = parser.parse_args()
    if args.heavy and args.seconds == parser.get_default("seconds"):
        args.seconds = 15.0
    niceness = TRAINING_NICENESS if args.niceness is None else args.niceness
    print(
        f"{CLIENTS} clients polling the API, the simulator at 110 Hz with a capture, "
        f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}; "
        f"{args.rounds} x {args.seconds:g} s per condition"
        + (f"; heavy: {ISSUE_RUN}, a page's live stream, the run's curve" if args.heavy else "")
    )
    result = measure(niceness, args.seconds, args.rounds, args.heavy)
    idle, busy = result["idle"], result["training"]
    for name, row in result.items():
        print(
            f"{name:<9} {row['req_per_s']:6.0f} req/s   p50 {row['p50_ms']:6.1f} ms   "
            f"p99 {row['p99_ms']:6.1f} ms   {row['dropped']} frames dropped"
        )
    verdict = "meets" if busy["p99_ms"] < GOAL_P99_MS else "misses"
    print(
        f"p99 while training / p99 without: {busy['p99_ms'] / idle['p99_ms']:.2f}x; "
        f"{busy['p99_ms']:.0f} ms {verdict} the {GOAL_P99_MS:.0f} ms goal "
        f"(nice {niceness}); frames dropped while training: {busy['dropped']}"
    )
    if args.upload_mb > 0:
        upload_stall(args.upload_mb)


if __name__ == "__main__":
    main()
