"""``studio train``: train Dyna-Q on the arm grid (or, with ``--task arm-reach``, on the arm's
continuous joints with tile coding, as the page does) from the terminal into a run folder.

The run folder is the same one the page makes (:class:`studio.learning.RunFolder`): started in a
data folder, ``studio train --out runs/my-run`` shows up in the page's run list, where it can be
plotted, watched and exported. It holds ``config.json`` (everything needed to repeat the run),
``status.json``, ``steps.csv`` (checkpointed every second while training), ``curves.csv`` and
``policy.policy.npz`` (written at the end, also after Ctrl-C).

Settings come from ``--config FILE.json`` and/or flags (flags win); anything left out takes the
learning package's defaults (``DynaQConfig``, ``ArmGrid``, ``DEFAULT_EXPERIMENTS`` ...). The file
is a run's ``config.json`` (to repeat a run) or looks like::

    {"grid": {"joints": 3, "bins": 11, "low_deg": -180, "high_deg": 180, "goal": [5, 6, 2]},
     "config": {"planning": "full", "planning_steps": 100, "alpha": 0.1},
     "experiments": 20, "episodes": 100, "seed": 0,
     "demonstrations": [[12, 133, ...], ...]}

Boxes no move may touch come from ``--obstacle CX,CY,CZ,SX,SY,SZ`` (centre and full sizes in
metres, in the robot's base frame; repeatable), for either task.

Demonstrations may also come from ``--demos FILE.json`` (repeatable: each adds its demonstrations): a JSON list of state lists, an object with
a ``"demonstrations"`` list, or a cut ``*.demo.json``, whose grid path is computed from its joint
trajectory on the run's grid by the one demonstration-to-grid-path function
(:meth:`ArmGrid.path_from_joints`), as the page does; or be generated with ``--generated-demos N``
(noisy shortest-ish paths, as ``studio reproduce`` uses).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, cast

# Only light modules here: the flags' defaults and choices. What a run needs (the learners,
# numba, the robot models) is imported where it runs, so `studio train --help` and a mistyped
# flag answer at once.
from studio import StudioError, read_json
from studio._layout import RECORDINGS_DIR
from studio.kinematics import DEFAULT_ROBOT, robot_names, robot_spec
from studio.learning import (
    ACTION_SETS,
    CLONING_KIND,
    DEFAULT_EPISODES,
    DEFAULT_EXPERIMENTS,
    DEFAULT_SEED,
    DEFAULT_SHAPING,
    DEMO_SHAPING,
    GRID_DEFAULTS,
    OWN_LEARNER,
    PLANNERS,
    REACH_DEFAULTS,
    TASK_KINDS,
    TEACHER_KIND,
    DynaQConfig,
    LearningError,
)
from studio.samples import SAMPLES_DIR

if TYPE_CHECKING:
    from studio.learning import DemonstrationPath, LiveProgress, RunRecord, RunRequest

from ._options import add_obstacle_option

NAME = "train"
HELP = "Train Dyna-Q on the arm grid or the arm's continuous joints: a run folder with curves and a policy out."
REACH_REWARD_FLAGS = ("shaping", "demo_potential")
"""The continuous task's reward settings ``studio train`` sets (:class:`ArmReach` fields)."""
_DYNAQ = DynaQConfig()


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The flags; each default named in its help is the learning package's."""
    parser.add_argument("--config", type=Path, help="JSON file with grid, config and run settings")
    parser.add_argument(
        "--out", type=Path, help="run folder (default: runs/<time>-<planning>-<id>)"
    )
    parser.add_argument("--name", help="a label for the run (shown in the page's run list)")
    parser.add_argument(
        "--planning", choices=PLANNERS, help=f"planner (default: {_DYNAQ.planning})"
    )
    parser.add_argument(
        "--planning-steps",
        type=int,
        help=f"planning updates per real step (default: {_DYNAQ.planning_steps})",
    )
    parser.add_argument("--alpha", type=float, help=f"learning rate (default: {_DYNAQ.alpha})")
    parser.add_argument("--gamma", type=float, help=f"discount factor (default: {_DYNAQ.gamma})")
    parser.add_argument(
        "--epsilon", type=float, help=f"exploration probability (default: {_DYNAQ.epsilon})"
    )
    parser.add_argument(
        "--experiments",
        type=int,
        help=f"independent experiments (default: {DEFAULT_EXPERIMENTS})",
    )
    parser.add_argument(
        "--episodes", type=int, help=f"episodes per experiment (default: {DEFAULT_EPISODES})"
    )
    parser.add_argument("--seed", type=int, help=f"random seed (default: {DEFAULT_SEED})")
    parser.add_argument(
        "--task",
        choices=TASK_KINDS,
        default=TASK_KINDS[0],
        help="what is learnt: the paper's grid, tabular, or the arm's continuous joints with "
        "tile coding, as the page's Task choice (default: %(default)s)",
    )
    parser.add_argument(
        "--robot",
        help=f"the robot trained on: the grid's first three joints or the continuous task's "
        f"first --joints (default: {DEFAULT_ROBOT}, the paper's; `studio robots` lists them: "
        f"{', '.join(robot_names())})",
    )
    parser.add_argument(
        "--joints",
        type=int,
        help=f"grid joints (default: {GRID_DEFAULTS['joints']}); with --task arm-reach, joints 1..J learnt "
        f"(default: {REACH_DEFAULTS['joints']})",
    )
    parser.add_argument(
        "--bins", type=int, help=f"bins per joint (default: {GRID_DEFAULTS['bins']})"
    )
    _add_reach_arguments(parser)
    goal = parser.add_mutually_exclusive_group()
    goal.add_argument(
        "--goal",
        help="goal bins, comma-separated (default: the bins nearest the robot's default goal)",
    )
    goal.add_argument(
        "--goal-deg",
        help="goal as joint 1-3 angles in degrees, comma-separated, checked against the robot's "
        "limits as the page does, e.g. -30,45,-90 (default: the robot's default goal)",
    )
    parser.add_argument(
        "--demos",
        type=Path,
        action="append",
        help="a cut demonstration (a *.demo.json file, or the name of one in recordings/ or of a "
        "shipped sample such as sample-reach-2), or a JSON file of grid state lists; repeatable",
    )
    add_obstacle_option(parser, "no move may touch")
    parser.add_argument("--generated-demos", type=int, help="replay N generated demonstrations")
    parser.add_argument("--workers", type=int, default=None, help="threads (default: all cores)")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")


