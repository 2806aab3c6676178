"""The operator's body at one live pose, with the tape laid on the taped arm's sleeve.

The fit models the tape along the arm's bones; drawn there it would hide inside the arm's mesh.
:func:`tape_on_sleeve` lifts every tape point closer to the upper arm's (forearm's) axis than a
sleeve's radius out onto it, radially; points away from the arm (on the back) stay.
:func:`pose_body` does one forward-kinematics pass per pose for both the meshes and the tape's
sleeve, so a viewer only places what it is given.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._meshes import HumanBody

SLEEVE_LIFT_M = (0.055, 0.045)
"""How far the tape lies from the upper arm's and the forearm's axis (m): on the sleeve, where
it is strapped, rather than inside the arm's mesh."""
SLEEVE_ROUNDS = 3
"""Rounds of pushing tape points off the arm's segments: a point pushed off one segment near
the elbow may land inside the other, and a few rounds settle it."""
ARM_LINKS = ("upperarm", "lowerarm", "hand")
"""The ``human.urdf`` links whose origins (shoulder, elbow, wrist) make the sleeve's axis."""


@dataclass(frozen=True, eq=False)
class PosedBody:
    """The operator's meshes and tape at one pose, in the taped arm's base frame.

    Attributes:
        parts: ``(len(body.parts), 4, 4)`` pose of every mesh.
        tape: ``(N, 3)`` tape points on the sleeve (m), or None without a tape.
    """

    parts: np.ndarray
    tape: np.ndarray | None


def tape_on_sleeve(
    tape: np.ndarray,
    axis: np.ndarray,
    lift_m: tuple[float, float] = SLEEVE_LIFT_M,
    rounds: int = SLEEVE_ROUNDS,
) -> np.ndarray:
    """Tape points lifted off the arm's axis onto its surface.

    Args:
        tape: ``(N, 3)`` tape points (m).
        axis: ``(3, 3)`` shoulder, elbow and wrist positions (m), in the tape's frame.
        lift_m: the sleeve's radius around the upper arm and around the forearm (m).
        rounds: passes over both segments.

    Returns:
        ``(N, 3)``: each point closer to a segment than its ``lift_m`` pushed out radially to
        that distance (a point on the axis itself goes to any side); the others unchanged.
    """
    axis = np.asarray(axis, dtype=float)
    out = np.array(tape, dtype=float)
    for _ in range(rounds):  # all points at once: this runs for every live pose shown
        for k, (a, b, lift) in enumerate(zip(axis[:-1], axis[1:], lift_m, strict=True)):
            ab = b - a
            along = (out - a) @ ab / (ab @ ab)
            t = np.clip(along, 0.0, 1.0)
            c = a + t[:, None] * ab
            away = out - c
            d = np.linalg.norm(away, axis=1)
            # Past the elbow, a point is the other segment's: pushed out of this one's end, a
            # point on the axis would go along it, then across the other, twice as far.
            beyond_elbow = (along > 1.0) if k == 0 else (along < 0.0)
            inside = (d < lift) & ~beyond_elbow
            if not inside.any():
                continue
            on_axis = inside & (d <= 1e-9)
            if on_axis.any():  # any direction across the axis
                across = np.cross(ab, np.eye(3)[int(np.argmin(np.abs(ab)))])
                away[on_axis] = across
                d[on_axis] = np.linalg.norm(across)
            out[inside] = c[inside] + away[inside] / d[inside, None] * lift
    return out


def sleeve_axis(body: HumanBody, parts: np.ndarray) -> np.ndarray:
    """The taped arm's shoulder, elbow and wrist ``(3, 3)`` from the mesh poses ``parts``
    (each arm link carries a mesh, posed at the link's frame)."""
    frames = [part.frame for part in body.parts]
    return np.stack([parts[frames.index(f"{body.side}_{link}"), :3, 3] for link in ARM_LINKS])


def pose_body(
    body: HumanBody,
    q_human: np.ndarray | None,
    tape: np.ndarray | None = None,
    lift_m: tuple[float, float] = SLEEVE_LIFT_M,
) -> PosedBody:
    """The body's meshes with the taped arm at ``q_human`` and ``tape`` on its sleeve, from one
    forward-kinematics pass.

    Args:
        body: the operator's meshes; ``body.side`` is the taped arm.
        q_human: the taped arm's seven joints (rad), or None for the neutral pose.
        tape: ``(N, 3)`` tape points in the arm base frame (m), or None.
        lift_m: the sleeve's radius around the upper arm and the forearm (m).
    """
    parts = body.poses(q_human)
    if tape is None or len(tape) < 2:
        return PosedBody(parts, None)
    return PosedBody(parts, tape_on_sleeve(tape, sleeve_axis(body, parts), lift_m))
