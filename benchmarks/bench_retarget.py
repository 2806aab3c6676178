"""Retargeting the operator's arm onto every offered robot: time per frame and what it reaches.

For each robot, a minute of the studio's known arm motion (``arm_motion``) at 110 Hz goes
through ``Retargeter(robot=load_robot(name))`` (cartesian; warm-started IK, one null-space elbow
step a frame, joint steps capped, self-collision guard). The baseline, in the same run, solves
the same targets cold from the robot's home pose every frame (what a naive per-frame IK does).

Prints per robot: the median and p99 time of a frame (ours, and the baseline's, and their
ratio), the share of frames whose tool is within 1 cm (and within 1 cm and 5 deg where the
robot follows the orientation) of the target, the largest joint step between frames, and how
many sampled frames are in self-collision.

    python benchmarks/bench_retarget.py [--seconds 60] [--robots panda ur5 ...]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from studio.kinematics import HumanArm, Retargeter, arm_motion, load_robot, robot_names


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    cos = (np.trace(a[:3, :3].T @ b[:3, :3]) - 1) / 2
    return math.degrees(math.acos(float(np.clip(cos, -1, 1))))


def bench(name: str, seconds: float) -> None:
    arm = load_robot(name)
    motion = arm_motion(np.arange(0.0, seconds, 1 / 110), HumanArm())
    ours = Retargeter(robot=None if name == "puma560" else arm, mode="cartesian")
    times, q = [], []
    for q_human in motion:
        t0 = time.perf_counter()
        q.append(ours.robot_from_human(q_human))
        times.append(time.perf_counter() - t0)
    q = np.array(q)
    cold = []
    for q_human in motion[::10]:
        target = ours.hand_target(q_human)
        t0 = time.perf_counter()
        arm.inverse(target, arm.home, iterations=ours.config.ik_iterations)
        cold.append(time.perf_counter() - t0)
    near = full = 0
    for q_robot, q_human in zip(q, motion, strict=True):
        target, got = ours.hand_target(q_human), arm.forward(q_robot)
        close = np.linalg.norm(got[:3, 3] - target[:3, 3]) < 0.01
        near += close
        full += close and (not arm.spec.orientation or _angle_deg(got, target) < 5)
    step = np.degrees(np.abs(np.diff(q, axis=0))).max()
    hits = sum(bool(arm.self_collisions(p)) for p in q[::11]) if arm.checks_collisions else 0
    median, cold_median = np.median(times) * 1e3, np.median(cold) * 1e3
    print(
        f"{name:8s} frame median {median:.2f} ms (p99 {np.percentile(times, 99) * 1e3:.1f}); "
        f"cold IK {cold_median:.2f} ms: ratio {cold_median / median:.1f}x | "
        f"tool within 1 cm {near / len(q):.0%}, and 5 deg {full / len(q):.0%} | "
        f"largest step {step:.1f} deg | self-collision {hits}/{len(q[::11])}",
        flush=True,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--robots", nargs="*", default=list(robot_names()))
    args = parser.parse_args()
    for name in args.robots:
        bench(name, args.seconds)


if __name__ == "__main__":
    main()
