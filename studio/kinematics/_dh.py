"""What a Puma560 is: its standard-DH table with its limits, what pictures it, and its URDF.

A leaf module: the model (:mod:`._puma`) and the robot registry (:mod:`._robots`) both read this
description, and it imports neither, so the dependency runs one way.

The URDF (:func:`urdf_from_dh`): URDF link ``link{i}`` is Pinocchio joint i's frame (DH frame i-1
turned by q_i about its z), so each revolute joint's origin is the previous DH row's fixed part
``Tz(d) Tx(a) Rx(alpha)``; a fixed joint then places the ``tool`` link at DH frame 6. Numbers are
written with Python's round-trip float formatting, so a tool that loads the file gets the same
kinematics as :class:`~studio.kinematics.Puma560` to the last bit of the DH parameters.
:func:`puma560_urdf` is the file the robot registry loads (``load_robot("puma560")``), with the
link meshes of ``rtb-data`` as its visual and collision geometry, like every other arm's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import PurePosixPath
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    import numpy as np
    import pinocchio as pin

# Pinocchio, numpy and the XML quoting (which loads urllib, http and email) are imported where a
# pose or the URDF is built, not with this module: the robot registry reads the Puma560's ready
# pose and grid range here without loading them (`studio train --help` lists the robots).

PUMA_READY_DEG = (0.0, 45.0, -90.0, 0.0, 0.0, 0.0)
"""The Puma560's ``RobotSpec.ready``, the paper's goal: the paper shows its goal only as a picture
(Fig. 7), so joints 1-3 at (0, 45, -90) (an arm reaching forward and down, inside the limits), the
wrist at 0."""

PAPER_GRID_RANGE_DEG = (-180.0, 180.0)
"""The paper's range of every joint, degrees (its task space: 11 bins over [-180, 180] for joints
1-3, giving 1331 states): the Puma560's ``RobotSpec.grid_range_deg``."""

PUMA_WRIST_PAIRS = (("link4", "link6"),)
"""The Puma560's ``RobotSpec.close_by_design``: its wrist links 4 and 6 (rtb-data's meshes) both
hug the wrist centre, 2.5 mm apart at every pose (at rest, and over the three sample
demonstrations), so a clearance of more than that refused every motion; joint 5 between them
turns within its +-100 degrees without the two meeting."""


@dataclass(frozen=True)
class DHRow:
    """One row of a standard-DH table: ``Rz(q) Tz(d) Tx(a) Rx(alpha)``, a revolute joint.

    Attributes:
        d: offset along the previous z axis (m).
        a: length along the new x axis (m).
        alpha: twist about the new x axis (rad).
        lower: lower joint limit (rad).
        upper: upper joint limit (rad).
        velocity: the joint's speed limit (rad/s); 0: not known.
        effort: the joint's torque limit (N m); 0: not known.
    """

    d: float
    a: float
    alpha: float
    lower: float
    upper: float
    velocity: float = 0.0
    effort: float = 0.0

    def fixed(self) -> pin.SE3:
        """The joint-independent part ``Tz(d) Tx(a) Rx(alpha)`` of this row."""
        import numpy as np
        import pinocchio as pin

        c, s = math.cos(self.alpha), math.sin(self.alpha)
        rotation = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
        return pin.SE3(rotation, np.array([self.a, 0.0, self.d]))


PUMA_VELOCITY = (1.92, 1.51, 2.40, 5.34, 5.09, 5.74)
"""The Puma560's joint speed limits (rad/s, joints 1-6). P. I. Corke, *Visual Control of Robots:
High-Performance Visual Servoing*, Research Studies Press, 1996, Table 2.21 ("load referenced"
joint rates): the motors' measured saturation speeds (Table 2.18: 120, 163, 129, 406, 366,
440 rad/s at the motor) over the gear ratios (Table 2.9: 62.6111, 107.815, 53.7063, 76.0364,
71.923, 76.686, the ratios the Robotics Toolbox's ``models/DH/Puma560.py`` carries as ``G``).
Unimation published no per-joint speed that we could find; this is the measured one."""

PUMA_EFFORT = (97.6, 186.4, 89.4, 24.2, 20.1, 21.3)
"""The Puma560's joint torque limits (N m, joints 1-6): B. Armstrong, O. Khatib and J. Burdick,
"The explicit dynamic model and inertial parameters of the PUMA 560 arm", Proc. IEEE ICRA 1986,
Table 7 ("maximum torque"). Cyberbotics' Webots Puma560 model gives its joint 1 and 2 motors the
same 97.6 and 186.4 N m."""