def _add_reach_arguments(parser: argparse.ArgumentParser) -> None:
    """The continuous task's flags (``--task arm-reach``) and the learner's."""
    parser.add_argument(
        "--step-deg",
        type=float,
        help=f"arm-reach: joint increment per action, degrees (default: {REACH_DEFAULTS['step_deg']:g})",
    )
    parser.add_argument(
        "--actions",
        choices=ACTION_SETS,
        help="arm-reach: what one action moves: one joint, also two joints together, any "
        "joints at once, one joint or all of them along the --demos (follow), or any joints "
        "at once or all of them along the --demos (all-follow) "
        f"(default: {REACH_DEFAULTS['actions']})",
    )
    parser.add_argument(
        "--tilings",
        type=int,
        help=f"arm-reach: offset tilings of each joint (default: {REACH_DEFAULTS['tilings']})",
    )
    parser.add_argument(
        "--tiles",
        type=int,
        help="arm-reach: tiles per joint in each tiling (default: 32, or more for a robot whose "
        "joints 1-3 turn further, so none of their tiles is wider than 10 degrees)",
    )
    parser.add_argument(
        "--shaping",
        type=float,
        help="arm-reach: weight of the shaping potential toward the goal's joint angles, reward "
        "per joint step; 0 leaves the paper's reward, +100 at the goal and -1 a step "
        f"(default: {DEFAULT_SHAPING:g})",
    )
    parser.add_argument(
        "--demo-potential",
        type=float,
        help="arm-reach: weight of the --demos' shaping potential (Brys et al. 2015: the joint "
        "distance to the demonstrated end pose), reward per joint step; 0 switches it off "
        f"(default: {DEMO_SHAPING:g} less --shaping, so {DEMO_SHAPING:g} under the paper's reward)",
    )
    parser.add_argument(
        "--learner",
        choices=(OWN_LEARNER, TEACHER_KIND, CLONING_KIND),
        help=f"what learns: {OWN_LEARNER} (the task's own: tabular on the grid, tile-coded on "
        f"arm-reach), or a baseline of arm-reach that learns nothing from reward: {TEACHER_KIND} "
        f"(the --demos followed at every step) or {CLONING_KIND} (behaviour cloning: the nearest "
        f"demonstrated state's move) (default: {OWN_LEARNER})",
    )


