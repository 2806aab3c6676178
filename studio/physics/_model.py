"""A robot's MuJoCo model: its URDF compiled, position servos limited by its efforts, the table.

:func:`build_model` compiles :func:`~._mjcf.mujoco_urdf`'s text with ``mujoco.MjSpec`` and adds
what a URDF does not say but a real arm has:

- **the arm's joints only:** joints beyond :attr:`RobotArm.nq` (fingers, grippers) are locked
  where the studio's model locks them (0, or the nearest limit), as
  :func:`~studio.kinematics.load_robot` does;
- **a position servo per joint** (:data:`SERVO_HZ`, critically damped), a feed-forward motor
  for the torque the trajectory itself needs (:func:`~._replay.simulate` computes it from the
  model) and the arm's own gravity compensation, as a robot's joint controller has; their total
  force is limited by the URDF's ``effort`` (``actfrcrange``), so a motion that asks more of a
  joint than its motor gives saturates it; a URDF effort of 0 (not modelled) leaves the joint
  unlimited;
- **gravity** (9.81 m/s^2 down) and **the table the robot stands on**: the plane of its base, as
  :meth:`RobotArm.table_contacts` models it (the links the first joint turns about the vertical
  stand on it and never touch it; the others can be driven into it);
- **the same self-collision pairs as the studio's checks** (:meth:`RobotArm.self_collisions`):
  link pairs the studio leaves out (adjacent links, the SRDF's disabled pairs) are excluded;
- **the task's obstacles** when given (:class:`~studio.kinematics.Obstacle`): fixed boxes in the
  base frame, named ``obstacle_1``, ``obstacle_2``, ... as the studio's own check names them,
  which every link a joint moves can touch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from studio.kinematics import TABLE, Obstacle, RobotArm

from ._errors import PhysicsError

if TYPE_CHECKING:
    import mujoco

TIMESTEP_S = 1e-3
"""The simulation's step (s): 1 kHz, a robot joint controller's usual rate."""

SERVO_HZ = 10.0
"""Each joint servo's natural frequency (Hz) at its largest inertia: its stiffness is that
inertia times (2 pi f)^2, its damping critical there. A 10-Hz servo lags 2.5 mrad behind a
10 rad/s^2 acceleration. Where the joint's inertia is smaller the servo is stiffer; its damping
of at least stiffness times the step, integrated implicitly, keeps it stable at any stiffness."""

INERTIA_POSES = 32
"""How many poses (home and random ones within the limits) a joint's largest inertia is taken
over."""

FRICTION_ERROR_RAD = 2e-3
"""The most a joint's dry friction (the URDF's ``<dynamics friction>``) may hold a servo off its
target at rest (rad): where the inertia alone gives a softer servo (a light wrist against a
1 N m friction, the xArm7's), its stiffness is raised to this, and its damping to at least
stiffness times the step, which keeps the stiffer servo stable (the damping is integrated
implicitly)."""

FEEDFORWARD = "_feedforward"
"""The ending of each joint's feed-forward motor's name (its servo has the joint's name)."""

_ROBOT_CONTACT = 1
"""The contact bit every link's geometry has: link against link."""
_TABLE_CONTACT = 2
"""The contact bit of the table and of the links that can be driven into it."""
_OBSTACLE_CONTACT = 4
"""The contact bit of the obstacles and of every link a joint moves."""


@dataclass(frozen=True)
class PhysicsModel:
    """A compiled robot for :func:`~._replay.simulate`.

    Attributes:
        arm: the studio's model of the same robot (joint names, limits, self-collision pairs).
        model: the MuJoCo model.
        qpos: the arm joints' addresses in ``qpos``, in :attr:`RobotArm.joint_names` order.
        dofs: their addresses in ``qvel`` and ``qfrc_*``.
        effort: each joint's force limit (N m or N; infinity where the URDF models none).
        kp, kv: each servo's stiffness and damping.
        tool: the body whose pose is the tool's (:attr:`RobotSpec.tool`).
        table: the table's geom id.
        links: each body's name (the URDF's link names), by body id.
        obstacles: each obstacle's geom id, by its name (``obstacle_1``, ...).
    """

    arm: RobotArm
    model: mujoco.MjModel
    qpos: np.ndarray
    dofs: np.ndarray
    effort: np.ndarray
    kp: np.ndarray
    kv: np.ndarray
    tool: int
    table: int
    links: tuple[str, ...]
    obstacles: dict[int, str] = field(default_factory=dict)

    def tool_poses(self, q: np.ndarray) -> np.ndarray:
        """The tool's pose (4x4, base frame) at each row of ``q``, from MuJoCo's kinematics."""
        import mujoco

        data = mujoco.MjData(self.model)
        poses = np.tile(np.eye(4), (len(q), 1, 1))
        for i, row in enumerate(np.atleast_2d(q)):
            data.qpos[self.qpos] = row
            mujoco.mj_kinematics(self.model, data)
            poses[i, :3, :3] = data.xmat[self.tool].reshape(3, 3)
            poses[i, :3, 3] = data.xpos[self.tool]
        return poses


def _lock(spec: mujoco.MjSpec, joint: mujoco.MjsJoint) -> None:
    """Remove ``joint``, its body kept where the joint's locked value (0, or the nearest limit)
    put it."""
    import mujoco

    low, high = (float(v) for v in joint.range)
    value = float(np.clip(0.0, low, high)) if low < high else 0.0
    body = joint.parent
    if value:
        axis = np.asarray(joint.axis, dtype=float)
        axis /= np.linalg.norm(axis)
        turn = np.eye(3)
        shift = np.zeros(3)
        if joint.type == mujoco.mjtJoint.mjJNT_HINGE:
            turned = np.zeros(4)
            mujoco.mju_axisAngle2Quat(turned, axis, value)
            mujoco.mju_quat2Mat(turn.reshape(9), turned)
            quat = np.zeros(4)
            mujoco.mju_mulQuat(quat, np.asarray(body.quat, dtype=float), turned)
            pivot = np.asarray(joint.pos, dtype=float)
            shift = pivot - turn @ pivot
            body.quat = quat
        else:
            shift = axis * value
        frame = np.zeros(9)
        mujoco.mju_quat2Mat(frame, np.asarray(body.quat, dtype=float))
        body.pos = np.asarray(body.pos, dtype=float) + frame.reshape(3, 3) @ shift
    spec.delete(joint)


def _collision_links(arm: RobotArm) -> tuple[set[frozenset[str]], set[str]]:
    """The link pairs the studio checks for self-collision, and the links that can touch the
    table (moved by a joint after the first), from the studio's own collision model."""
    geom, frames = arm.collision_model, arm.model.frames

    def link(k: int) -> str:
        return frames[geom.geometryObjects[k].parentFrame].name

    pairs = {frozenset((link(p.first), link(p.second))) for p in geom.collisionPairs}
    table = {link(k) for k, obj in enumerate(geom.geometryObjects) if obj.parentJoint >= 2}
    return pairs, table


def _set_contacts(spec: mujoco.MjSpec, arm: RobotArm, obstacles: tuple[Obstacle, ...]) -> None:
    """The table plane, the obstacles, and contact bits and exclusions so that MuJoCo collides
    exactly the pairs the studio checks."""
    import mujoco

    frames = arm.model.frames
    pairs, on_table = _collision_links(arm)
    with_geoms = []
    for body in spec.bodies:
        geoms = body.geoms
        if not geoms or body.name == "world":
            continue
        with_geoms.append(body.name)
        for g in geoms:
            g.contype = _ROBOT_CONTACT
            g.conaffinity = _ROBOT_CONTACT | (_TABLE_CONTACT if body.name in on_table else 0)
    for i, a in enumerate(with_geoms):
        for b in with_geoms[i + 1 :]:
            if frozenset((a, b)) not in pairs:
                spec.add_exclude(bodyname1=a, bodyname2=b)
    spec.worldbody.add_geom(
        name=TABLE,
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[0.0, 0.0, 0.01],  # 0: an infinite plane, as the studio's table is
        contype=_TABLE_CONTACT,
        conaffinity=0,
    )
    moving = (
        {
            frames[obj.parentFrame].name
            for obj in arm.collision_model.geometryObjects
            if obj.parentJoint >= 1
        }
        if obstacles
        else set()
    )
    for body in spec.bodies:
        if body.name in moving:
            for g in body.geoms:
                g.conaffinity |= _OBSTACLE_CONTACT
    for i, box in enumerate(obstacles):
        spec.worldbody.add_geom(
            name=f"obstacle_{i + 1}",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            pos=list(box.centre),
            size=[0.5 * side for side in box.size],
            contype=_OBSTACLE_CONTACT,
            conaffinity=0,
        )


def build_model(
    arm: RobotArm, urdf_text: str, obstacles: tuple[Obstacle, ...] = ()
) -> PhysicsModel:
    """Compile ``urdf_text`` (:func:`~._mjcf.mujoco_urdf`'s) for ``arm``, with servos, gravity,
    the table and ``obstacles`` (see the module docstring).

    Raises:
        PhysicsError: MuJoCo cannot compile it, or it lacks a joint or the tool of ``arm``.
    """
    import mujoco

    try:
        spec = mujoco.MjSpec.from_string(urdf_text)
    except ValueError as err:
        raise PhysicsError(
            f"MuJoCo cannot read the {arm.spec.title} URDF ({err}); reinstall the robot's "
            "description (example-robot-data)."
        ) from None
    spec.option.timestep = TIMESTEP_S
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    names = set(arm.joint_names)
    missing = names - {j.name for j in spec.joints}
    if missing:
        raise PhysicsError(
            f"The {arm.spec.title} URDF compiled by MuJoCo has no joint {sorted(missing)[0]}; "
            "its URDF changed: report it."
        )
    locked = [j for j in spec.joints if j.name not in names]
    for equality in spec.equalities:  # a mimic joint's coupling goes with the joints it couples
        if {equality.name1, equality.name2} & {j.name for j in locked}:
            spec.delete(equality)
    for joint in locked:
        _lock(spec, joint)
    efforts = _efforts(arm)
    for body in spec.bodies:
        body.gravcomp = 1.0  # the arm's controller holds it against gravity...
    for name, effort in zip(arm.joint_names, efforts, strict=True):
        joint = spec.joint(name)
        joint.actgravcomp = True  # ...with its motors, within their force limits
        if math.isfinite(effort):
            joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_TRUE
            joint.actfrcrange = [-effort, effort]
        actuator = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        actuator.set_to_position(kp=1.0, kv=1.0)
        actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    for name in arm.joint_names:  # after the servos: ctrl[nq:] is the feed-forward torque
        actuator = spec.add_actuator(
            name=f"{name}{FEEDFORWARD}", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT
        )
        actuator.set_to_motor()
        actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    _set_contacts(spec, arm, tuple(obstacles))
    try:
        model = spec.compile()
    except ValueError as err:
        raise PhysicsError(
            f"MuJoCo cannot compile the {arm.spec.title} model ({err}); its URDF or meshes are "
            "damaged: reinstall the robot's description (example-robot-data)."
        ) from None
    links = tuple(model.body(i).name for i in range(model.nbody))
    if arm.spec.tool not in links:
        raise PhysicsError(
            f"The {arm.spec.title} model MuJoCo compiled has no link {arm.spec.tool!r} (the "
            "tool); its URDF changed: report it."
        )
    qpos = np.array([model.joint(n).qposadr[0] for n in arm.joint_names])
    dofs = np.array([model.joint(n).dofadr[0] for n in arm.joint_names])
    kp, kv = _gains(model, qpos, dofs, arm)
    servos = slice(0, arm.nq)
    model.actuator_gainprm[servos, 0] = kp
    model.actuator_biasprm[servos, 1] = -kp
    model.actuator_biasprm[servos, 2] = -kv
    return PhysicsModel(
        arm,
        model,
        qpos,
        dofs,
        efforts,
        kp,
        kv,
        links.index(arm.spec.tool),
        model.geom(TABLE).id,
        links,
        {model.geom(f"obstacle_{i + 1}").id: f"obstacle_{i + 1}" for i in range(len(obstacles))},
    )


def _efforts(arm: RobotArm) -> np.ndarray:
    """Each arm joint's URDF effort limit, infinity where it is 0 (not modelled)."""
    effort = np.array(arm.model.effortLimit, dtype=float)
    return np.where(effort > 0.0, effort, np.inf)


def _gains(
    model: mujoco.MjModel, qpos: np.ndarray, dofs: np.ndarray, arm: RobotArm
) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and damping of :data:`SERVO_HZ` servos, from each joint's largest inertia over
    :data:`INERTIA_POSES` poses (home and random ones within the limits): a servo tuned at a
    folded pose lagged seconds behind with the arm stretched out (the Kinova's first joint)."""
    import mujoco

    data = mujoco.MjData(model)
    full = np.zeros((model.nv, model.nv))
    rng = np.random.default_rng(0)
    poses = [arm.home, *rng.uniform(arm.lower, arm.upper, size=(INERTIA_POSES - 1, arm.nq))]
    inertia = np.zeros(len(dofs))
    for q in poses:
        data.qpos[qpos] = q
        mujoco.mj_forward(model, data)
        mujoco.mj_fullM(model, data, full)
        inertia = np.maximum(inertia, np.diag(full)[dofs])
    omega = 2.0 * math.pi * SERVO_HZ
    kp = np.maximum(inertia * omega**2, model.dof_frictionloss[dofs] / FRICTION_ERROR_RAD)
    kv = np.maximum(2.0 * np.sqrt(kp * inertia), kp * TIMESTEP_S)
    return kp, kv
