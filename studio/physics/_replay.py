"""Replay a joint trajectory in MuJoCo: :func:`simulate` gives its :class:`SimulationReport`.

The arm starts at rest at the first sample. The trajectory between samples is a cubic spline
through them (twice differentiable, as a joint trajectory controller interpolates), held at
the last sample for :data:`SETTLE_S` after it. At every :data:`~._model.TIMESTEP_S` step each
servo is given the spline's position and velocity, and each feed-forward motor the torque the
spline's motion takes on the model (inertia, Coriolis, the joint's own damping and friction;
gravity is the arm's compensation's), as a computed-torque controller does. At each sample's time
the simulated joints and tool are compared with the trajectory's (the tool's pose from the same
MuJoCo model at the commanded joints), each motor's total force with its limit, and the contacts
MuJoCo found are gathered by link pair.
"""

from __future__ import annotations

import math

import numpy as np

from studio.kinematics import TABLE

from ._errors import PhysicsError
from ._model import TIMESTEP_S, PhysicsModel
from ._report import Contact, SimulationReport

SETTLE_S = 0.5
"""How long the arm holds the last sample before :func:`simulate` judges whether it completed."""

COMPLETION_M = 0.01
"""How near (m) the tool must rest to the last sample's tool position for the motion to count
as completed (issue 39's tracking goal, 1 cm)."""

MAX_DURATION_S = 600.0
"""The longest trajectory :func:`simulate` replays (s): ten minutes, 600 000 steps."""

_SATURATED = 1e-6
"""A motor whose force is within this share of its limit is at its limit."""


def _checked(model: PhysicsModel, times: object, q: object) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(times, dtype=float)
    joints = np.asarray(q, dtype=float)
    arm = model.arm
    if t.ndim != 1 or joints.ndim != 2 or len(t) != len(joints) or len(t) < 2:
        raise PhysicsError(
            f"A trajectory needs at least 2 samples of {arm.nq} joints with a time each; got "
            f"times of shape {t.shape} and joints of shape {joints.shape}."
        )
    if joints.shape[1] != arm.nq:
        raise PhysicsError(
            f"The {arm.spec.title} has {arm.nq} joints; the trajectory gives {joints.shape[1]}: "
            "simulate it on the robot it was exported for."
        )
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(joints))):
        raise PhysicsError("The trajectory holds NaN or infinite values; export it again.")
    if np.any(np.diff(t) <= 0.0):
        raise PhysicsError(
            "The trajectory's times do not increase sample by sample; export it again."
        )
    if t[-1] - t[0] > MAX_DURATION_S:
        raise PhysicsError(
            f"The trajectory lasts {t[-1] - t[0]:.0f} s, more than the {MAX_DURATION_S:.0f} s "
            "a replay simulates; cut it shorter."
        )
    return t - t[0], joints


