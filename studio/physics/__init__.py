"""Physics: a robot's joint trajectory replayed in MuJoCo on the robot's own URDF, with its
motors' force limits, gravity and the table it stands on.

:func:`mujoco_urdf` makes a URDF readable by MuJoCo, :func:`build_model` compiles it for a
:class:`~studio.kinematics.RobotArm`, :func:`simulate` replays a trajectory and gives a
:class:`SimulationReport`: whether the motion completed, the largest joint and tool tracking
errors, the samples where a motor saturates, and every contact (self, table). ``mujoco`` is
imported only when a model is built, so importing this package stays fast.
"""

from ._errors import PhysicsError as PhysicsError
from ._mjcf import mujoco_urdf as mujoco_urdf
from ._model import PhysicsModel as PhysicsModel
from ._model import build_model as build_model
from ._replay import COMPLETION_M as COMPLETION_M
from ._replay import simulate as simulate
from ._report import JSON_KEYS as JSON_KEYS
from ._report import Contact as Contact
from ._report import SimulationReport as SimulationReport
