"""The studio page's speed in a real browser, each figure against a baseline in the same run.

1. First paint and DOMContentLoaded of the studio page vs a minimal static HTML page served by the
   same uvicorn/FastAPI stack, plus the time until the 3D scene's canvas exists (goal: < 2 s).
2. Curve updates per second in the page while a run trains (goal: >= 5/s).
3. Training slowdown with the page open vs no page at all (same run config; goal: <= 10 %).

Run: ``python benchmarks/bench_web.py`` (about a minute; needs /usr/bin/chromium).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
CHROMIUM = "/usr/bin/chromium"
FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
]
BASELINE_HTML = "<!doctype html><html><head><title>baseline</title></head><body><h1>baseline</h1><p>static page</p></body></html>"
TRAIN = {"planning": "full", "episodes": 500, "experiments": 20, "bins": 31, "seed": 1}
"""A run of a few seconds (a finer grid than the paper's 11 bins, which trains in a blink)."""
SAMPLE = "sample-reach-1"
"""A shipped recording, paused, to hold the scene still."""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def http(method: str, url: str, body: Any = None) -> Any:
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(
        url, data=data, method=method, headers={"Content-Type": "application/json"}
    )
    with urllib.request.urlopen(req, timeout=30) as r:
        raw = r.read()
        return json.loads(raw) if raw else None


def start_studio(data_dir: Path) -> tuple[subprocess.Popen[bytes], str]:
    port, vport = free_port(), free_port()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "studio",
            "serve",
            "--data-dir",
            str(data_dir),
            "--port",
            str(port),
            "--viser-port",
            str(vport),
            "--no-browser",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        cwd=data_dir,
    )
    base = f"http://127.0.0.1:{port}"
    end = time.monotonic() + 90
    while time.monotonic() < end:
        try:
            http("GET", base + "/api/config")
            return proc, base
        except OSError:
            if proc.poll() is not None:
                raise SystemExit("studio serve exited early") from None
            time.sleep(0.25)
    proc.kill()
    raise SystemExit("studio serve did not start")


def start_baseline() -> str:
    """A minimal HTML page on the same uvicorn + FastAPI stack as the studio."""
    import uvicorn
    from fastapi import FastAPI
    from fastapi.responses import HTMLResponse

    app = FastAPI()

    @app.get("/")
    def index() -> HTMLResponse:
        return HTMLResponse(BASELINE_HTML)

    port = free_port()
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="error"))
    threading.Thread(target=server.run, daemon=True).start()
    while not server.started:
        time.sleep(0.05)
    return f"http://127.0.0.1:{port}/"


def paint_times(browser: Any, url: str, scene: bool) -> dict[str, float]:
    """One cold load in a fresh context: first contentful paint, DOMContentLoaded, scene canvas."""
    ctx = browser.new_context(viewport={"width": 1440, "height": 900})
    page = ctx.new_page()
    t0 = time.perf_counter()
    page.goto(url, wait_until="load")
    out = page.evaluate(
        """() => new Promise((resolve) => {
            const nav = performance.getEntriesByType('navigation')[0];
            new PerformanceObserver((list, obs) => {
                const fcp = list.getEntries().find((p) => p.name === 'first-contentful-paint');
                if (fcp) { obs.disconnect(); resolve({dcl: nav.domContentLoadedEventEnd, fcp: fcp.startTime}); }
            }).observe({type: 'paint', buffered: true});
        })"""
    )
    if scene:
        page.frame_locator("#scene").locator("canvas").first.wait_for(
            state="attached", timeout=60_000
        )
        out["canvas"] = (time.perf_counter() - t0) * 1000.0
    ctx.close()
    return out


def train(base: str, name: str) -> dict[str, Any]:
    """Run TRAIN to the end; the run with ``wall``: seconds from submitting to done (+-0.05 s)."""
    t0 = time.perf_counter()
    run = http("POST", base + "/api/runs", {**TRAIN, "name": name})
    while True:
        run = http("GET", f"{base}/api/runs/{run['id']}")
        if run["status"] in ("done", "stopped", "failed"):
            run["wall"] = time.perf_counter() - t0
            return run
        time.sleep(0.05)


def wall(run: dict[str, Any]) -> float:
    return run["wall"]


