"""The compiled forward kinematics of the arm task: a serial chain's joint (its placement and
rotation) and every joint's frame, from the flat parameter array (:mod:`._reach_layout`), and
writing a robot's chain into that array.

:func:`._reach.tool_pose` composes it up to the tool frame; the obstacle check
(:mod:`._obstacles`) needs the frame of every joint, to place the spheres that hold the links.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._errors import ConfigError
from ._reach_layout import (
    _CHAIN,
    _CHAIN_N,
    _FRAMES_N,
    _HOLD,
    _J,
    _LINK,
    _TOOL,
    MAX_CHAIN,
)
from ._robot import task_arm


@njit(nogil=True, cache=True, inline="always")
def compose(out, values, base):
    """``out = out @ M`` with ``M``'s rotation row-major at ``values[base:base + 9]`` and its
    translation at ``values[base + 9:base + 12]``."""
    for r in range(3):
        x, y, z = out[r, 0], out[r, 1], out[r, 2]
        for c in range(3):
            out[r, c] = x * values[base + c] + y * values[base + 3 + c] + z * values[base + 6 + c]
        out[r, 3] += x * values[base + 9] + y * values[base + 10] + z * values[base + 11]


@njit(nogil=True, cache=True)
def chain_joint(out, params, state, i, rotation):
    """``out = out @ jointPlacement_i @ R(axis_i, q_i)``: joint ``i``'s fixed placement, then the
    rotation by its angle about its axis (Rodrigues); ``q_i`` from ``state`` for a learned
    joint, else the held goal angle. ``rotation`` is scratch space of 12 floats."""
    base = _CHAIN + _LINK * i
    compose(out, params, base)
    theta = state[i] if i < int(params[_J]) else params[_HOLD + i]
    c, s = math.cos(theta), math.sin(theta)
    ux, uy, uz = params[base + 12], params[base + 13], params[base + 14]
    t = 1.0 - c
    rotation[0] = c + t * ux * ux
    rotation[1] = t * ux * uy - s * uz
    rotation[2] = t * ux * uz + s * uy
    rotation[3] = t * ux * uy + s * uz
    rotation[4] = c + t * uy * uy
    rotation[5] = t * uy * uz - s * ux
    rotation[6] = t * ux * uz - s * uy
    rotation[7] = t * uy * uz + s * ux
    rotation[8] = c + t * uz * uz
    rotation[9] = rotation[10] = rotation[11] = 0.0
    compose(out, rotation, 0)


@njit(nogil=True, cache=True)
def chain_frames(params, state, pose, rotation, frames):
    """Every joint's frame ``oMi`` (Pinocchio's, joint 1 first) into ``frames`` ``(n, 4, 4)``
    (``pose``: 4x4 scratch, ``rotation``: 12 floats of scratch)."""
    for r in range(4):
        for c in range(4):
            pose[r, c] = 1.0 if r == c else 0.0
    for i in range(int(params[_FRAMES_N])):
        chain_joint(pose, params, state, i, rotation)
        frames[i] = pose


def put_chain(p: np.ndarray, robot: str) -> None:
    """Write ``robot``'s serial chain (:attr:`studio.kinematics.RobotArm.chain`, the one reading
    of its Pinocchio model, which the compiled IK also runs on) into the parameter array ``p``:
    the tool pose's forward kinematics, and every joint's frame for the obstacle check."""
    chain = task_arm(robot).chain
    moving = chain.tool_joint + 1  # the joints, from the first, that move the tool
    if moving > MAX_CHAIN or moving < 1:
        raise ConfigError(
            [f"The {robot} moves its tool with {moving} joints; give an arm of 1 to {MAX_CHAIN}."],
            ["robot"],
        )
    frames = min(MAX_CHAIN, len(chain.translations))
    p[_CHAIN_N] = moving
    p[_FRAMES_N] = frames
    for i in range(frames):
        link = p[_CHAIN + _LINK * i : _CHAIN + _LINK * (i + 1)]
        link[:9] = chain.rotations[i].reshape(-1)
        link[9:12] = chain.translations[i]
        link[12:] = chain.axes[i]
    p[_TOOL : _TOOL + 9] = chain.tool_rotation.reshape(-1)
    p[_TOOL + 9 : _TOOL + 12] = chain.tool_translation
