"""The robots the studio offers, by name: their files, arm joints and defaults (no model loaded).

A light module: ``studio train --help`` and the page's robot list read the names here, while
:mod:`._robots` and :mod:`._robot_load` build a :class:`RobotArm` (Pinocchio, numba) from a spec
only when a robot is loaded.
"""

from __future__ import annotations

import importlib.metadata
import math
import sysconfig
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from ._checks import KinematicsError
from ._dh import PAPER_GRID_RANGE_DEG, PUMA_READY_DEG, PUMA_WRIST_PAIRS, puma560_urdf

LIMIT_MARGIN_RAD = 0.02
"""The margin (rad) every plan keeps from each joint's hard (URDF) limit, by default: a robot's
:attr:`RobotArm.lower` and :attr:`RobotArm.upper` are its hard limits less this (less a tenth of
a joint's range where that is smaller), and the retargeting's IK, the learners' tasks and the
export's checks all use them; an exported URDF keeps the hard ones
(:meth:`RobotArm.with_limit_margin` gives another margin)."""


@dataclass(frozen=True)
class RobotSpec:
    """One offered robot: where its files are and which of its joints form the arm.

    Attributes:
        name: the name users type (``--robot panda``).
        title: the name people read.
        urdf: the URDF, relative to the robots folder (empty when ``generate`` builds it).
        srdf: the SRDF whose disabled collision pairs are honoured (empty: none).
        tool: the frame whose pose is the tool's.
        arm_joints: how many of the URDF's first joints form the arm (the rest are locked).
        orientation: whether retargeting asks for the tool's orientation too (an arm with fewer
            than six joints cannot reach every orientation, so it follows the position only).
        acceleration: joint acceleration limits (rad/s^2), or empty for twice the velocity limit.
        elbow: the joint (1-based) whose origin is the arm's elbow, for the null-space task.
        ready: a pose in the middle of the workspace (degrees) that tasks aim for by default,
            where :attr:`RobotArm.home` is a poor aim (the Puma560's: the paper's goal,
            :data:`PUMA_READY_DEG`); empty: ``home``.
        approach: the tool frame's axis that points out of the tool, along its fingers
            (``"z"``, the ROS convention, or ``"x"`` where the URDF's tool frame has it so).
        facing: the direction the arm faces in its URDF's base frame, as an angle about z from
            +x (rad): the studio turns its targets and its drawing by it, so that every arm
            faces the operator (the SO-100's URDF faces -y).
        hollow: the radius, as a share of :attr:`RobotArm.reach`, of the column around the
            first joint's axis that the tool cannot enter with the arm raised (an arm whose
            shoulder is offset sideways, the UR's), or can enter only by turning its first
            joint faster than it can (the SO-100's): the retargeting keeps hand targets out of
            it smoothly (:attr:`RetargetConfig.hollow_softness`); 0 for none.
        usable_reach: the share of :attr:`RobotArm.reach` (the farthest the tool gets, at
            whatever orientation) that the retargeting maps the operator's reach onto, times
            :attr:`RetargetConfig.reach_fraction`: less than 1 for an arm whose tool reaches
            that far only at a few orientations.
        generate: builds the URDF's text, for a robot whose URDF is made from a description in
            code rather than read from a file (the Puma560's, from its DH table).
        package: the installed package whose files (meshes) the URDF names, for the sentence
            that says what to reinstall when one is missing.
        joint_mode: whether its joints can follow the operator's one by one (the paper's joint
            mode, :data:`studio.kinematics._retarget.JOINT_MAP`: the Puma560's); every robot
            follows the hand in cartesian mode.
        close_by_design: link pairs never checked against each other, as an SRDF's
            ``disable_collisions`` lists them, for a robot without an SRDF whose links sit
            within the checks' margin of each other at every pose (:data:`PUMA_WRIST_PAIRS`).
        grid_range_deg: the ``(low, high)`` range, degrees, over which the learning grid bins
            every joint (the paper's task space, :data:`PAPER_GRID_RANGE_DEG`, the Puma560's);
            empty: each joint's own limits.
        lerobot_driver: the LeRobot driver that drives this arm itself (the ``robot_type`` it
            registers, whose joint conventions the arm's LeRobot datasets follow); empty: none.
    """

    name: str
    title: str
    urdf: str
    srdf: str
    tool: str
    arm_joints: int
    orientation: bool = True
    acceleration: tuple[float, ...] = field(default=())
    elbow: int = 3
    ready: tuple[float, ...] = field(default=())
    approach: str = "z"
    facing: float = 0.0
    hollow: float = 0.0
    usable_reach: float = 1.0
    generate: Callable[[], str] | None = None
    package: str = "example-robot-data"
    joint_mode: bool = False
    close_by_design: tuple[tuple[str, str], ...] = ()
    grid_range_deg: tuple[float, float] | tuple[()] = ()
    lerobot_driver: str = ""