#: Corke's Puma560 (Robotics Toolbox, ``models/DH/Puma560.py``; the joint limits there are from
#: Wang & Chen 1991), all joint offsets zero; speed and torque limits as above.
DH_TABLE: tuple[DHRow, ...] = tuple(
    DHRow(d, a, alpha, math.radians(-limit), math.radians(limit), velocity, effort)
    for (d, a, alpha, limit), velocity, effort in zip(
        (
            (0.67183, 0.0, math.pi / 2, 160),
            (0.0, 0.4318, 0.0, 110),
            (0.15005, 0.0203, -math.pi / 2, 135),
            (0.4318, 0.0, math.pi / 2, 266),
            (0.0, 0.0, -math.pi / 2, 100),
            (0.0, 0.0, 0.0, 266),
        ),
        PUMA_VELOCITY,
        PUMA_EFFORT,
        strict=True,
    )
)

PUMA_MESH_DIR = PurePosixPath("meshes/UNIMATE/puma560")
"""Where ``rtb-data`` keeps the Puma560 link meshes, relative to its package folder ``rtbdata``:
``link{j}.stl`` drawn in DH frame j (``link0`` the base), as the Robotics Toolbox attaches them."""

PUMA_LINK_COLORS = (
    (0.55, 0.56, 0.60),
    (0.80, 0.80, 0.82),
    (0.86, 0.86, 0.88),
    (0.80, 0.80, 0.82),
    (0.40, 0.42, 0.46),
    (0.40, 0.42, 0.46),
    (0.25, 0.26, 0.30),
)
"""Link colours (rgb in [0, 1]): the Unimate's grey castings, a darker wrist."""


Shape = Literal["cylinder", "box", "sphere"]


@dataclass(frozen=True)
class LinkVisual:
    """One simple solid of the robot's picture, rigidly attached to a joint frame.

    Attributes:
        name: unique name (also the URDF visual's name).
        joint: index into :meth:`Puma560.joint_frames` (0 = base, i = DH frame i).
        shape: ``"cylinder"`` (axis along the solid's own z, centred on its origin),
            ``"box"`` (centred) or ``"sphere"``.
        dimensions: cylinder (radius, length); box (x, y, z) full sizes; sphere (radius,); in m.
        offset: 4x4 pose of the solid in the joint frame.
        rgb: colour, three floats in [0, 1].
    """

    name: str
    joint: int
    shape: Shape
    dimensions: tuple[float, ...]
    offset: np.ndarray = field(repr=False)
    rgb: tuple[float, float, float]


@dataclass(frozen=True)
class LinkMesh:
    """A mesh file drawn in one DH frame (0 = base, i = DH frame i), as a URDF names it."""

    joint: int
    filename: str
    rgb: tuple[float, float, float]


def puma560_link_meshes() -> tuple[LinkMesh, ...]:
    """The ``rtb-data`` link meshes, each in its DH frame, as ``package://rtbdata/...`` files."""
    return tuple(
        LinkMesh(j, f"package://rtbdata/{PUMA_MESH_DIR}/link{j}.stl", rgb)
        for j, rgb in enumerate(PUMA_LINK_COLORS)
    )


# ------------------------------------------------------------------------------------- URDF

#: Values smaller than this are float noise of composed rotations (cos(pi/2) = 6e-17), written 0.
_NOISE = 1e-15


def _num(value: float) -> str:
    """Shortest text that reads back to the same float (float noise written as 0)."""
    return "0" if abs(value) < _NOISE else repr(float(value))


def _origin(pose: np.ndarray) -> str:
    """A URDF ``<origin>`` element for a 4x4 pose (rpy is fixed-axis x, y, z)."""
    import pinocchio as pin

    xyz = " ".join(_num(v) for v in pose[:3, 3])
    rpy = " ".join(_num(v) for v in pin.rpy.matrixToRpy(pose[:3, :3]))
    return f'<origin xyz="{xyz}" rpy="{rpy}"/>'


def _geometry(visual: LinkVisual) -> str:
    dims = visual.dimensions
    if visual.shape == "cylinder":
        return f'<cylinder radius="{_num(dims[0])}" length="{_num(dims[1])}"/>'
    if visual.shape == "box":
        return f'<box size="{" ".join(_num(v) for v in dims)}"/>'
    return f'<sphere radius="{_num(dims[0])}"/>'


