"""Exports: a policy, a demonstration or a recording as a robot's joint trajectory, checked for
safety, in the formats robot people use (CSV, MCAP with ROS 2 messages, LeRobotDataset v3.0), and
a robot's URDF with its meshes.

The public names are listed in ``docs/architecture.md``; the formats in ``studio/export/README.md``.
"""

import typing

from .. import _lazy

if typing.TYPE_CHECKING:  # the public names, each loaded when first used (see studio/_lazy.py)
    # a recorded motion on a robot has its home in studio.motion; the names stay here for scripts
    from studio.motion import Finding as Finding
    from studio.motion import Motion as Motion
    from studio.motion import demonstration_motion as demonstration_motion
    from studio.motion import recording_motion as recording_motion
    from studio.motion import series_motion as series_motion
    from studio.motion import training_demonstration as training_demonstration

    from ._choices import FORMAT_SUFFIXES as FORMAT_SUFFIXES
    from ._choices import FORMATS as FORMATS
    from ._choices import LIMIT_FRACTION as LIMIT_FRACTION
    from ._errors import ExportError as ExportError
    from ._errors import SafetyError as SafetyError
    from ._export import Exported as Exported
    from ._export import export_motion as export_motion
    from ._export import fit_timing as fit_timing
    from ._export import simulate_motion as simulate_motion
    from ._formats import DESCRIPTION_TOPIC as DESCRIPTION_TOPIC
    from ._formats import JOINT_STATE as JOINT_STATE
    from ._formats import JOINT_TRAJECTORY as JOINT_TRAJECTORY
    from ._formats import STATE_TOPIC as STATE_TOPIC
    from ._formats import TF_TOPIC as TF_TOPIC
    from ._formats import TRAJECTORY_TOPIC as TRAJECTORY_TOPIC
    from ._formats import write_csv as write_csv
    from ._formats import write_mcap as write_mcap
    from ._lerobot import CODEBASE_VERSION as CODEBASE_VERSION
    from ._lerobot import LeRobotConventions as LeRobotConventions
    from ._lerobot import lerobot_conventions as lerobot_conventions
    from ._lerobot import write_lerobot as write_lerobot
    from ._likeness import demonstration_of as demonstration_of
    from ._likeness import likeness_motions as likeness_motions
    from ._read import Trajectory as Trajectory
    from ._read import read_trajectory as read_trajectory
    from ._safety import COLLISION_MARGIN_M as COLLISION_MARGIN_M
    from ._safety import check_trajectory as check_trajectory
    from ._simulate import physics_model as physics_model
    from ._simulate import simulate_trajectory as simulate_trajectory
    from ._sources import check_policy_robot as check_policy_robot
    from ._sources import find_source as find_source
    from ._sources import source_kind as source_kind
    from ._tf import LinkTransforms as LinkTransforms
    from ._tf import link_transforms as link_transforms
    from ._timing import time_path as time_path
    from ._urdf import export_urdf as export_urdf
    from ._urdf import portable_urdf as portable_urdf

__getattr__, __dir__, __all__ = _lazy.lazy_exports(__name__, __file__)