UR_READY_DEG = (0.0, -90.0, 90.0, -90.0, -90.0, 0.0)
"""The UR arms' ready pose: upper arm up, forearm level and forward, tool pointing down. Their
``home`` (every joint 0) is the arm stretched out level, at the edge of the workspace."""

UR_HOLLOW = 0.2
"""The UR arms' :attr:`RobotSpec.hollow`. Their wrist is offset sideways from the first axis
(0.11, 0.11 and 0.16 m on the UR3, UR5 and UR10), so with the arm raised the tool cannot come
nearer the axis than about that: a hand held straight above or below the operator's shoulder,
mapped there, was out of every pose's reach (85-211 of the 566 frames ``test_reach`` judges).
Kept 0.2 of the reach out, such a frame is reached. Between 0.15
and 0.25 the frames reached change by a few points either way, differently on each motion."""

SO100_HOLLOW = 0.1
"""The SO-100's :attr:`RobotSpec.hollow`. It follows the hand's position only, and its first
joint turns the whole arm about the vertical: a target near that axis is reached by turning it
by the target's angle around the axis, which a hand passing a centimetre or two from it swings
through 120 degrees in a fraction of a second. The operator's hand held near the shoulder (a
reach's start) mapped there: the first joint then had to turn 8.6 times as fast as its 1 rad/s
allows, and the exports of sample-reach-2 and -3 took 2.3 and 3.0 times the person's duration.
Kept 0.1 of the reach out, they take 1.15 and 1.38 times it, and the arm reaches every frame of
the three samples and the simulator minute (it missed 10% of sample-reach-3). At 0.15 the
exports took longer (1.39 and 1.42 times), and at 0.2-0.25 the hand's targets were moved out by
more than a centimetre on 5-27% of the frames of samples 2 and 3 (``benchmarks/bench_reach.py``).
The SO-101, whose URDF allows its joints 10 rad/s, keeps pace without it."""

UR_USABLE_REACH = 0.9
"""The UR5's and UR10's :attr:`RobotSpec.usable_reach`. Their wrist offsets (0.09-0.16 m) put
the farthest tool positions at a few orientations only: with the hand's targets drawn back to
0.95 of the sampled reach, the arm tracked them with its elbow straight and could follow the
hand back in only on the other shoulder branch, missing 10% of the test motions' frames (a
walk between branches each time). Mapped onto 0.9 of it, they miss 1.0% (UR5) and none (UR10);
also on 20 s of ``arm_motion`` (4.5-5% -> 0%) and 30 s of simulator, seed 5 (8-9% -> 1.3-1.6%),
with the hand's target drawn back into the reach as often as before. The UR3 gains on one
motion and loses on another, so it keeps 1."""