def chromium_cpu_seconds() -> float:
    """CPU seconds used so far by every Chromium process on this machine (Linux /proc)."""
    tick = os.sysconf("SC_CLK_TCK")
    total = 0.0
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                if b"chromium" not in f.read():
                    continue
            with open(f"/proc/{pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:  # the process ended meanwhile
            continue
        total += (int(fields[11]) + int(fields[12])) / tick
    return total


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--loads", type=int, default=3, help="cold page loads per page")
    parser.add_argument("--runs", type=int, default=3, help="training runs per condition")
    args = parser.parse_args()
    if not Path(CHROMIUM).exists():
        raise SystemExit(f"needs Chromium at {CHROMIUM}")
    from playwright.sync_api import sync_playwright

    data = Path(tempfile.mkdtemp(prefix="bench-web-"))
    (data / "recordings").mkdir()
    for sample in (REPO / "recordings").glob("sample-*"):
        shutil.copy(sample, data / "recordings" / sample.name)
    proc, base = start_studio(data)
    try:
        baseline_url = start_baseline()
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True)
            paint_times(browser, base + "/", scene=True)  # warm caches (page files, numba) once
            paint_times(browser, baseline_url, scene=False)
            studio = [paint_times(browser, base + "/", scene=True) for _ in range(args.loads)]
            basic = [paint_times(browser, baseline_url, scene=False) for _ in range(args.loads)]
            med = lambda rows, k: statistics.median(r[k] for r in rows)  # noqa: E731
            print(f"== first paint (median of {args.loads} cold loads, ms)")
            print(
                f"  studio   FCP {med(studio, 'fcp'):7.0f}  DOMContentLoaded {med(studio, 'dcl'):7.0f}  scene canvas {med(studio, 'canvas'):7.0f}"
            )
            print(
                f"  baseline FCP {med(basic, 'fcp'):7.0f}  DOMContentLoaded {med(basic, 'dcl'):7.0f}"
            )
            print(
                f"  ratio    FCP {med(studio, 'fcp') / med(basic, 'fcp'):7.2f}x DOMContentLoaded {med(studio, 'dcl') / med(basic, 'dcl'):6.2f}x"
            )
            print(
                f"  goal: studio first paint < 2000 ms -> {'OK' if med(studio, 'fcp') < 2000 else 'MISSED'}"
            )

            # Each page condition against training with no page open under the same live source
            # (the simulator's kinematics cost the studio a little CPU of their own).
            train(base, "warm-up")
            without_live = [wall(train(base, f"no-page-live-{i}")) for i in range(args.runs)]
            live = measure_with_page(browser, base, "live", args.runs)
            # The scene still: a paused recording feeds no new poses.
            http("PUT", base + "/api/source", {"kind": "recording", "recording": SAMPLE})
            http("POST", base + "/api/source/playback", {"action": "pause"})
            without_idle = [wall(train(base, f"no-page-idle-{i}")) for i in range(args.runs)]
            idle = measure_with_page(browser, base, "idle", args.runs)
            browser.close()
        print(f"== training ({TRAIN}, median of {args.runs} runs each, s of wall time)")
        for label, without, (walls, rates, cores) in (
            ("scene still", without_idle, idle),
            ("live simulator", without_live, live),
        ):
            w0, w1 = statistics.median(without), statistics.median(walls)
            rate = statistics.median(rates) if rates else float("nan")
            print(
                f"  {label:<15} no page {w0:5.2f}  page {w1:5.2f}   slowdown {w1 / w0:5.2f}x (goal <= 1.10)"
                f"   curve updates {rate:5.1f}/s (goal >= 5)"
                f"   browser used {statistics.median(cores):4.2f} of {os.cpu_count()} cores"
            )
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
        shutil.rmtree(data, ignore_errors=True)
    return 0


def measure_with_page(
    browser: Any, base: str, tag: str, runs: int
) -> tuple[list[float], list[float], list[float]]:
    """Train ``runs`` times with the page open: wall times, curve updates per second seen, and
    the cores the browser used meanwhile (it competes with training for this machine's CPU)."""
    ctx = browser.new_context(viewport={"width": 1440, "height": 900})
    page = ctx.new_page()
    page.goto(base + "/")
    page.wait_for_selector("body[data-ready='1']", timeout=30_000)
    time.sleep(2.0)  # the scene connects and settles
    walls, rates, cores = [], [], []
    for i in range(runs):
        before = page.evaluate("() => window.studio.curveRenders || 0")
        cpu = chromium_cpu_seconds()
        run = train(base, f"{tag}-page-{i}")
        cores.append((chromium_cpu_seconds() - cpu) / wall(run))
        renders = page.evaluate("() => window.studio.curveRenders || 0") - before
        walls.append(wall(run))
        rates.append(renders / wall(run))
    ctx.close()
    return walls, rates, cores


if __name__ == "__main__":
    raise SystemExit(main())