def _read_json(path: Path, what: str) -> object:
    """A JSON file the user names, read bounded (size, nesting depth, regular files only)."""
    if not path.exists():
        raise LearningError(f"The {what} file {path} does not exist; check the path.")
    try:
        return read_json(path, f"The {what} file {path}")
    except StudioError as err:
        raise LearningError(str(err)) from None


def demonstration_file(given: Path) -> Path:
    """The file ``--demos`` names: a path, else a demonstration's name (``sample-reach-2``, with
    or without ``.demo.json``) in the data folder's ``recordings/``, else a shipped sample's.

    Raises:
        LearningError: no such file or demonstration.
    """
    from studio.capture import DEMO_SUFFIX  # with numpy: only when a demonstration is named

    if given.exists() or len(given.parts) != 1:
        return given
    name = given.name.removesuffix(DEMO_SUFFIX)
    candidates = [
        Path(RECORDINGS_DIR) / f"{name}{DEMO_SUFFIX}",
        SAMPLES_DIR / f"{name}{DEMO_SUFFIX}",
    ]
    for candidate in candidates:
        if candidate.is_file():
            return candidate
    samples = sorted(p.name.removesuffix(DEMO_SUFFIX) for p in SAMPLES_DIR.glob(f"*{DEMO_SUFFIX}"))
    raise LearningError(
        f"There is no demonstration file {given}, nor a demonstration {name!r} in {candidates[0].parent}/ or among the samples ({', '.join(samples)}); check the name or give a path."
    )


def _grid_paths(data: object, source: Path) -> list[list[int]]:
    """The grid state paths of a JSON file (``--demos``, or a config's ``demonstrations``)."""
    if isinstance(data, dict) and "demonstrations" in data:
        data = data["demonstrations"]
    if not isinstance(data, list) or not all(isinstance(d, list) for d in data):
        raise LearningError(
            f"{source} holds no demonstrations; give a list of grid state lists, an object with 'demonstrations', or a *.demo.json file."
        )
    return data


def _recorded(source: Path, robot: str) -> DemonstrationPath:
    """A cut demonstration (``*.demo.json``): its joint trajectory on ``robot`` (the stored
    Puma560 one, or its recording's segment retargeted onto another robot), which the run
    replays along the path the page replays, never the file's stored ``grid_path`` (written by
    older code, or edited by hand); its times too, for the run's likeness card."""
    from studio.motion import MotionError, training_demonstration

    try:
        return training_demonstration(source, robot, f"The demonstration {source}")
    except MotionError as err:
        raise LearningError(str(err)) from None


def _numbers(text: str, flag: str, kind: Callable[[str], float], example: str) -> list[float]:
    try:
        return [kind(v) for v in text.split(",")]
    except ValueError:
        raise LearningError(
            f"{flag} is {text!r}; give numbers separated by commas, e.g. {example}."
        ) from None


