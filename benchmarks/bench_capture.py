"""Capture speed: the recorder and every source, against naive baselines measured in the same run.

1. Recorder: frames/s of :class:`RecordingWriter` (buffered, flushed + fsynced every 0.5 s)
   versus naive recorders that open, append one line and close the file per frame, or fsync
   every line (as crash-safe as ours, and what a quick script does to be safe).
2. Playback into the recorder, as fast as possible: frames/s and multiple of real time (110 Hz);
   the issue asks for at least 20x.
3. Reader: frames/s of :func:`read_recording` versus a per-line ``csv`` + ``float`` parse.
4. Simulator generator (:func:`simulate`): frames/s and multiple of real time.
5. Live sources at 110 Hz (simulator, playback, UDP network bridge, serial tape on a pty), each
   feeding a consumer that runs the kinematics pipeline on every frame (reconstruct, and the arm
   fit + retarget when the kinematics package has them): measured rate and dropped frames.

Run: ``python benchmarks/bench_capture.py [--frames 20000] [--live-seconds 3]``.
"""

from __future__ import annotations

import argparse
import csv
import multiprocessing
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from studio.capture import (
    NetworkSource,
    PlaybackSource,
    RecordingWriter,
    SerialSource,
    ShapeTapeEmulator,
    SimulatorSource,
    TapeFrame,
    read_recording,
    simulate,
    stream_source,
)
from studio.capture._recording_format import columns, format_row, header_line
from studio.capture._recording_writer import recording_meta

REAL_TIME_HZ = 110.0


