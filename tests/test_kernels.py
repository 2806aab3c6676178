"""Every compiled kernel is compiled for one signature (``studio/_kernels.py``).

numba compiles a kernel again for each new combination of argument types, read-only arrays and
literal constants included: a second signature costs seconds to tens of seconds of CPU on a
machine's first run, in every process that meets it before numba's disk cache holds it, and it
is a compile the studio's preparation at start-up never covers. The forms that compiled a second
signature before are each taken here, in a fresh interpreter, after the preparation (which runs a
learner with and without a demonstration, a rollout and an evaluation).

A kernel called from Python lists each signature it was called with, loaded from the disk cache
or compiled. A kernel called only from other kernels lists one only where it was compiled in this
process: a second signature of those (a literal constant passed in, as ``reach_step(..., -1)``
once was) shows only where they compile here, with a cold cache (this file alone with ``-n 0``
on a fresh clone; the whole suite prepares them before its workers start).
"""

from __future__ import annotations

import subprocess
import sys

SCRIPT = r"""
import sys

import numpy as np
from numba.core.registry import CPUDispatcher

from studio.kinematics import load_robot
from studio.kinematics._robot_load import prepare_arm_ik
from studio.kinematics.human._tape import TapeConfig, reconstruct
from studio.learning import ArmReach
from studio.learning._prepare import _warm
from studio.learning.tasks._reach import tool_positions

_warm("arm-reach")
prepare_arm_ik()

arm = load_robot("puma560", geometry=False)
q = np.array(arm.home) + 0.1  # writable
arm.forward(arm.home)  # read-only joints
arm.forward(q)
arm.inverse(arm.forward(q), arm.home)  # the robot's (read-only) limits
arm.inverse(arm.forward(q), q, lower=q - 0.2, upper=q + 0.2)  # computed (writable) bounds

config = TapeConfig()
bend = np.full(config.regions, 0.01)
reconstruct(bend, bend, config)
bend.flags.writeable = False
reconstruct(bend, bend, config)

task = ArmReach(joints=3)
goal = np.asarray(task.goal[:3])
path = np.linspace(goal + np.radians([30.0, -30.0, 30.0]), goal, 40)
task.demonstration_actions(path)  # the demonstration's walk over the action table
tool_positions("puma560", np.zeros((2, 6)))  # a copy of a task's parameters

twice = []
for name, module in list(sys.modules.items()):
    if name == "studio" or name.startswith("studio."):
        for attr, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and len(value.signatures) > 1:
                twice.append(f"{name}.{attr}: " + " | ".join(map(str, value.signatures)))
print("\n".join(sorted(set(twice))) or "one each")
"""


def test_every_kernel_is_compiled_for_one_signature() -> None:
    out = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=900, check=False
    )
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.strip() == "one each", out.stdout
