"""Retargeting the operator's arm onto every offered robot: time per frame and what it reaches.

For each robot, the studio's known arm motion (``arm_motion``) at 110 Hz goes through
``Retargeter(robot=load_robot(name))`` in cartesian mode (ours: the compiled IK warm-started from
the last answer, restarts when it misses, one null-space elbow step a frame, joint steps capped,
the self-collision guard measuring only the link pairs that may have come close). The baseline,
in the same run and on the same hand targets, is the previous live path, kept below as the
reference: the IK as a loop of Pinocchio and NumPy calls, a position-only second solve when the
pose is missed, and every link pair measured every frame (for the Puma560: its IK without the
step cap, as before).

Prints per robot, ours against the baseline: the median and p99 time of a frame and their
ratio, the share of frames whose tool is within 1 cm and 5 deg of the target
(``studio.kinematics.tool_reaches``; 1 cm only where the robot follows the position), the share
of frames whose target was reachable but missed, the largest joint step between frames and how
often a joint turns back between frames (``turn_backs``: jitter, or a pose flipping between two
IK answers).
Then, for ours, why frames were missed, judged on every 11th frame by
``studio.kinematics.reachable`` (the one definition the tests use too): the hand drawn back into
the arm's reach sphere (the raised shoulder carries it beyond), targets no pose reaches (out of
reach: joint limits or orientation), targets reachable only on another branch of the IK (the
step cap walks the robot there over several frames), targets reachable within one frame's step
of where the robot stood (the retargeting should never miss these), and self-collisions among
those frames.
Then the same motion as a recording: ``retarget_path`` plans which IK branch to take where, with
the whole motion known; its share reached and reachable-but-missed against the live pass's, how
many of its misses a pose reaches on the way between the path's reached frames either side at
the step cap (the plan should leave none), and the seconds it takes against the live pass's.

    python benchmarks/bench_retarget.py [--seconds 20] [--robots panda ur5 ...]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
import pinocchio as pin

from studio.kinematics import (
    HumanArm,
    Puma560,
    RetargetConfig,
    Retargeter,
    RobotArm,
    arm_motion,
    load_robot,
    reachable,
    retarget_path,
    robot_names,
    tool_reaches,
)
from studio.kinematics.human._filter import turn_backs


def previous_inverse(
    arm: RobotArm, target: np.ndarray, q0: np.ndarray, elbow: np.ndarray | None, iterations: int
) -> tuple[np.ndarray, bool, float]:
    """The previous ``RobotArm.inverse``: the same DLS as a Python loop over Pinocchio calls.

    Returns (q, success, position error)."""
    model, data, tool = arm.model, arm.data, arm.tool_frame
    elbow_joint = min(arm.spec.elbow, model.njoints - 1)
    pos_only = target.shape == (3,) or not arm.spec.orientation
    target_p = target if target.shape == (3,) else target[:3, 3]
    target_R = np.eye(3) if target.shape == (3,) else target[:3, :3]
    rows = 3 if pos_only else 6
    damp, e, q = np.eye(rows) * 1e-4, np.empty(rows), q0.copy()
    pos_err = rot_err = math.inf
    elbow_steps = 1
    for it in range(iterations + 1):
        pin.forwardKinematics(model, data, q)
        oMtool = pin.updateFramePlacement(model, data, tool)
        e[:3] = target_p - oMtool.translation
        pos_err = float(np.linalg.norm(e[:3]))
        if pos_only:
            rot_err = 0.0
        else:
            e[3:] = pin.log3(target_R @ oMtool.rotation.T)
            rot_err = float(np.linalg.norm(e[3:]))
        reached = pos_err <= 1e-3 and rot_err <= math.radians(1.0)
        if it == iterations or (reached and elbow is None):
            break
        pin.computeJointJacobians(model, data, q)
        J = pin.getFrameJacobian(model, data, tool, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:rows]
        JJt = J @ J.T + damp
        dq = J.T @ np.linalg.solve(JJt, e)
        if elbow is not None and arm.nq > rows:
            Je = pin.getJointJacobian(
                model, data, elbow_joint, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
            )[:3]
            pull = Je.T @ (elbow - data.oMi[elbow_joint].translation)
            null = np.eye(arm.nq) - J.T @ np.linalg.solve(JJt, J)
            secondary = 0.5 * null @ pull
            if reached and (elbow_steps <= 0 or float(np.abs(secondary).max()) < 1e-4):
                break
            elbow_steps -= reached
            dq += secondary
        biggest = float(np.abs(dq).max())
        if biggest > 0.2:
            dq *= 0.2 / biggest
        q = np.minimum(np.maximum(q + dq, arm.lower), arm.upper)
    return q, pos_err <= 1e-3 and rot_err <= math.radians(1.0), pos_err


class PreviousPath:
    """The previous live path of one frame, on the targets ours computes."""

    def __init__(self, arm: RobotArm, ours: Retargeter) -> None:
        self.arm, self.ours, self.q_prev = arm, ours, None
        self.config = RetargetConfig()
        self.puma = ours.robot if isinstance(ours.robot, Puma560) else None

    def frame(self, q_human: np.ndarray) -> np.ndarray:
        target = self.ours.hand_target(q_human)
        if self.puma is not None:
            found = self.puma.inverse(target, q0=self.q_prev)
            if not found.success:
                position = self.puma.inverse(target[:3, 3], q0=found.q, position_only=True)
                found = position if position.success or position.error < found.error else found
            self.q_prev = found.q
            return found.q
        arm, iterations = self.arm, self.config.ik_iterations
        elbow = self.ours.elbow_target(q_human) if arm.nq > 6 else None
        start = arm.home if self.q_prev is None else self.q_prev
        q, success, error = previous_inverse(arm, target, start, elbow, iterations)
        if not success and arm.spec.orientation:
            q2, success2, error2 = previous_inverse(arm, target[:3, 3], q, elbow, iterations)
            q = q2 if success2 or error2 < error else q
        if self.q_prev is not None:
            step = self.config.max_joint_step
            q = self.q_prev + np.clip(q - self.q_prev, -step, step)
        if arm.checks_collisions and arm.self_collisions(q, self.config.clearance):
            q = arm.home if self.q_prev is None else self.q_prev
        self.q_prev = q
        return q


def run(frame, motion: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    times, q = np.empty(len(motion)), []
    for i, q_human in enumerate(motion):
        t0 = time.perf_counter()
        q.append(frame(q_human))
        times[i] = time.perf_counter() - t0
    return times * 1e3, np.array(q)


def bench(name: str, seconds: float) -> None:
    arm = load_robot(name)
    motion = arm_motion(np.arange(0.0, seconds, 1 / 110), HumanArm())
    ours = Retargeter(robot=None if name == "puma560" else arm, mode="cartesian")
    previous = PreviousPath(arm, Retargeter(robot=ours.robot, mode="cartesian"))
    pulled = []

    def our_frame(q_human: np.ndarray) -> np.ndarray:
        q = ours.robot_from_human(q_human)
        pulled.append(ours.pulled_in)
        return q

    previous_ms, previous_q = run(previous.frame, motion)
    ours_ms, ours_q = run(our_frame, motion)
    targets = [ours.hand_target(q_human) for q_human in motion]
    rows = {}
    for label, ms, q in (("ours", ours_ms, ours_q), ("previous", previous_ms, previous_q)):
        reached = np.array([tool_reaches(arm, p, t) for p, t in zip(q, targets, strict=True)])
        step = float(np.degrees(np.abs(np.diff(q, axis=0))).max())
        rows[label] = (np.median(ms), np.percentile(ms, 99), reached, step, turn_backs(q))
    (m, p99, reached, step, turns), (m0, p990, reached0, step0, turns0) = (
        rows["ours"],
        rows["previous"],
    )
    sample = range(1, len(motion), 11)
    missed = [i for i in sample if not reached[i]]
    near = [i for i in missed if reachable(arm, targets[i], near=ours_q[i - 1])]
    walked = [i for i in missed if i not in near and reachable(arm, targets[i])]
    drawn = np.mean(np.array(pulled) > RetargetConfig().reach_tolerance)
    hits = sum(bool(arm.self_collisions(ours_q[i])) for i in sample)
    print(
        f"{name:8s} median {m:.2f} ms (previous {m0:.2f}, {m0 / m:.1f}x) | p99 {p99:.2f} "
        f"(previous {p990:.2f}) | reached {reached.mean():.0%} (previous {reached0.mean():.0%}) "
        f"| reachable but missed {(len(near) + len(walked)) / len(sample):.1%} "
        f"| largest step {step:.1f} deg (previous {step0:.1f}) "
        f"| joints turning back {turns} times (previous {turns0})",
        flush=True,
    )
    print(
        f"{'':8s} hand drawn into reach {drawn:.0%} of frames | of {len(sample)} sampled frames "
        f"{len(missed)} missed: {len(missed) - len(near) - len(walked)} out of reach; "
        f"{len(walked)} reachable only on another IK branch (walked there at the step cap); "
        f"{len(near)} reachable within a step | self-collision {hits}/{len(sample)}",
        flush=True,
    )
    if name != "puma560":  # its recordings play in joint mode: no branches to plan
        planned(arm, motion, targets, reached, len(near) + len(walked), ours_ms.sum() / 1e3)


def planned(
    arm: RobotArm,
    motion: np.ndarray,
    targets: list[np.ndarray],
    live_reached: np.ndarray,
    live_missed: int,
    live_s: float,
) -> None:
    """The same motion as a recording: ``retarget_path`` plans its IK branches with the whole
    motion known; against the live pass above (``live_*``), on the same targets and frames."""
    t0 = time.perf_counter()
    q = retarget_path(arm, motion).q
    seconds = time.perf_counter() - t0
    reached = np.array([tool_reaches(arm, p, t) for p, t in zip(q, targets, strict=True)])
    sample = range(1, len(motion), 11)
    missed = [i for i in sample if not reached[i] and reachable(arm, targets[i])]
    on_the_way = [
        i for i in missed if reachable(arm, targets[i], within_steps_of=_ends(q, reached, i))
    ]
    step = float(np.degrees(np.abs(np.diff(q, axis=0))).max())
    hits = sum(bool(arm.self_collisions(q[i])) for i in sample)
    print(
        f"{'':8s} as a recording, branches planned: reached {reached.mean():.0%} (live "
        f"{live_reached.mean():.0%}) | reachable but missed {len(missed) / len(sample):.1%} "
        f"(live {live_missed / len(sample):.1%}; of the planned, {len(on_the_way)} reachable "
        f"on the way between their reached neighbours) | largest step {step:.1f} deg | "
        f"self-collision {hits}/{len(sample)} | {seconds:.1f} s for the motion "
        f"(live {live_s:.1f} s, {seconds / live_s:.1f}x)",
        flush=True,
    )


def _ends(q: np.ndarray, reached: np.ndarray, i: int) -> list[tuple[np.ndarray, int]]:
    """The path's nearest reached frames before and after frame ``i``, as ``(pose, frames
    away)``: a pose reaching frame ``i`` within the step cap of both could be walked through."""
    before = np.flatnonzero(reached[:i])[-1:]
    after = i + 1 + np.flatnonzero(reached[i + 1 :])[:1]
    return [(q[a], i - a) for a in before] + [(q[b], b - i) for b in after]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--robots", nargs="*", default=list(robot_names()))
    args = parser.parse_args()
    for name in args.robots:
        bench(name, args.seconds)


if __name__ == "__main__":
    main()