def _spec_of(args: argparse.Namespace) -> dict[str, object]:
    """The ``--config`` file's settings: a run's own ``config.json`` (to repeat an arm-grid run)
    or an object with ``grid``, ``config``, ``experiments`` ... (see the module docstring)."""
    if args.config is None:
        return {}
    spec = _read_json(args.config, "config")
    if not isinstance(spec, dict):
        raise LearningError(
            f"The config file {args.config} holds no JSON object; give an object with 'grid' and 'config'."
        )
    if "task" in spec or "format" in spec:  # a run's own config.json: repeat that run
        from studio.learning import RunRecord

        record = RunRecord.from_dict(spec)
        if record.kind != TASK_KINDS[0]:
            raise LearningError(
                f"The config file {args.config} is a {record.kind} run; --config repeats {TASK_KINDS[0]} runs, so give --task {record.kind} with its flags instead."
            )
        spec = {
            "grid": record.arm_grid().to_dict(),
            "config": record.config.to_dict(),
            "experiments": record.experiments,
            "episodes": record.episodes,
            "seed": record.seed,
            "demonstrations": record.demonstrations,
            "obstacles": list(record.arm_grid().obstacles),
        }
    return spec


def _picked(args: argparse.Namespace, spec: dict[str, object]) -> dict[str, object]:
    """The budget and the seed: each flag, else the config file's value, else the default."""
    out: dict[str, object] = {}
    for key, default in (
        ("experiments", DEFAULT_EXPERIMENTS),
        ("episodes", DEFAULT_EPISODES),
        ("seed", DEFAULT_SEED),
    ):
        value = getattr(args, key)
        value = spec.get(key) if value is None else value
        out[key] = default if value is None else value
    return out


def _dynaq_flags(args: argparse.Namespace) -> dict[str, object]:
    """The Dyna-Q settings given as flags."""
    keys = ("planning", "planning_steps", "alpha", "gamma", "epsilon")
    return {key: getattr(args, key) for key in keys if getattr(args, key) is not None}


def run_request(args: argparse.Namespace) -> RunRequest:
    """The run the flags (over the config file, over the learning defaults) ask for.

    Raises:
        LearningError: a file that cannot be read (bad settings are the resolver's to report).
    """
    from studio.capture import DEMO_FORMAT
    from studio.learning import RunRequest

    if getattr(args, "task", TASK_KINDS[0]) != TASK_KINDS[0]:
        return _reach_request(args)
    problems = [
        (
            flag,
            f"--{flag.replace('_', '-')} sets the continuous task; add --task {TASK_KINDS[1]} or leave it out.",
        )
        for flag in (*REACH_DEFAULTS, *REACH_REWARD_FLAGS)
        if flag != "joints" and getattr(args, flag, None) is not None
    ]
    spec = _spec_of(args)
    grid = dict(cast(dict, spec.get("grid", {})))
    robot = args.robot or str(grid.pop("robot", DEFAULT_ROBOT))
    grid.update({k: getattr(args, k) for k in ("joints", "bins") if getattr(args, k) is not None})
    if args.goal is not None:
        grid["goal"] = [int(g) for g in _numbers(args.goal, "--goal", int, "5,6,2")]
    grid_paths: list[list[int]] = []
    if "demonstrations" in spec:
        grid_paths = _grid_paths(spec["demonstrations"], args.config)
    recorded: list[DemonstrationPath] = []
    if args.demos:
        grid_paths = []
        for given in args.demos:
            demo_file = demonstration_file(given)
            data = _read_json(demo_file, "demonstrations")
            if isinstance(data, dict) and data.get("format") == DEMO_FORMAT:
                recorded.append(_recorded(demo_file, robot))
            else:
                grid_paths += _grid_paths(data, demo_file)
    if args.generated_demos:
        grid_paths, recorded = [], []
    goal_deg = None
    if args.goal_deg is not None:
        goal_deg = _numbers(args.goal_deg, "--goal-deg", float, "0,45,-90")
    return RunRequest(
        robot=robot,
        config={**cast(dict, spec.get("config", {})), **_dynaq_flags(args)},
        grid=grid,
        goal_deg=goal_deg,
        **_picked(args, spec),  # type: ignore[arg-type]
        demonstrations=recorded,
        grid_paths=grid_paths,
        generated=args.generated_demos or 0,
        name=args.name or "",
        origin="cli",
        obstacles=args.obstacle or spec.get("obstacles") or (),
        problems=problems,
        learner=args.learner or "",
    )


