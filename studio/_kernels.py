"""The one form of an input array handed to a compiled (numba) kernel from Python.

numba compiles a kernel once per combination of argument types, and an array's type includes
whether it is read-only. The studio keeps its fixed arrays read-only (a task's parameters, a
robot's limits and home pose), and computes others afresh (writable), so one kernel called with
both compiled twice: tens of seconds of CPU on a machine's first run, in every process that met
the second form before numba's disk cache held it, and a stall the preparation at start-up
(``prepare_in_background``, ``prepare_arm_ik``) did not cover. Every input array that a kernel
only reads goes in as :func:`frozen`; arrays the kernel writes stay as they are.
"""

from __future__ import annotations

import numpy as np


def frozen(values: object) -> np.ndarray:
    """``values`` as a read-only, C-contiguous float64 array: the array itself when it is one
    already, else a read-only view of it (or of a contiguous float64 copy). The caller's array
    stays writable; the view follows later writes to it."""
    array = np.ascontiguousarray(values, dtype=np.float64)
    if array.flags.writeable:
        array = array.view()
        array.flags.writeable = False
    return array