def best_of(fn, repeats: int = 3) -> float:
    """Best wall time of ``repeats`` runs (the machine is shared)."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def naive_record(path: Path, frames: list[TapeFrame]) -> None:
    """Open, append one line, close: per frame (what a quick script does)."""
    with open(path, "w") as f:
        f.write(header_line(recording_meta(16)) + ",".join(columns(16)) + "\n")
    for fr in frames:
        with open(path, "a") as f:
            f.write(format_row(fr.t, fr.frame, fr.status, fr.bend, fr.twist))


def naive_safe_record(path: Path, frames: list[TapeFrame]) -> None:
    """Write, flush and fsync every line (the naive way never to lose a frame)."""
    with open(path, "w") as f:
        f.write(header_line(recording_meta(16)) + ",".join(columns(16)) + "\n")
        for fr in frames:
            f.write(format_row(fr.t, fr.frame, fr.status, fr.bend, fr.twist))
            f.flush()
            os.fsync(f.fileno())


def naive_read(path: Path) -> np.ndarray:
    """csv.reader and float() per field."""
    rows = []
    with open(path) as f:
        for row in csv.reader(line for line in f if not line.startswith("#")):
            rows.append([float(x) for x in row] if row[0] != "t" else None)
    return np.array([r for r in rows if r is not None])


def pipeline():
    """A per-frame function running the kinematics pipeline (whatever has landed)."""
    import studio.kinematics as kin

    config = kin.TapeConfig()
    steps = ["reconstruct"]
    fitter = retargeter = None
    if hasattr(kin, "ArmFitter"):
        fitter = kin.ArmFitter(kin.HumanArm(), config)
        steps.append("fit")
    if hasattr(kin, "Retargeter"):
        retargeter = kin.Retargeter("joint", mirror=True)
        steps.append("retarget")

    def run(frame: TapeFrame) -> None:
        shape = kin.reconstruct(frame.bend, frame.twist, config)
        if fitter is not None:
            fit = fitter.fit(shape)
            if retargeter is not None:
                retargeter.robot_from_human(fit.q_human)

    return run, "+".join(steps)


def emulate_tape(conn, recording_path: Path) -> None:
    """Child process: a ShapeTape emulator replaying a recording until told to stop."""
    replay = read_recording(recording_path)
    n = len(replay)
    emulator = ShapeTapeEmulator(lambda k: (replay.bend[k % n], replay.twist[k % n], 0)).start()
    conn.send(emulator.port)
    conn.recv()
    emulator.unplug()


def live(source, seconds: float, per_frame, before=None) -> tuple[float, int, int]:
    """Consume a live source for ``seconds`` with ``per_frame`` on each frame: (rate, frames, dropped)."""
    source.start()
    if before is not None:
        before()
    count = 0
    start = time.monotonic()
    while time.monotonic() - start < seconds:
        for frame in source.read(timeout=0.05):
            per_frame(frame)
            count += 1
    status = source.status()
    source.stop()
    return status.rate_hz, count, status.dropped + (1 if status.error else 0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20000, help="frames for the offline runs")
    parser.add_argument("--live-seconds", type=float, default=3.0, help="seconds per live source")
    args = parser.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench-capture-"))
    n = args.frames

    t_sim = best_of(lambda: simulate(n / REAL_TIME_HZ, seed=0), repeats=1)
    frames = simulate(n / REAL_TIME_HZ, seed=0).frames
    print(
        f"simulate():     {n / t_sim:10.0f} frames/s = {n / t_sim / REAL_TIME_HZ:6.0f}x real time"
    )

    counter = iter(range(10**6))

    def ours() -> None:
        with RecordingWriter(tmp / f"ours{next(counter)}.tape.csv", 16) as w:
            for i in range(0, n, 11):  # batches as a 110 Hz source delivers them
                w.write_many(frames[i : i + 11])

    t_ours = best_of(ours)
    n_naive = min(n, 5000)
    t_naive = best_of(lambda: naive_record(tmp / "naive.tape.csv", frames[:n_naive])) * n / n_naive
    n_safe = min(n, 1000)
    t_safe = (
        best_of(lambda: naive_safe_record(tmp / "safe.tape.csv", frames[:n_safe]), 1) * n / n_safe
    )
    print(
        f"recorder:       {n / t_ours:10.0f} frames/s vs naive open/append/close {n / t_naive:8.0f} frames/s"
        f"  ratio {t_naive / t_ours:5.1f}x"
    )
    print(
        f"                {'':10s}            vs naive fsync per line    {n / t_safe:8.0f} frames/s"
        f"  ratio {t_safe / t_ours:5.1f}x"
    )

    path = tmp / "ours0.tape.csv"
    t_read = best_of(lambda: read_recording(path))
    t_naive_read = best_of(lambda: naive_read(path))
    print(
        f"reader:         {n / t_read:10.0f} frames/s vs naive csv+float {n / t_naive_read:8.0f} frames/s"
        f"  ratio {t_naive_read / t_read:5.1f}x"
    )

    rec = read_recording(path)

    def playback_into_recorder() -> None:
        source = PlaybackSource(rec, speed=None)
        with RecordingWriter(tmp / f"play{next(counter)}.tape.csv", 16) as w:
            source.start()
            written = 0
            while written < n:
                got = source.read(timeout=0.5)
                w.write_many(got)
                written += len(got)
            source.stop()

    t_play = best_of(playback_into_recorder)
    print(
        f"playback->rec:  {n / t_play:10.0f} frames/s = {n / t_play / REAL_TIME_HZ:6.0f}x real time (target >= 20x)"
    )

    per_frame, steps = pipeline()
    t_pipe = best_of(lambda: [per_frame(f) for f in frames[:200]], repeats=1) / 200
    print(
        f"pipeline ({steps}): {t_pipe * 1e3:.2f} ms/frame = {1 / t_pipe:.0f} frames/s on one core"
    )
    print(f"live sources at 110 Hz for {args.live_seconds:g} s each, pipeline on every frame:")
    secs = args.live_seconds
    results = {}
    results["simulator"] = live(SimulatorSource(seed=0), secs, per_frame)
    results["playback"] = live(PlaybackSource(rec, speed=1.0), secs, per_frame)
    receiver = NetworkSource(port=0)
    receiver.start()
    host, port = receiver.address
    import threading

    sender = threading.Thread(
        target=stream_source,
        args=(PlaybackSource(rec, speed=1.0), host, port, secs + 0.5),
        daemon=True,
    )
    results["network"] = live(receiver, secs, per_frame, before=sender.start)
    # the emulated tape runs in its own process, as a real tape is its own hardware
    parent, child = multiprocessing.Pipe()
    device = multiprocessing.get_context("fork").Process(
        target=emulate_tape, args=(child, path), daemon=True
    )
    device.start()
    port = parent.recv()
    results["serial"] = live(SerialSource(port, rate_hz=REAL_TIME_HZ), secs, per_frame)
    parent.send("stop")
    device.join(5)
    for name, (rate, count, dropped) in results.items():
        print(f"  {name:10s} {rate:6.1f} Hz  {count:5d} frames  dropped {dropped}")


if __name__ == "__main__":
    main()