def _quoted(text: str) -> str:
    """``text`` as a quoted XML attribute value."""
    from xml.sax.saxutils import quoteattr

    return quoteattr(text)


def _shape(name: str, origin: str, geometry: str, rgb: Sequence[float]) -> list[str]:
    """A ``<visual>`` of ``geometry`` in ``rgb`` and its ``<collision>`` twin."""
    rgba = " ".join(_num(v) for v in (*rgb, 1.0))
    return [
        f"    <visual name={_quoted(name)}>",
        f"      {origin}",
        f"      <geometry>{geometry}</geometry>",
        f'      <material name={_quoted(name + "_colour")}><color rgba="{rgba}"/></material>',
        "    </visual>",
        f"    <collision name={_quoted(name)}>",
        f"      {origin}",
        f"      <geometry>{geometry}</geometry>",
        "    </collision>",
    ]


def _link(
    name: str,
    visuals: Sequence[LinkVisual],
    meshes: Sequence[LinkMesh],
    linkMjoint: np.ndarray,
) -> list[str]:
    """A link whose frame holds its DH frame at ``linkMjoint``, with its solids or meshes."""
    lines = [f'  <link name="{name}">']
    for visual in visuals:
        origin = _origin(linkMjoint @ visual.offset)
        lines += _shape(visual.name, origin, _geometry(visual), visual.rgb)
    for mesh in meshes:
        geometry = f"<mesh filename={_quoted(mesh.filename)}/>"
        lines += _shape(f"{name}_mesh", _origin(linkMjoint), geometry, mesh.rgb)
    return [*lines, "  </link>"]


def urdf_from_dh(
    dh: Sequence[DHRow],
    visuals: Sequence[LinkVisual] = (),
    meshes: Sequence[LinkMesh] = (),
) -> str:
    """The URDF text of a standard-DH arm: links ``base_link``, ``link1``..``linkN``, ``tool``;
    joints ``joint1``..``jointN`` (revolute, with the DH table's position, speed and torque
    limits) and ``tool_joint`` (fixed).

    Args:
        dh: the DH rows, joint 1 first.
        visuals: simple solids, each attached to a joint frame (0 = base, i = DH frame i): each
            is both a visual and a collision shape.
        meshes: mesh files, each attached to a DH frame likewise: each is both a visual and a
            collision shape.

    Returns:
        A complete URDF document.
    """
    import numpy as np

    frames = range(len(dh) + 1)
    on = [[v for v in visuals if v.joint == i] for i in frames]
    drawn = [[m for m in meshes if m.joint == i] for i in frames]
    lines = [
        '<?xml version="1.0"?>',
        "<!-- Puma560, Corke's standard DH model, generated by Teach Studio. Speed limits: Corke"
        " 1996, Table 2.21; torque limits: Armstrong, Khatib & Burdick 1986, Table 7. -->",
        '<robot name="puma560">',
    ]
    lines += _link("base_link", on[0], drawn[0], np.eye(4))
    parent = "base_link"
    previous = np.eye(4)  # the previous DH row's fixed part: where joint i sits in its parent
    for i, row in enumerate(dh, start=1):
        child = f"link{i}"
        lines += [
            f'  <joint name="joint{i}" type="revolute">',
            f'    <parent link="{parent}"/>',
            f'    <child link="{child}"/>',
            f"    {_origin(previous)}",
            '    <axis xyz="0 0 1"/>',
            f'    <limit lower="{_num(row.lower)}" upper="{_num(row.upper)}" '
            f'effort="{_num(row.effort)}" velocity="{_num(row.velocity)}"/>',
            "  </joint>",
        ]
        previous = row.fixed().homogeneous
        lines += _link(child, on[i], drawn[i], previous)
        parent = child
    lines += [
        '  <joint name="tool_joint" type="fixed">',
        f'    <parent link="{parent}"/>',
        '    <child link="tool"/>',
        f"    {_origin(previous)}",
        "  </joint>",
        '  <link name="tool"/>',
        "</robot>",
        "",
    ]
    return "\n".join(lines)


def puma560_urdf() -> str:
    """The Puma560's URDF as the robot registry loads it: :data:`DH_TABLE`'s joints and limits,
    and the ``rtb-data`` link meshes as visual and collision geometry (``package://rtbdata``)."""
    return urdf_from_dh(DH_TABLE, meshes=puma560_link_meshes())
