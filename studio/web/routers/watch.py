"""``/api/watch``: the robot in the scene performs a learned policy, step by step."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from fastapi import APIRouter, Response

from studio.kinematics import DEFAULT_ROBOT
from studio.learning import (
    DemonstrationMotion,
    DmpPolicyFile,
    LearningError,
    PolicyFile,
    TilePolicyFile,
    check_policy_robot,
    default_goal,
    greedy_path,
    greedy_rollout,
    likeness_cards,
    rollout,
    rollout_dmp_policy,
    rollout_tile_policy,
    save_trajectory_csv,
)

from .._deps import StudioDep
from .._errors import ConflictError, InvalidError
from .._schemas import LikenessPublic, WatchCreate, WatchPublic
from . import file_responses

AnyPolicy = PolicyFile | TilePolicyFile | DmpPolicyFile
"""A policy of any kind, as the studio loads it."""

router = APIRouter(prefix="/api/watch", tags=["watch"])

ROLLOUT_RATE_HZ = 50.0
"""Samples per second of a watched rollout (the scene interpolates between them)."""
ROUND_DECIMALS = 6
"""Seconds and radians are sent to a micro-unit: far below what the scene can show."""
TILE_DEMONSTRATION_PATH = "demonstration"
"""Name of the scene path showing a continuous run's (or a movement primitive's) demonstration
beside the watched robot."""
TILE_WATCH_MAX_STEPS = 1_500
"""Most joint steps of a watched continuous rollout (a minute of motion at 0.04 s per step)."""


@router.post("")
def watch(body: WatchCreate, studio: StudioDep) -> WatchPublic:
    """Roll the greedy policy of a run or an uploaded policy (exactly one; 422 otherwise) out from
    a random or the current pose and play it in the scene (409 if the run has no policy yet)."""
    policy, key = studio.load_policy(body.run, body.policy)
    if policy.robot is not None:  # (None: not an arm's policy, refused below)
        try:
            check_policy_robot(
                policy.robot,
                studio.pipeline.robot_name,
                "This policy",
                f"pick the {policy.robot} under Source to watch it",
            )
        except LearningError as err:
            raise ConflictError(str(err)) from None
    if isinstance(policy, TilePolicyFile):
        watched = _watch_tile_policy(body, studio, policy, key)
    elif isinstance(policy, DmpPolicyFile):
        watched = _watch_dmp_policy(body, studio, policy, key)
    else:
        watched = _watch_grid_policy(body, studio, policy, key)
    likeness, note = likeness_public(body, studio, policy, key)
    return watched.model_copy(update={"likeness": likeness, "likeness_note": note})


def _demonstration_motions(
    body: WatchCreate, studio: StudioDep, policy: AnyPolicy, key: str
) -> list[DemonstrationMotion]:
    """The demonstrations to compare with: the one asked for, else the run's own (kept in its
    record, or by name from the list for a run recorded before motions were kept), else a
    movement primitive's."""
    names: list[str] = [body.demonstration] if body.demonstration else []
    if not names and key.startswith("run:"):
        record = studio.runs.get(key.removeprefix("run:")).folder.record
        if record.demonstration_motions:
            return list(record.demonstration_motions)
        names = list(record.demonstration_names)
    if not names and isinstance(policy, DmpPolicyFile):
        return [DemonstrationMotion("its demonstration", policy.demo_times, policy.demo_q)]
    robot = policy.robot or DEFAULT_ROBOT
    motions = []
    for name in names:
        studio.demonstrations.load(name)  # 404 with the store's sentence
        # on the policy's robot: the Puma560's stored path, another's retargeted (422 if not)
        demo = studio.demonstration_path(name, robot)
        times = demo.times if demo.times is not None else np.zeros(0)
        try:
            motions.append(DemonstrationMotion.checked(name, times, demo.q_robot))
        except LearningError as err:
            raise InvalidError(str(err)) from None
    return motions


def likeness_public(
    body: WatchCreate, studio: StudioDep, policy: AnyPolicy, key: str
) -> tuple[LikenessPublic | None, str]:
    """The watched policy's likeness card against its first demonstration, rolled out from that
    demonstration's own start; or None and the sentence saying why there is none."""
    motions = _demonstration_motions(body, studio, policy, key)
    if not motions:
        return None, (
            "No likeness card: this policy was not taught from a recorded demonstration; "
            "choose one to compare with."
        )
    motion, card = likeness_cards(policy, motions[:1])[0]
    if isinstance(card, str):
        return None, card
    return LikenessPublic.model_validate({"name": motion.name, **card.to_dict()}), ""


def _watch_grid_policy(
    body: WatchCreate, studio: StudioDep, policy: PolicyFile, key: str
) -> WatchPublic:
    """Play a grid policy from a random start or the current pose's bin."""
    grid = policy.grid
    seed = start_seed(body)
    if body.start == "current":
        q_now = (
            studio.scene.current_q_robot()
            if studio.scene is not None
            else studio.pipeline.q_robot()
        )
        start = grid.state_of_angles(np.asarray(q_now)[: grid.joints])
    else:
        starts = grid.mdp().start_states
        start = int(starts[np.random.default_rng(seed).integers(len(starts))])
    hold = default_goal(grid.robot)  # the joints beyond the grid's
    if body.start == "current" and len(q_now) == len(hold):
        hold[grid.joints :] = np.asarray(q_now)[grid.joints :]
    times, q = rollout(policy, start, ROLLOUT_RATE_HZ, hold=hold)
    states = greedy_path(policy, start)
    studio.keep_rollout(key, times, q)
    if studio.scene is not None:
        goal = default_goal(grid.robot)
        goal[: grid.joints] = grid.angles_of(grid.goal_state)
        studio.scene.set_goal(goal)
        studio.scene.play_trajectory(times, q, states, robot=grid.robot)
    return WatchPublic(
        steps=len(states) - 1,
        seed=seed,
        states=states,
        times=np.round(times, ROUND_DECIMALS).tolist(),
        q_robot=np.round(q, ROUND_DECIMALS).tolist(),
        reached_goal=states[-1] == grid.goal_state,
    )


