"""The studio's 3D scene, drawn with viser: the operator and the robot taught, their paths and
goals, playbacks on the robot, the camera presets and the hand guide's handle.

The rest of the web layer holds the scene by the :class:`Scene` protocol (the live pipeline by
:class:`LiveScene`), so a test can hand in a fake and the studio runs headless with none.

Importing the package loads none of its modules (``studio/_lazy.py``), so the child process that
simplifies a robot's meshes (:mod:`._simplify`) loads only what that needs.
"""

import typing

from ... import _lazy

if typing.TYPE_CHECKING:  # the public names, each loaded when first used (see studio/_lazy.py)
    from ._model import PLAYBACK_SPEEDS as PLAYBACK_SPEEDS
    from ._model import Playback as Playback
    from ._protocols import LivePose as LivePose
    from ._protocols import LiveScene as LiveScene
    from ._protocols import Scene as Scene
    from ._robot_playback import PREVIEW_FRAMES as PREVIEW_FRAMES
    from ._robot_playback import RobotPlayer as RobotPlayer
    from ._robot_view import RobotViews as RobotViews
    from ._scene import SceneLayout as SceneLayout
    from ._scene import StudioScene as StudioScene
    from ._views import VIEW_NAMES as VIEW_NAMES

__getattr__, __dir__, __all__ = _lazy.lazy_exports(__name__, __file__)