ROBOT_SPECS: dict[str, RobotSpec] = {
    spec.name: spec
    for spec in (
        RobotSpec(
            "puma560",
            "Puma560 (the paper's robot)",
            "",
            "",
            "tool",
            6,
            generate=puma560_urdf,
            package="rtb-data",
            ready=PUMA_READY_DEG,
            joint_mode=True,
            close_by_design=PUMA_WRIST_PAIRS,
            grid_range_deg=PAPER_GRID_RANGE_DEG,
        ),
        RobotSpec(
            "panda",
            "Franka Emika Panda",
            "panda_description/urdf/panda.urdf",
            "panda_description/srdf/panda.srdf",
            "panda_hand_tcp",
            7,
            # Franka's datasheet (docs.franka.de, "Limits for Panda").
            acceleration=(15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0),
            elbow=4,
        ),
        RobotSpec(
            "ur3",
            "Universal Robots UR3",
            "ur_description/urdf/ur3_robot.urdf",
            "ur_description/srdf/ur5.srdf",
            "tool0",
            6,
            ready=UR_READY_DEG,
            hollow=UR_HOLLOW,
        ),
        RobotSpec(
            "ur5",
            "Universal Robots UR5",
            "ur_description/urdf/ur5_robot.urdf",
            "ur_description/srdf/ur5.srdf",
            "tool0",
            6,
            ready=UR_READY_DEG,
            hollow=UR_HOLLOW,
            usable_reach=UR_USABLE_REACH,
        ),
        RobotSpec(
            "ur10",
            "Universal Robots UR10",
            "ur_description/urdf/ur10_robot.urdf",
            "ur_description/srdf/ur5.srdf",
            "tool0",
            6,
            ready=UR_READY_DEG,
            hollow=UR_HOLLOW,
            usable_reach=UR_USABLE_REACH,
        ),
        RobotSpec(
            "so100",
            "SO-100 (LeRobot)",
            "so_arm_description/urdf/so100.urdf",
            "",
            "wrist",
            5,
            orientation=False,
            facing=-math.pi / 2,
            hollow=SO100_HOLLOW,
            lerobot_driver="so100_follower",
        ),
        RobotSpec(
            "so101",
            "SO-101 (LeRobot)",
            "so_arm_description/urdf/so101.urdf",
            "",
            "gripper_frame_link",
            5,
            orientation=False,
            lerobot_driver="so101_follower",
        ),
        RobotSpec(
            "xarm7",
            "UFactory xArm7",
            "xarm_description/urdf/xarm7.urdf",
            "xarm_description/srdf/xarm7.srdf",
            "link_eef",
            7,
            elbow=4,
        ),
        RobotSpec(
            "z1",
            "Unitree Z1",
            "z1_description/urdf/z1.urdf",
            "",
            "gripperStator",
            6,
            approach="x",
        ),
        RobotSpec(
            "kinova",
            "Kinova Jaco 2 (j2s6s200)",
            "kinova_description/robots/kinova.urdf",
            "kinova_description/srdf/kinova.srdf",
            "j2s6s200_end_effector",
            6,
            approach="x",
        ),
    )
}
"""Every offered robot by name; the Puma560 first (the default, the paper's)."""

DEFAULT_ROBOT = "puma560"


def robot_names() -> tuple[str, ...]:
    """The names of the offered robots, the default first."""
    return tuple(ROBOT_SPECS)


def robot_spec(name: object) -> RobotSpec:
    """The spec of robot ``name``, or a KinematicsError listing the offered names."""
    spec = ROBOT_SPECS.get(name) if isinstance(name, str) else None
    if spec is None:
        raise KinematicsError(
            f"Unknown robot {name!r}; use one of {', '.join(robot_names())} (`studio robots` "
            "lists them with their joints)."
        )
    return spec


ROBOTS_RELATIVE = Path("cmeel.prefix/share/example-robot-data/robots")
"""Where the ``example-robot-data`` wheel installs its robots, relative to site-packages."""


def robots_folder() -> Path:
    """The folder of example-robot-data's robots, or a KinematicsError saying how to install it."""
    candidates: list[Path] = []
    try:
        dist = importlib.metadata.distribution("example-robot-data")
        candidates.append(Path(str(dist.locate_file(ROBOTS_RELATIVE))))
    except importlib.metadata.PackageNotFoundError:
        pass
    for key in ("purelib", "platlib"):
        candidates.append(Path(sysconfig.get_paths()[key]) / ROBOTS_RELATIVE)
    for path in candidates:
        if path.is_dir():
            return path
    raise KinematicsError(
        "The robot models of example-robot-data were not found; install them with "
        "`pip install example-robot-data`."
    )
