"""Timing an export: TOPP-RA along the path against Ruckig stopping at every waypoint.

The export times a demonstration's path with TOPP-RA (``studio.export.time_path``). The
alternative named by the issue, Ruckig, plans from one state to one target in its open-source
edition (no intermediate waypoints), so following a path means stopping at each waypoint. For
each shipped demonstration, on the Puma560 with the same thinned waypoints and the same limits
(0.8 of the robot's), this prints the trajectory's duration and the time to compute it with
both, measured interleaved in the same run, and their ratios; then the safety checks' cost per
sample for a robot with collision geometry (the Panda) and without (the Puma560); then a
recording's export with its fitted arm smoothed with the future, against the live filter.

Run: ``python benchmarks/bench_export.py`` (about a minute; ``pip install ruckig`` for the
baseline). Wall times on a shared machine are noisy; the durations are not.
"""

from __future__ import annotations

import time

import numpy as np

from studio.capture import load_demonstration
from studio.export import LIMIT_FRACTION, check_trajectory, time_path
from studio.export._timing import PATH_TOLERANCE_RAD, _thin
from studio.kinematics import load_robot
from studio.samples import SAMPLES_DIR

RATE_HZ = 50.0


def ruckig_stops(robot, q: np.ndarray) -> float:
    """Duration (s) of Ruckig moves from waypoint to waypoint, at rest at each."""
    import ruckig

    dof = q.shape[1]
    otg = ruckig.Ruckig(dof)
    total = 0.0
    for a, b in zip(q[:-1], q[1:], strict=True):
        inp = ruckig.InputParameter(dof)
        inp.current_position, inp.target_position = a.tolist(), b.tolist()
        inp.max_velocity = (LIMIT_FRACTION * robot.velocity).tolist()
        inp.max_acceleration = (LIMIT_FRACTION * robot.acceleration).tolist()
        inp.max_jerk = [1e3] * dof  # effectively unbounded: TOPP-RA bounds no jerk either
        out = ruckig.Trajectory(dof)
        otg.calculate(inp, out)
        total += out.duration
    return total


def main() -> None:
    puma = load_robot("puma560")
    print(f"{'demonstration':<26}{'TOPP-RA s':>10}{'Ruckig s':>10}{'ratio':>7}"
          f"{'TOPP-RA cpu':>13}{'Ruckig cpu':>12}")  # fmt: skip
    for k in (1, 2, 3):
        demo = load_demonstration(SAMPLES_DIR / f"sample-reach-{k}.demo.json")
        q = demo.q_robot[np.r_[True, np.abs(np.diff(demo.q_robot, axis=0)).max(axis=1) > 1e-9]]
        waypoints = q[_thin(q, PATH_TOLERANCE_RAD)]
        t0 = time.process_time()
        times, _ = time_path(puma, demo.q_robot, RATE_HZ)
        t1 = time.process_time()
        stops = ruckig_stops(puma, waypoints)
        t2 = time.process_time()
        print(f"{demo.recording.name + f' #{k}':<26}{times[-1]:>10.1f}{stops:>10.1f}"
              f"{stops / times[-1]:>7.2f}{t1 - t0:>12.2f}s{t2 - t1:>11.2f}s")  # fmt: skip
    s = np.linspace(0.0, 1.0, 200)[:, None]
    arc = np.hstack([0.8 * np.sin(np.pi * s), 0.5 * s, -0.6 * s**2, np.zeros((200, 3))])
    waypoints = arc[_thin(arc, PATH_TOLERANCE_RAD)]
    t0 = time.process_time()
    times, _ = time_path(puma, arc, RATE_HZ)
    t1 = time.process_time()
    stops = ruckig_stops(puma, waypoints)
    t2 = time.process_time()
    print(f"{'a smooth arc':<26}{times[-1]:>10.1f}{stops:>10.1f}{stops / times[-1]:>7.2f}"
          f"{t1 - t0:>12.2f}s{t2 - t1:>11.2f}s")  # fmt: skip
    for name in ("puma560", "panda"):
        robot = load_robot(name)
        path = np.linspace(robot.home, np.clip(robot.home + 0.3, robot.lower, robot.upper), 500)
        t = np.arange(500) / 110.0
        t0 = time.process_time()
        check_trajectory(robot, t, path)
        per = (time.process_time() - t0) / 500
        print(f"safety checks, {name}: {per * 1e3:.3f} ms of CPU per sample")
    recorded_noise()


def recorded_noise() -> None:
    """A recording exported onto a robot: its fitted arm smoothed with the future
    (``smooth_recorded_arm``, what ``fit_frames`` does) against the live filter (the baseline),
    on simulated takes whose true arm is known. Printed per take and robot: the timed
    trajectory's duration as a share of the true arm's path's, the joints' turns back, and the
    shoulder and elbow's mean error (deg)."""
    import tempfile
    from pathlib import Path

    from studio.capture import RecordingWriter, human_angles, read_any_recording, simulate
    from studio.kinematics import ArmTracker, retarget_path
    from studio.kinematics.human._filter import turn_backs

    print("\na recording's export, smoothed with the future (ours) against the live filter (base):")
    print(f"{'take':<8}{'robot':<8}{'duration / true':>18}{'turns back':>14}"
          f"{'sh+el err deg':>16}{'ratio':>7}")  # fmt: skip
    folder = Path(tempfile.mkdtemp())
    for seed in (1, 3, 7):
        sim = simulate(10.0, seed=seed)
        path = folder / f"take-{seed}.tape.csv"
        with RecordingWriter(path, config=sim.config, source="simulator") as writer:
            writer.write_many(sim.frames)
        ours = human_angles(read_any_recording(path), slice(None))
        tracker = ArmTracker(sim.config)
        base = [tracker.track(f.bend, f.twist, f.t).q_human for f in sim.frames]
        for name in ("panda", "ur5", "kinova"):
            robot = load_robot(name)
            true_s = time_path(robot, retarget_path(robot, sim.q_human).q, RATE_HZ)[0][-1]
            row = []
            for q_human in (ours, np.array(base)):
                q = retarget_path(robot, q_human).q
                error = np.degrees(np.abs(q_human - sim.q_human)[:, [0, 1, 3]]).mean()
                row.append((time_path(robot, q, RATE_HZ)[0][-1] / true_s, turn_backs(q), error))
            (d, n, e), (bd, bn, be) = row
            print(f"{seed:<8}{name:<8}{d:>8.2f} / {bd:<8.2f}{n:>6} / {bn:<6}"
                  f"{e:>7.2f} / {be:<7.2f}{bd / d:>6.2f}x")  # fmt: skip


if __name__ == "__main__":
    main()
