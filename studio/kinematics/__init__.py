"""Kinematics: Puma560 and human-arm models, tape and pose-landmark fitting, retargeting.

The public names are listed in ``docs/architecture.md``.
"""

import typing

from .. import _lazy

if typing.TYPE_CHECKING:  # the public names, each loaded when first used (see studio/_lazy.py)
    from ._checks import KinematicsError as KinematicsError
    from ._checks import Obstacle as Obstacle
    from ._checks import check_obstacles as check_obstacles
    from ._clearance import OBSTACLE_TOUCH_M as OBSTACLE_TOUCH_M
    from ._clearance import ObstacleGuard as ObstacleGuard
    from ._clearance import sphere_cover as sphere_cover
    from ._meshes import SLEEVE_LIFT_M as SLEEVE_LIFT_M
    from ._meshes import HumanBody as HumanBody
    from ._meshes import MeshConfig as MeshConfig
    from ._meshes import MeshPart as MeshPart
    from ._meshes import PosedBody as PosedBody
    from ._meshes import pose_body as pose_body
    from ._meshes import puma560_meshes as puma560_meshes
    from ._meshes import robot_meshes as robot_meshes
    from ._puma import IKConfig as IKConfig
    from ._puma import Puma560 as Puma560
    from ._retarget import RetargetConfig as RetargetConfig
    from ._retarget import Retargeter as Retargeter
    from ._retarget_path import RetargetedPath as RetargetedPath
    from ._retarget_path import reachable as reachable
    from ._retarget_path import retarget_path as retarget_path
    from ._retarget_path import tool_reaches as tool_reaches
    from ._robot_load import isolate_robot_loading as isolate_robot_loading
    from ._robot_load import keep_robot_geometry as keep_robot_geometry
    from ._robot_load import load_robot as load_robot
    from ._robot_load import prepare_arm_ik_in_background as prepare_arm_ik_in_background
    from ._robot_load import robot_cache_folder as robot_cache_folder
    from ._robot_load import robot_is_kept as robot_is_kept
    from ._robot_specs import DEFAULT_ROBOT as DEFAULT_ROBOT
    from ._robot_specs import LIMIT_MARGIN_RAD as LIMIT_MARGIN_RAD
    from ._robot_specs import robot_names as robot_names
    from ._robot_specs import robot_spec as robot_spec
    from ._robots import TABLE as TABLE
    from ._robots import RobotArm as RobotArm
    from .human._fit import ArmFitter as ArmFitter
    from .human._fit import FitConfig as FitConfig
    from .human._hand_ik import HandIKConfig as HandIKConfig
    from .human._hand_ik import fit_hand_pose as fit_hand_pose
    from .human._human import HumanArm as HumanArm
    from .human._pose import PoseConfig as PoseConfig
    from .human._pose import PoseFit as PoseFit
    from .human._pose import fit_pose_landmarks as fit_pose_landmarks
    from .human._pose_stream import BodyShape as BodyShape
    from .human._pose_stream import PoseStreamFitter as PoseStreamFitter
    from .human._pose_stream import StreamConfig as StreamConfig
    from .human._pose_stream import arm_motion as arm_motion
    from .human._pose_stream import landmarks_from_arm as landmarks_from_arm
    from .human._pose_stream import smooth_landmarks as smooth_landmarks
    from .human._tape import TapeConfig as TapeConfig
    from .human._tape import reconstruct as reconstruct
    from .human._tape import tape_from_arm as tape_from_arm
    from .human._tracker import ArmTracker as ArmTracker
    from .human._tracker import TrackerConfig as TrackerConfig
    from .human._tracker import smooth_recorded_arm as smooth_recorded_arm

__getattr__, __dir__, __all__ = _lazy.lazy_exports(__name__, __file__)
