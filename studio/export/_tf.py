"""Every link's transform from its parent link, per sample: what ``/tf`` carries in an MCAP file,
so that Foxglove draws the robot from ``/robot_description`` moving, with no other file.

The links and their parents come from the robot's Pinocchio model itself (each body frame hangs
from a joint frame, which hangs from its parent body), so fixed joints (a hand, a flange, a tool
point) are included exactly as the URDF has them, and nothing is parsed twice.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin


@dataclass(frozen=True)
class LinkTransforms:
    """The transforms of a robot's links over a motion.

    Attributes:
        root: the root link (the URDF's base), the frame every other link hangs from.
        edges: ``(parent link, child link)`` for each transform, in the model's order.
        translation: (N, E, 3) metres, child origin in the parent's frame, per sample.
        rotation: (N, E, 4) quaternions ``x, y, z, w``, per sample.
    """

    root: str
    edges: tuple[tuple[str, str], ...]
    translation: np.ndarray
    rotation: np.ndarray


def _edges(model: pin.Model) -> tuple[str, list[tuple[int, int]]]:
    """The root link's name and each ``(parent body frame, child body frame)`` pair."""
    frames = model.frames
    bodies = [i for i, f in enumerate(frames) if f.type == pin.FrameType.BODY]
    pairs = []
    root = ""
    for child in bodies:
        joint = frames[child].parentFrame
        parent = frames[joint].parentFrame
        if frames[parent].type != pin.FrameType.BODY or parent == child:
            root = root or frames[child].name  # hangs from the universe: the URDF's base
            continue
        pairs.append((parent, child))
    return root or frames[0].name, pairs


def link_transforms(model: pin.Model, q: np.ndarray) -> LinkTransforms:
    """Each link's pose in its parent link's frame at every row of ``q`` (N, model.nq)."""
    data = model.createData()
    root, pairs = _edges(model)
    rows = np.atleast_2d(np.asarray(q, dtype=float))
    translation = np.empty((len(rows), len(pairs), 3))
    rotation = np.empty((len(rows), len(pairs), 4))
    for n, row in enumerate(rows):
        pin.framesForwardKinematics(model, data, row)
        for e, (parent, child) in enumerate(pairs):
            parentMchild = data.oMf[parent].actInv(data.oMf[child])
            translation[n, e] = parentMchild.translation
            rotation[n, e] = pin.Quaternion(parentMchild.rotation).coeffs()  # x, y, z, w
    names = tuple((model.frames[p].name, model.frames[c].name) for p, c in pairs)
    return LinkTransforms(root, names, translation, rotation)