def _watch_tile_policy(
    body: WatchCreate, studio: StudioDep, policy: TilePolicyFile, key: str
) -> WatchPublic:
    """Play a tile-coded arm policy: one joint step at a time, the run's demonstration beside it."""
    task = policy.task
    if task is None:
        raise ConflictError(
            f"This policy was trained on {policy.env_id or 'another environment'}, not the arm; only arm policies can be watched."
        )
    seed = start_seed(body)
    if body.start == "current":
        q_now = np.asarray(
            studio.scene.current_q_robot()
            if studio.scene is not None
            else studio.pipeline.q_robot()
        )
        start = np.clip(q_now[: task.joints], task.lower, task.upper)
    else:
        start = task.random_start(np.random.default_rng(seed))
    times, q, reached = rollout_tile_policy(policy, start, ROLLOUT_RATE_HZ, TILE_WATCH_MAX_STEPS)
    # the joint path the trajectory was sampled from (deterministic: the same greedy steps)
    path, _ = greedy_rollout(task, policy.coder, policy.weights, start, TILE_WATCH_MAX_STEPS)
    studio.keep_rollout(key, times, q)
    if studio.scene is not None:
        studio.scene.set_goal(np.asarray(task.goal))
        studio.scene.clear_path(TILE_DEMONSTRATION_PATH)
        demos = (
            studio.runs.get(key.removeprefix("run:")).folder.record.demonstrations
            if key.startswith("run:")
            else []
        )
        if demos:  # its joints on the task's robot, the others at the goal's
            path = np.tile(np.asarray(task.goal), (len(demos[0]), 1))
            path[:, : task.joints] = np.asarray(demos[0])[:, : task.joints]
            studio.scene.show_path(TILE_DEMONSTRATION_PATH, path, robot=task.robot)
        studio.scene.play_trajectory(times, q, robot=task.robot)
    return WatchPublic(
        steps=len(path) - 1,
        seed=seed,
        states=[],
        times=np.round(times, ROUND_DECIMALS).tolist(),
        q_robot=np.round(q, ROUND_DECIMALS).tolist(),
        reached_goal=bool(reached),
    )


def _watch_dmp_policy(
    body: WatchCreate, studio: StudioDep, policy: DmpPolicyFile, key: str
) -> WatchPublic:
    """Play a movement primitive from its demonstration's start (or the current pose) to its goal."""
    start = None
    if body.start == "current":
        scene = studio.scene
        now = np.asarray(scene.current_q_robot() if scene else studio.pipeline.q_robot())
        start = now if len(now) == len(policy.goal) else None  # another robot's: its own start
    times, q, reached = rollout_dmp_policy(policy, start, ROLLOUT_RATE_HZ)
    studio.keep_rollout(key, times, q)
    if studio.scene is not None:
        studio.scene.set_goal(policy.goal, robot=policy.robot)
        # the demonstration it was fitted to, beside it, as a continuous run's
        studio.scene.show_path(TILE_DEMONSTRATION_PATH, policy.demo_q, robot=policy.robot)
        studio.scene.play_trajectory(times, q, robot=policy.robot)
    return WatchPublic(
        steps=len(times) - 1,
        seed=None,
        states=[],
        times=np.round(times, ROUND_DECIMALS).tolist(),
        q_robot=np.round(q, ROUND_DECIMALS).tolist(),
        reached_goal=reached,
    )


@router.post("/stop", status_code=204)
def stop_watch(studio: StudioDep) -> Response:
    """Stop the playback; the robot follows the live source again."""
    with studio.watch_lock:
        studio.watching = None
    if studio.scene is not None:
        studio.scene.stop_playback()
    return Response(status_code=204)


@router.get("/trajectory.csv", response_class=Response, responses=file_responses("text/csv"))
def download_trajectory(
    studio: StudioDep, run: str | None = None, policy: str | None = None
) -> Response:
    """The rollout last watched of a run's policy (``?run=<id>``) or an uploaded one
    (``?policy=<name>``), or with neither the last rollout watched, as CSV: ``time,q1..q6``
    (seconds, radians), named ``<run id or policy name>.rollout.csv`` as ``studio export``
    names it. 409 when that policy has not been watched yet."""
    key = None if run is None and policy is None else studio.policy_file(run, policy)[1]
    last = studio.watched_rollout(key)
    if last is None:
        if key is None:
            raise ConflictError(
                "Nothing has been watched yet; watch a policy first, then download."
            )
        kind, name = key.split(":", 1)
        raise ConflictError(
            f"{'Run' if kind == 'run' else 'Policy'} {name} has not been watched yet; watch it first, then download its rollout."
        )
    key, times, q = last
    filename = f"{key.split(':', 1)[-1]}.rollout.csv"
    with tempfile.TemporaryDirectory() as folder:  # the learning package's CSV format, as is
        path = Path(folder) / filename
        save_trajectory_csv(path, times, q)
        text = path.read_text()
    return Response(
        text,
        media_type="text/csv",
        headers={"Content-Disposition": f'attachment; filename="{filename}"'},
    )


def start_seed(body: WatchCreate) -> int | None:
    """The seed of a random start: the one asked for, else a fresh one the answer reports (so
    the same start can be watched again); None for a start from the current pose."""
    if body.start != "random":
        return None
    if body.seed is not None:
        return body.seed
    return int(np.random.default_rng().integers(2**31))
