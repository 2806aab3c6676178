"""Learning engine: tabular MDPs, Dyna-Q with four planners, the arm grid task, policy files.

The public names (see ``docs/architecture.md`` and this package's ``README.md``)::

    from studio.learning import ArmGrid, DynaQConfig, run_experiments

    grid = ArmGrid()  # the paper's 3 joints x 11 bins, 27 actions
    result = run_experiments(grid.mdp(), DynaQConfig(planning="full"), experiments=20, episodes=100, seed=0)
    result.mean_steps()  # the learning curve

Subpackages by responsibility: ``tasks`` (what is learned), ``tabular``, ``linear`` and
``primitives`` (the learners, each behind the one ``Learner`` interface, registered by kind:
``learner_of(policy).roll_out(policy, Start(seed=0), 50.0)``), ``likeness``, ``runs``, ``sweeps``
and ``paper``. Import every public name from here.
"""

from __future__ import annotations

import typing

from .. import _lazy
from .tasks._gym_ids import register_when_imported as _register_environments

if typing.TYPE_CHECKING:  # the public names, each loaded when first used (see studio/_lazy.py)
    from ._config import ACTION_SETS as ACTION_SETS
    from ._config import CLONING_KIND as CLONING_KIND
    from ._config import DEFAULT_EPISODES as DEFAULT_EPISODES
    from ._config import DEFAULT_EXPERIMENTS as DEFAULT_EXPERIMENTS
    from ._config import DEFAULT_SEED as DEFAULT_SEED
    from ._config import DEFAULT_SHAPING as DEFAULT_SHAPING
    from ._config import DEMO_SHAPING as DEMO_SHAPING
    from ._config import GRID_DEFAULTS as GRID_DEFAULTS
    from ._config import MAX_EPISODE_RUNS as MAX_EPISODE_RUNS
    from ._config import MAX_EPISODES as MAX_EPISODES
    from ._config import MAX_EXPERIMENTS as MAX_EXPERIMENTS
    from ._config import OWN_LEARNER as OWN_LEARNER
    from ._config import PLANNERS as PLANNERS
    from ._config import REACH_DEFAULTS as REACH_DEFAULTS
    from ._config import ROLLOUT_MAX_STEPS as ROLLOUT_MAX_STEPS
    from ._config import ROLLOUT_RATE_HZ as ROLLOUT_RATE_HZ
    from ._config import ROLLOUT_SECONDS_PER_STEP as ROLLOUT_SECONDS_PER_STEP
    from ._config import TASK_KINDS as TASK_KINDS
    from ._config import TEACHER_KIND as TEACHER_KIND
    from ._config import TILE_ROLLOUT_MAX_STEPS as TILE_ROLLOUT_MAX_STEPS
    from ._config import TILE_ROLLOUT_SECONDS_PER_STEP as TILE_ROLLOUT_SECONDS_PER_STEP
    from ._config import DynaQConfig as DynaQConfig
    from ._config import check_budget as check_budget
    from ._errors import ConfigError as ConfigError
    from ._errors import LearningError as LearningError
    from ._errors import PolicyFileError as PolicyFileError
    from ._evaluate import evaluate_policy as evaluate_policy
    from ._experiments import run_experiments as run_experiments
    from ._interface import Evaluation as Evaluation
    from ._interface import Learner as Learner
    from ._interface import Rollout as Rollout
    from ._interface import Start as Start
    from ._learner import LiveProgress as LiveProgress
    from ._prepare import prepare_in_background as prepare_in_background
    from ._registry import AnyPolicy as AnyPolicy
    from ._registry import learner as learner
    from ._registry import learner_of as learner_of
    from ._registry import load_any_policy as load_any_policy
    from ._registry import register_learner as register_learner
    from ._tiles import TileCoding as TileCoding
    from .likeness._likeness import LikenessCard as LikenessCard
    from .likeness._likeness import dtw_distance as dtw_distance
    from .likeness._likeness import frechet_distance as frechet_distance
    from .likeness._likeness import ldlj as ldlj
    from .likeness._likeness import likeness_card as likeness_card
    from .likeness._likeness import puma_tool_positions as puma_tool_positions
    from .likeness._likeness import sparc as sparc
    from .likeness._policy import policy_likeness_card as policy_likeness_card
    from .likeness._run import likeness_cards as likeness_cards
    from .linear._learner import FORM_ACTIONS as FORM_ACTIONS
    from .linear._linear import greedy_rollout as greedy_rollout
    from .linear._policy import TilePolicyFile as TilePolicyFile
    from .linear._policy import demonstrated_pace as demonstrated_pace
    from .linear._policy import rollout_tile_policy as rollout_tile_policy
    from .paper._reproduce import generate_demonstrations as generate_demonstrations
    from .paper._reproduce import reproduce as reproduce
    from .primitives._dmp import DMP_BASIS as DMP_BASIS
    from .primitives._dmp import fit_movement_primitive as fit_movement_primitive
    from .primitives._dmp import roll_out_primitive as roll_out_primitive
    from .primitives._policy import DmpPolicyFile as DmpPolicyFile
    from .primitives._policy import dmp_likeness_card as dmp_likeness_card
    from .primitives._policy import fit_dmp_policy as fit_dmp_policy
    from .primitives._policy import load_dmp_policy as load_dmp_policy
    from .primitives._policy import rollout_dmp_policy as rollout_dmp_policy
    from .primitives._policy import save_dmp_policy as save_dmp_policy
    from .runs._curves import FIGURE_POINTS as FIGURE_POINTS
    from .runs._curves import curve_figure as curve_figure
    from .runs._curves import curve_plot as curve_plot
    from .runs._curves import curve_statistics as curve_statistics
    from .runs._curves import curves_csv as curves_csv
    from .runs._curves import downsample_curve as downsample_curve
    from .runs._curves import write_curves_csv as write_curves_csv
    from .runs._folder import RunFolder as RunFolder
    from .runs._folder import delete_run_folder as delete_run_folder
    from .runs._folder import find_runs as find_runs
    from .runs._live_curve import LiveCurve as LiveCurve
    from .runs._notes import RunBusyError as RunBusyError
    from .runs._notes import RunNotes as RunNotes
    from .runs._notes import RunNotesError as RunNotesError
    from .runs._notes import read_run_notes as read_run_notes
    from .runs._notes import write_run_notes as write_run_notes
    from .runs._record import RunRecord as RunRecord
    from .runs._request import DemonstrationPath as DemonstrationPath
    from .runs._request import RunRequest as RunRequest
    from .runs._request import resolve_run as resolve_run
    from .runs._request import without_demonstrations as without_demonstrations
    from .runs._summary import POLICY_SUFFIX as POLICY_SUFFIX
    from .runs._summary import goal_degrees as goal_degrees
    from .runs._summary import has_default_goal as has_default_goal
    from .runs._summary import policy_summary as policy_summary
    from .sweeps._list import SweepInfo as SweepInfo
    from .sweeps._list import list_sweeps as list_sweeps
    from .sweeps._list import load_sweep as load_sweep
    from .sweeps._list import resume_target as resume_target
    from .sweeps._ray import SweepProgress as SweepProgress
    from .sweeps._ray import run_sweep as run_sweep
    from .sweeps._spec import SweepError as SweepError
    from .sweeps._spec import SweepSpec as SweepSpec
    from .sweeps._spec import load_sweep_spec as load_sweep_spec
    from .tabular._dynaq import warm_up as warm_up
    from .tabular._policy import PolicyFile as PolicyFile
    from .tabular._policy import greedy_path as greedy_path
    from .tabular._policy import load_policy as load_policy
    from .tabular._policy import rollout as rollout
    from .tabular._policy import save_trajectory_csv as save_trajectory_csv
    from .tasks._arm import MAX_TABLE_ENTRIES as MAX_TABLE_ENTRIES
    from .tasks._arm import ArmGrid as ArmGrid
    from .tasks._demo_motion import DemonstrationMotion as DemonstrationMotion
    from .tasks._demo_motion import motion_problem as motion_problem
    from .tasks._goal import DEFAULT_GOAL_JOINTS_DEG as DEFAULT_GOAL_JOINTS_DEG
    from .tasks._goal import check_goal_deg as check_goal_deg
    from .tasks._goal import default_goal_deg as default_goal_deg
    from .tasks._goal import goal_pose as goal_pose
    from .tasks._goal import grid_for_goal as grid_for_goal
    from .tasks._mdp import TabularMDP as TabularMDP
    from .tasks._obstacles import obstacle_guard as obstacle_guard
    from .tasks._obstacles import policy_obstacles as policy_obstacles
    from .tasks._reach import ArmReach as ArmReach
    from .tasks._robot import DEFAULT_GOAL_DEG as DEFAULT_GOAL_DEG
    from .tasks._robot import check_policy_robot as check_policy_robot
    from .tasks._robot import default_goal as default_goal

__getattr__, __dir__, __all__ = _lazy.lazy_exports(__name__, __file__)
_register_environments()  # "TeachStudio/ArmGrid-v0" and "TeachStudio/ArmReach-v0", once Gymnasium loads
