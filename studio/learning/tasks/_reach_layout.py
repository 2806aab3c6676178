"""The flat float64 parameter array the arm task's compiled functions take: its layout.

One definition for :mod:`._reach` (the task, its dynamics and forward kinematics) and
:mod:`._follow` (the follow action), which both read it; and the rows of its action table
(:func:`action_directions`).
"""

import itertools

import numpy as np

MAX_JOINTS = 6
"""Most joints a task learns (the first six of a seven-joint arm such as the Panda)."""
MAX_CHAIN = 7
"""Most joints of an arm whose forward kinematics the compiled twin computes."""

# layout of the flat float64 parameter array the compiled functions take
_J, _STEP, _POS_TOL2, _MIN_TRACE = 0, 1, 2, 3
_GOAL_P = 4  # 3 values
_GOAL_R = 7  # 9 values, row-major
_LOWER = 16  # MAX_JOINTS values
_UPPER = 22
# 28-45: free (the Puma560's DH table was here; every arm's forward kinematics is its chain now)
_SHAPING = 46
_POS_TOL = 47
_ANG_TOL = 48
_MULTI = 49  # 0: one joint per action (the fast path), else the table below
_CHAIN_N = 50  # the serial chain's joints that move the tool
_HOLD = 51  # MAX_CHAIN values: every joint's angle when not learned (the goal's)
_CHAIN = _HOLD + MAX_CHAIN  # per joint: placement rotation (9, row-major), translation, axis
_LINK = 15
_TOOL = _CHAIN + _LINK * MAX_CHAIN  # jointMtool: rotation (9, row-major), translation (3)
_FRAMES_N = _TOOL + 12  # the chain's joints, written for every robot (the obstacle check's frames)
_N_BOXES = _TOOL + 13  # obstacles: how many boxes (0: none, no check)
_N_SPHERES = _TOOL + 14  # how many spheres hold the links
_OBST = _TOOL + 15  # where the boxes, then the spheres, start in the array
_SWEEP = _TOOL + 16  # a bound on any link point's distance from any joint axis (m)
_COUNTS = _TOOL + 17  # the action table's rows, then the followed paths' points
_TABLE = _COUNTS + 2  # per action, MAX_JOINTS directions -1/0/+1; then the followed points
_N_PARAMS = _TABLE
_POINT = MAX_JOINTS + 2  # a followed point: its joints, its path's last point, the path left (rad)
_BOX = 6  # an obstacle: its centre, then its half sizes (m)
_SPHERE = 5  # a sphere: its joint (1 = the first), its centre in that joint's frame, its radius


def action_directions(joints: int, actions: str = "single") -> np.ndarray:
    """The moves of action set ``actions`` over ``joints`` joints: int8 ``(n, joints)``, -1/0/+1.

    Singles first (joint 1 up, joint 1 down, joint 2 up, ...), then with ``"pairs"`` or ``"all"``
    each pair of joints ``j < k`` as (+, +), (+, -), (-, +), (-, -), then with ``"all"`` the
    moves of three or more joints (in ``itertools.product((1, 0, -1), repeat=joints)`` order).
    ``"all-follow"``'s table is ``"all"``'s (its follow action comes after the table).
    """
    if actions == "all-follow":
        actions = "all"
    rows: list[tuple[int, ...]] = []
    for j in range(joints):
        for d in (1, -1):
            rows.append(tuple(d if i == j else 0 for i in range(joints)))
    if actions in ("pairs", "all"):
        for j, k in itertools.combinations(range(joints), 2):
            for dj, dk in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
                rows.append(tuple(dj if i == j else dk if i == k else 0 for i in range(joints)))
    if actions == "all":
        rows += [m for m in itertools.product((1, 0, -1), repeat=joints) if sum(map(abs, m)) > 2]
    return np.array(rows, dtype=np.int8).reshape(-1, joints)