def _reach_request(args: argparse.Namespace) -> RunRequest:
    """:func:`run_request` for ``--task arm-reach``: the page's continuous-task settings."""
    from studio.capture import DEMO_FORMAT
    from studio.learning import RunRequest

    problems = [
        (flag, f"--{flag.replace('_', '-')} {why}; leave it out with --task {args.task}.")
        for flag, why in (
            ("config", "repeats arm-grid runs"),
            ("bins", "sets the arm grid"),
            ("goal", "sets goal bins of the arm grid; give --goal-deg"),
            ("generated_demos", "generates arm-grid paths; give --demos"),
        )
        if getattr(args, flag) is not None
    ]
    robot = args.robot or DEFAULT_ROBOT
    goal_deg = None  # the robot's default goal pose, whole
    if args.goal_deg is not None:
        goal_deg = _numbers(args.goal_deg, "--goal-deg", float, "0,45,-90")
    recorded = []
    for given in args.demos or ():
        demo_file = demonstration_file(given)
        data = _read_json(demo_file, "demonstrations")
        if not isinstance(data, dict) or data.get("format") != DEMO_FORMAT:
            raise LearningError(
                f"{demo_file} is not a cut demonstration; the continuous task replays a *.demo.json (its joint path)."
            )
        recorded.append(_recorded(demo_file, robot))
    return RunRequest(
        task=args.task,
        robot=robot,
        config=_dynaq_flags(args),
        reach={
            k: getattr(args, k)
            for k in (*REACH_DEFAULTS, *REACH_REWARD_FLAGS)
            if getattr(args, k) is not None
        },
        goal_deg=goal_deg,
        **_picked(args, {}),  # type: ignore[arg-type]
        demonstrations=recorded,
        name=args.name or "",
        origin="cli",
        obstacles=args.obstacle or (),
        problems=problems,
        learner=args.learner or "",
    )


def resolve(args: argparse.Namespace) -> RunRecord:
    """The run's checked record (:func:`studio.learning.resolve_run`), every bad setting
    reported at once.

    Raises:
        LearningError: a bad file or flag (a :class:`ConfigError` lists every bad field).
    """
    from studio.learning import resolve_run

    return resolve_run(run_request(args))


def run(args: argparse.Namespace) -> int:
    """Train into a new run folder; Ctrl-C stops at the next episode and keeps what was learnt."""
    from studio.learning import LiveProgress, RunFolder

    record = resolve(args)
    if args.out is None:
        folder = RunFolder.create(Path("runs"), record, status="running")
    else:
        folder = RunFolder.create(args.out.parent, record, name=args.out.name, status="running")
    live = LiveProgress(record.experiments, record.episodes)
    bar = None
    if not args.no_progress:
        from tqdm import tqdm

        bar = tqdm(total=live.total, unit="episode", desc="train")
    shown = [0]

    def progress(live: LiveProgress) -> None:
        if bar is not None:
            note = live.note or "train"
            if bar.desc != note:
                bar.set_description_str(note)
            done = live.completed
            bar.update(done - shown[0])
            shown[0] = done

    start = time.perf_counter()
    try:
        result = folder.train(live, workers=args.workers, on_checkpoint=progress)
    except KeyboardInterrupt:
        if bar is not None:
            bar.close()
        print(
            f"Stopped: {live.completed} of {live.total} episodes kept in {folder.path}/ "
            f"(curve{' and policy' if folder.has_policy else ''})."
        )
        return 130
    if bar is not None:
        progress(live)
        bar.close()
    if result is None:
        raise LearningError(folder.error or f"The run in {folder.path} did not train.")
    wall = time.perf_counter() - start
    mean = result.mean_steps()
    print(
        f"Trained the {robot_spec(record.robot).title} {record.experiments} x {record.episodes} episodes ({record.config.planning} planning) in {wall:.2f} s "
        f"({result.cpu_seconds.sum():.2f} CPU s): mean steps {mean[0]:.0f} in episode 1, "
        f"{mean[-1]:.1f} in episode {record.episodes}."
    )
    print(
        f"Wrote config.json, status.json, steps.csv, curves.csv and policy.policy.npz to {folder.path}/"
    )
    return 0
