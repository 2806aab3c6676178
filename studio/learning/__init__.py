"""Learning engine: tabular MDPs, Dyna-Q with four planners, the arm grid task, policy files.

The public names (see ``docs/architecture.md`` and this package's ``README.md``)::

    from studio.learning import ArmGrid, DynaQConfig, run_experiments

    grid = ArmGrid()  # the paper's 3 joints x 11 bins, 27 actions
    result = run_experiments(grid.mdp(), DynaQConfig(planning="full"), experiments=20, episodes=100, seed=0)
    result.mean_steps()  # the learning curve
"""

from __future__ import annotations

from ._arm import MAX_TABLE_ENTRIES as MAX_TABLE_ENTRIES
from ._arm import ArmGrid as ArmGrid
from ._config import DEFAULT_EPISODES as DEFAULT_EPISODES
from ._config import DEFAULT_EXPERIMENTS as DEFAULT_EXPERIMENTS
from ._config import DEFAULT_SEED as DEFAULT_SEED
from ._config import MAX_EPISODE_RUNS as MAX_EPISODE_RUNS
from ._config import MAX_EPISODES as MAX_EPISODES
from ._config import MAX_EXPERIMENTS as MAX_EXPERIMENTS
from ._config import PLANNERS as PLANNERS
from ._config import DynaQConfig as DynaQConfig
from ._config import check_budget as check_budget
from ._curves import FIGURE_POINTS as FIGURE_POINTS
from ._curves import curve_figure as curve_figure
from ._curves import curve_plot as curve_plot
from ._curves import curve_statistics as curve_statistics
from ._curves import curves_csv as curves_csv
from ._curves import downsample_curve as downsample_curve
from ._curves import write_curves_csv as write_curves_csv
from ._demo_motion import DemonstrationMotion as DemonstrationMotion
from ._demo_motion import motion_problem as motion_problem
from ._dmp import DMP_BASIS as DMP_BASIS
from ._dmp import fit_movement_primitive as fit_movement_primitive
from ._dmp import roll_out_primitive as roll_out_primitive
from ._dmp_policy import DmpPolicyFile as DmpPolicyFile
from ._dmp_policy import dmp_likeness_card as dmp_likeness_card
from ._dmp_policy import fit_dmp_policy as fit_dmp_policy
from ._dmp_policy import load_dmp_policy as load_dmp_policy
from ._dmp_policy import rollout_dmp_policy as rollout_dmp_policy
from ._dmp_policy import save_dmp_policy as save_dmp_policy
from ._dynaq import warm_up as warm_up
from ._errors import ConfigError as ConfigError
from ._errors import LearningError as LearningError
from ._errors import PolicyFileError as PolicyFileError
from ._experiments import run_experiments as run_experiments
from ._goal import DEFAULT_GOAL_JOINTS_DEG as DEFAULT_GOAL_JOINTS_DEG
from ._goal import check_goal_deg as check_goal_deg
from ._goal import default_goal_deg as default_goal_deg
from ._goal import goal_pose as goal_pose
from ._goal import grid_for_goal as grid_for_goal
from ._gym import register as _register_environments
from ._learner import LiveProgress as LiveProgress
from ._likeness import LikenessCard as LikenessCard
from ._likeness import dtw_distance as dtw_distance
from ._likeness import frechet_distance as frechet_distance
from ._likeness import ldlj as ldlj
from ._likeness import likeness_card as likeness_card
from ._likeness import puma_tool_positions as puma_tool_positions
from ._likeness import sparc as sparc
from ._linear import greedy_rollout as greedy_rollout
from ._linear_policy import DEFAULT_MAX_STEPS as TILE_ROLLOUT_MAX_STEPS  # noqa: F401 (re-export)
from ._linear_policy import DEFAULT_SECONDS_PER_STEP as TILE_ROLLOUT_SECONDS_PER_STEP  # noqa: F401
from ._linear_policy import TilePolicyFile as TilePolicyFile
from ._linear_policy import demonstrated_pace as demonstrated_pace
from ._linear_policy import load_any_policy as load_any_policy
from ._linear_policy import rollout_tile_policy as rollout_tile_policy
from ._live_curve import LiveCurve as LiveCurve
from ._mdp import TabularMDP as TabularMDP
from ._policy import ROLLOUT_MAX_STEPS as ROLLOUT_MAX_STEPS
from ._policy import ROLLOUT_RATE_HZ as ROLLOUT_RATE_HZ
from ._policy import ROLLOUT_SECONDS_PER_STEP as ROLLOUT_SECONDS_PER_STEP
from ._policy import PolicyFile as PolicyFile
from ._policy import greedy_path as greedy_path
from ._policy import load_policy as load_policy
from ._policy import rollout as rollout
from ._policy import save_trajectory_csv as save_trajectory_csv
from ._policy_likeness import policy_likeness_card as policy_likeness_card
from ._prepare import prepare_in_background as prepare_in_background
from ._reach import ACTION_SETS as ACTION_SETS
from ._reach import ArmReach as ArmReach
from ._reproduce import generate_demonstrations as generate_demonstrations
from ._reproduce import reproduce as reproduce
from ._robot import DEFAULT_GOAL_DEG as DEFAULT_GOAL_DEG
from ._robot import check_policy_robot as check_policy_robot
from ._robot import default_goal as default_goal
from ._run_likeness import likeness_cards as likeness_cards
from ._run_notes import RunBusyError as RunBusyError
from ._run_notes import RunNotes as RunNotes
from ._run_notes import RunNotesError as RunNotesError
from ._run_notes import read_run_notes as read_run_notes
from ._run_notes import write_run_notes as write_run_notes
from ._run_record import TASK_KINDS as TASK_KINDS
from ._run_record import RunRecord as RunRecord
from ._run_request import REACH_DEFAULTS as REACH_DEFAULTS
from ._run_request import DemonstrationPath as DemonstrationPath
from ._run_request import RunRequest as RunRequest
from ._run_request import resolve_run as resolve_run
from ._run_request import without_demonstrations as without_demonstrations
from ._runs import RunFolder as RunFolder
from ._runs import delete_run_folder as delete_run_folder
from ._runs import find_runs as find_runs
from ._summary import POLICY_SUFFIX as POLICY_SUFFIX
from ._summary import goal_degrees as goal_degrees
from ._summary import has_default_goal as has_default_goal
from ._summary import policy_summary as policy_summary
from ._sweep_list import SweepInfo as SweepInfo
from ._sweep_list import list_sweeps as list_sweeps
from ._sweep_list import load_sweep as load_sweep
from ._sweep_list import resume_target as resume_target
from ._sweep_ray import SweepProgress as SweepProgress
from ._sweep_ray import run_sweep as run_sweep
from ._sweep_spec import SweepError as SweepError
from ._sweep_spec import SweepSpec as SweepSpec
from ._sweep_spec import load_sweep_spec as load_sweep_spec
from ._tiles import TileCoding as TileCoding

_register_environments()  # "TeachStudio/ArmGrid-v0" and "TeachStudio/ArmReach-v0"