def _reference(
    t: np.ndarray, q: np.ndarray, steps: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The commanded positions, velocities and accelerations at every step: the samples joined
    by a cubic spline, then the last sample held at rest."""
    from scipy.interpolate import CubicSpline

    clock = np.minimum(np.arange(1, steps + 1) * TIMESTEP_S, t[-1])
    spline = CubicSpline(t, q, axis=0)
    moving = (np.arange(1, steps + 1) * TIMESTEP_S <= t[-1])[:, None]
    return spline(clock), spline(clock, 1) * moving, spline(clock, 2) * moving


def _feedforward(
    model: PhysicsModel, position: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray
) -> np.ndarray:
    """The torque each joint needs to move as commanded, at every step: inertia and Coriolis
    (``M qdd + C qd``, gravity left to the arm's compensation) and the joint's own damping and
    dry friction."""
    import mujoco

    mj = model.model
    data = mujoco.MjData(mj)
    dofs = model.dofs
    torque = np.empty_like(position)
    acc = np.zeros(mj.nv)
    inertial = np.zeros(mj.nv)
    for k in range(len(position)):
        data.qpos[model.qpos] = position[k]
        data.qvel[dofs] = velocity[k]
        acc[dofs] = acceleration[k]
        mujoco.mj_fwdPosition(mj, data)
        mujoco.mj_fwdVelocity(mj, data)  # qfrc_bias = C qd + g; qfrc_gravcomp = g
        mujoco.mj_mulM(mj, data, inertial, acc)
        torque[k] = (inertial + data.qfrc_bias - data.qfrc_gravcomp)[dofs]
    damping = mj.dof_damping[dofs]
    friction = mj.dof_frictionloss[dofs]
    return torque + damping * velocity + friction * np.sign(velocity)


def simulate(model: PhysicsModel, times: object, q: object) -> SimulationReport:
    """Replay ``q`` (one row of joint angles per sample, rad) at ``times`` (s) on ``model``.

    Raises:
        PhysicsError: the trajectory is malformed (shapes, NaN, times not increasing, too long).
    """
    import mujoco

    t, q = _checked(model, times, q)
    mj = model.model
    data = mujoco.MjData(mj)
    data.qpos[model.qpos] = q[0]
    mujoco.mj_forward(mj, data)
    at_sample = np.rint(t / TIMESTEP_S).astype(int)  # the step whose state a sample is judged at
    steps = int(at_sample[-1] + math.ceil(SETTLE_S / TIMESTEP_S))
    position, velocity, acceleration = _reference(t, q, steps)
    command = position + velocity * (model.kv / model.kp)  # kp (q* - q) + kv (qd* - qd)
    torque = _feedforward(model, position, velocity, acceleration)
    servos = len(model.qpos)
    limit = model.effort * (1.0 - _SATURATED)
    joints = np.empty((steps + 1, len(model.qpos)))
    joints[0] = q[0]
    saturated = np.zeros((steps + 1, len(model.qpos)), dtype=bool)
    touching: dict[tuple[str, str], list[tuple[int, float]]] = {}
    stable = True
    for k in range(1, steps + 1):
        data.ctrl[:servos] = command[k - 1]
        data.ctrl[servos:] = torque[k - 1]
        mujoco.mj_step(mj, data)
        joints[k] = data.qpos[model.qpos]
        saturated[k] = np.abs(data.qfrc_actuator[model.dofs]) >= limit
        if data.ncon:
            found = data.contact
            for (g1, g2), dist in zip(
                found.geom[: data.ncon], found.dist[: data.ncon], strict=True
            ):
                touching.setdefault(_pair(model, g1, g2), []).append((k, -float(dist)))
        if not np.all(np.isfinite(joints[k])):
            stable = False
            joints[k:] = np.nan
            break
    return _report(model, t, q, joints, saturated, touching, at_sample, stable)


def _pair(model: PhysicsModel, g1: int, g2: int) -> tuple[str, str]:
    for box, other in ((g1, g2), (g2, g1)):
        if box in model.obstacles:
            return model.links[model.model.geom_bodyid[other]], model.obstacles[box]
    if g1 == model.table or g2 == model.table:
        other = g2 if g1 == model.table else g1
        return model.links[model.model.geom_bodyid[other]], TABLE
    a, b = (model.links[model.model.geom_bodyid[g]] for g in (g1, g2))
    return (a, b) if a <= b else (b, a)


def _report(
    model: PhysicsModel,
    t: np.ndarray,
    q: np.ndarray,
    joints: np.ndarray,
    saturated: np.ndarray,
    touching: dict[tuple[str, str], list[tuple[int, float]]],
    at_sample: np.ndarray,
    stable: bool,
) -> SimulationReport:
    arm = model.arm
    got = joints[at_sample]
    joint_error = np.abs(got - q)
    wanted = model.tool_poses(q)[:, :3, 3]
    if stable:
        reached = model.tool_poses(got)[:, :3, 3]
        tool_error = np.linalg.norm(reached - wanted, axis=1)
        rest = model.tool_poses(joints[-1:])[0, :3, 3]
        completed = bool(np.linalg.norm(rest - wanted[-1]) <= COMPLETION_M)
    else:
        tool_error = np.full(len(t), np.inf)
        completed = False
    # a sample saturates when a motor reached its limit since the previous sample
    ends = np.concatenate([[0], at_sample[1:]])
    starts = np.concatenate([[0], at_sample[:-1] + 1])
    per_sample = np.array(
        [saturated[s : e + 1].any(axis=0) for s, e in zip(starts, ends, strict=True)]
    )
    hit = per_sample.any(axis=1)
    sample_of_step = np.searchsorted(at_sample, np.arange(len(joints)), side="left")
    contacts = []
    for (a, b), touches in touching.items():
        hit_samples = sorted({int(min(sample_of_step[k], len(t) - 1)) for k, _ in touches})
        contacts.append(
            Contact(
                a,
                b,
                hit_samples[0],
                float(t[hit_samples[0]]),
                len(hit_samples),
                max(0.0, max(depth for _, depth in touches)),
            )
        )
    contacts.sort(key=lambda c: (c.first_sample, c.link_a, c.link_b))
    return SimulationReport(
        robot=arm.name,
        completed=completed,
        max_joint_error_rad=float(np.nanmax(joint_error)) if stable else math.inf,
        max_tool_error_m=float(np.max(tool_error)),
        saturated_samples=int(hit.sum()),
        contacts=tuple(contacts),
        samples=len(t),
        duration_s=float(t[-1]),
        saturated_joints=tuple(
            n for n, s in zip(arm.joint_names, per_sample.any(axis=0), strict=True) if s
        ),
        first_saturated_sample=int(np.argmax(hit)) if hit.any() else None,
        obstacles=len(model.obstacles),
        unlimited_joints=tuple(
            n for n, e in zip(arm.joint_names, model.effort, strict=True) if not math.isfinite(e)
        ),
        times=t,
        q_simulated=got,
    )
