"""What a Puma560 is built from: standard-DH rows and the simple solids that picture its links.

A leaf module: the model (:mod:`._puma`) and its URDF (:mod:`._urdf`) both read these
descriptions, and neither imports the other's internals through here, so the dependency runs one
way (``_puma -> _urdf -> _dh``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import pinocchio as pin


@dataclass(frozen=True)
class DHRow:
    """One row of a standard-DH table: ``Rz(q) Tz(d) Tx(a) Rx(alpha)``, a revolute joint.

    Attributes:
        d: offset along the previous z axis (m).
        a: length along the new x axis (m).
        alpha: twist about the new x axis (rad).
        lower: lower joint limit (rad).
        upper: upper joint limit (rad).
    """

    d: float
    a: float
    alpha: float
    lower: float
    upper: float

    def fixed(self) -> pin.SE3:
        """The joint-independent part ``Tz(d) Tx(a) Rx(alpha)`` of this row."""
        c, s = math.cos(self.alpha), math.sin(self.alpha)
        rotation = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
        return pin.SE3(rotation, np.array([self.a, 0.0, self.d]))


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
