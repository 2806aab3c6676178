"""``/api/watch``: the robot in the scene performs a learned policy, step by step."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from fastapi import APIRouter, Response

from studio.kinematics import DEFAULT_ROBOT
from studio.learning import (
    AnyPolicy,
    DemonstrationMotion,
    LearningError,
    RunRecord,
    Start,
    check_policy_robot,
    learner_of,
    likeness_cards,
    save_trajectory_csv,
)

from .._deps import StudioDep
from .._errors import ConflictError, InvalidError
from .._schemas import LikenessPublic, WatchCreate, WatchPublic
from . import file_responses

router = APIRouter(prefix="/api/watch", tags=["watch"])

ROLLOUT_RATE_HZ = 50.0
"""Samples per second of a watched rollout (the scene interpolates between them)."""
ROUND_DECIMALS = 6
"""Seconds and radians are sent to a micro-unit: far below what the scene can show."""
TILE_DEMONSTRATION_PATH = "demonstration"
"""Name of the scene path showing a continuous run's (or a movement primitive's) demonstration
beside the watched robot."""


@router.post("")
def watch(body: WatchCreate, studio: StudioDep) -> WatchPublic:
    """Roll the greedy policy of a run or an uploaded policy (exactly one; 422 otherwise) out from
    a random or the current pose and play it in the scene (409 if the run has no policy yet)."""
    policy, key = studio.policies.load(body.run, body.policy)
    learner = learner_of(policy)
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
    problem = learner.not_an_arm(policy, "can be watched")
    if problem is not None:
        raise ConflictError(problem)
    if body.start == "current":
        scene = studio.scene
        now = np.asarray(scene.current_q_robot() if scene else studio.pipeline.q_robot())
        start = learner.pose_start(policy, now)
    else:
        start = Start(seed=start_seed(body))
    rollout = learner.roll_out(policy, start, ROLLOUT_RATE_HZ, max_steps=learner.watch_max_steps)
    studio.rollouts.keep(key, rollout.times, rollout.q)
    if studio.scene is not None:
        record = _run_record(studio, key)
        beside = learner.beside(policy, record.demonstrations if record is not None else [])
        studio.scene.set_goal(rollout.goal, robot=rollout.robot)
        if beside is not None:  # the demonstration it learned from, beside it
            studio.scene.show_path(TILE_DEMONSTRATION_PATH, beside, robot=rollout.robot)
        else:
            studio.scene.clear_path(TILE_DEMONSTRATION_PATH)
        states = list(rollout.states) if rollout.states else None
        studio.scene.play_trajectory(rollout.times, rollout.q, states, robot=rollout.robot)
    likeness, note = likeness_public(body, studio, policy, key)
    return WatchPublic(
        steps=rollout.steps,
        seed=rollout.seed,
        states=list(rollout.states),
        times=np.round(rollout.times, ROUND_DECIMALS).tolist(),
        q_robot=np.round(rollout.q, ROUND_DECIMALS).tolist(),
        reached_goal=rollout.reached,
        likeness=likeness,
        likeness_note=note,
    )


def _run_record(studio: StudioDep, key: str) -> RunRecord | None:
    """The record of the run whose policy ``key`` names (``run:<id>``), None for an upload."""
    if not key.startswith("run:"):
        return None
    return studio.runs.get(key.removeprefix("run:")).folder.record


def _demonstration_motions(
    body: WatchCreate, studio: StudioDep, policy: AnyPolicy, key: str
) -> list[DemonstrationMotion]:
    """The demonstrations to compare with: the one asked for, else the run's own (kept in its
    record, or by name from the list for a run recorded before motions were kept), else the one
    the policy file holds (a movement primitive's)."""
    names: list[str] = [body.demonstration] if body.demonstration else []
    record = _run_record(studio, key) if not names else None
    if record is not None:
        if record.demonstration_motions:
            return list(record.demonstration_motions)
        names = list(record.demonstration_names)
    own = learner_of(policy).own_demonstration(policy)
    if not names and own is not None:
        return [own]
    robot = policy.robot or DEFAULT_ROBOT
    motions = []
    for name in names:
        studio.demonstrations.store.load(name)  # 404 with the store's sentence
        # on the policy's robot: the Puma560's stored path, another's retargeted (422 if not)
        demo = studio.demonstrations.path_on(name, robot)
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


@router.post("/stop", status_code=204)
def stop_watch(studio: StudioDep) -> Response:
    """Stop the playback; the robot follows the live source again."""
    studio.rollouts.stop()
    return Response(status_code=204)


@router.get("/trajectory.csv", response_class=Response, responses=file_responses("text/csv"))
def download_trajectory(
    studio: StudioDep, run: str | None = None, policy: str | None = None
) -> Response:
    """The rollout last watched of a run's policy (``?run=<id>``) or an uploaded one
    (``?policy=<name>``), or with neither the last rollout watched, as CSV: ``time,q1..q6``
    (seconds, radians), named ``<run id or policy name>.rollout.csv`` as ``studio export``
    names it. 409 when that policy has not been watched yet."""
    key = None if run is None and policy is None else studio.policies.file(run, policy)[1]
    last = studio.rollouts.last(key)
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
