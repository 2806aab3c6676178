"""Request and response bodies of the API (see ``docs/api.md``).

Families follow FastAPI's convention: ``XCreate`` / ``XUpdate`` are what a client sends,
``XPublic`` is what the API returns. Field types are checked here; the domain rules (budget
limits, reachable goals, demonstration paths) are checked by the learning and capture packages,
whose one-sentence messages the API passes on as 422.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Annotated, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    StrictBool,
    StrictInt,
    Tag,
    field_validator,
)

from studio.learning import (
    DEFAULT_EPISODES,
    DEFAULT_EXPERIMENTS,
    DEFAULT_GOAL_JOINTS_DEG,
    DEFAULT_SEED,
    FORM_ACTIONS,
    REACH_DEFAULTS,
    TASK_KINDS,
    ArmGrid,
    DemonstrationPath,
    DynaQConfig,
    RunRequest,
)

PlanningName = Literal["zero", "full", "soft", "prioritized"]
RunStatus = Literal["queued", "running", "done", "stopped", "failed", "damaged"]
SourceKind = Literal["simulator", "recording", "network", "serial", "camera", "hand"]
Side = Literal["right", "left"]

DEFAULT_GOAL_DEG = DEFAULT_GOAL_JOINTS_DEG
"""The learning package's default goal for joints 1-3 (an arm reaching forward and down)."""
_DYNAQ = DynaQConfig()
"""The learning package's training defaults: ``RunCreate`` takes each of its defaults from here."""


class _Body(BaseModel):
    """Request bodies refuse unknown fields, so a typo is an error and not silently ignored."""

    model_config = ConfigDict(extra="forbid")


# ----------------------------------------------------------------------------- config


class ConfigPublic(BaseModel):
    """What the page needs to know at start."""

    viser_url: str
    version: str
    upload_limit_bytes: int
    data_dir: str
    scene_instance: str | None = None
    """The id the scene at ``viser_url`` answers at ``/studio-instance`` (None: not checked)."""
    training: RunDefaults | None = Field(
        None, description="the train form's defaults: the learning package's, served once"
    )
    planners: list[str] = Field(default_factory=list, description="the planning modes")
    scene_colors: dict[str, tuple[int, int, int]] = Field(
        default_factory=dict,
        description="the scene's named colours (0-255 rgb): the page's scene legend uses them",
    )


# ----------------------------------------------------------------------------- source


class PlaybackPublic(BaseModel):
    """Playback state of a recording source."""

    playing: bool
    speed: float | None
    t: float
    duration: float
    loop: bool


class RetargetPublic(BaseModel):
    """How the human arm is mapped onto the robot."""

    mode: Literal["joint", "cartesian"]
    mirror: bool


class SourcePublic(BaseModel):
    """The live source and pipeline as the page shows them."""

    kind: SourceKind | None
    running: bool
    rate_hz: float
    frames: int
    dropped: int
    error: str | None
    warning: str | None = None
    rejected: int = 0
    recording: str | None
    playback: PlaybackPublic | None
    retarget: RetargetPublic
    fit_residual_mm: float | None
    q_robot: list[float]
    recording_active: bool
    side: Side | None = Field(None, description="the teaching arm (the tape's for a tape source)")
    person_detected: bool | None = Field(
        None, description="camera: whether the last frame saw a person (null for other kinds)"
    )
    observable: list[bool] | None = Field(
        None, description="camera: which of the 7 arm joints the last frame determined"
    )
    camera_fps: float | None = Field(None, description="camera: the frame rate the page reported")
    model: str | None = Field(None, description="camera: the pose model the page reported")
    robot: str = Field("puma560", description="the robot taught (`studio robots` lists them)")
    robot_drawn: str | None = Field(
        None, description="the robot the 3D scene has drawn (null without a scene)"
    )
    robot_loading: str | None = Field(
        None, description="the robot chosen whose meshes the scene is reading (null when drawn)"
    )
    robot_notes: list[str] = Field(
        default_factory=list,
        description="one sentence each: meshes loading, a motion being retargeted onto the "
        "robot, what cannot be shown on it and why, or a recording played as the source: its "
        "path over the whole recording being planned or followed",
    )
    robot_warning: str | None = Field(
        None,
        description="why the robot does not follow the hand now (out of its reach, held "
        "clear of a self-collision, or turning between IK branches), else null",
    )


class SourceUpdate(_Body):
    """Switch the live source."""

    kind: SourceKind
    recording: str | None = None
    port: StrictInt | None = Field(None, ge=1, le=65535)
    device: str | None = None
    calibration: str | None = Field(
        None,
        description="serial only: path of the tape's calibration JSON on the studio's machine "
        "(flat-pose offsets and gains; see studio/capture); none reads raw counts as radians",
    )
    speed: float | None = Field(None, gt=0, le=100)
    loop: StrictBool | None = None
    seed: StrictInt | None = Field(None, ge=0)
    side: Side | None = Field(None, description="camera and hand: the teaching arm (default right)")


class LandmarksFrame(_Body):
    """One frame of MediaPipe Pose landmarks from the page (see docs/api.md), parsed only: the
    camera source judges its values and sizes, once, with one sentence (its body is bounded by
    the route's request limit)."""

    t: float = Field(description="the page's clock, seconds")
    world: list[list[float]] | None = Field(
        None, description="33 x [x, y, z, visibility], metres; null: no person"
    )
    image: list[list[float]] | None = Field(
        None, description="33 x [x, y, visibility], normalised image coordinates"
    )
    width: int = Field(description="image width, pixels")
    height: int = Field(description="image height, pixels")
    fps: float | None = None
    model: Literal["lite", "full", "heavy"] | None = None
    sender: str | None = Field(
        None,
        min_length=1,
        max_length=64,
        pattern=r"^[A-Za-z0-9_-]+$",
        description="the sending page's id, picked once per load (null: told apart by its clock)",
    )


class LandmarksPublic(BaseModel):
    """What the studio made of one landmark frame."""

    person_detected: bool
    observable: list[bool] | None
    warning: str | None
    q_human: list[float] | None = Field(None, description="this frame's fitted arm (rad)")
    q_robot: list[float] | None = Field(None, description="this frame's robot pose (rad)")


class HandTarget(_Body):
    """A pose of the operator's hand for the hand guide (arm frame, metres)."""

    position: list[float] = Field(max_length=3, description="[x, y, z] in the arm's frame, m")
    wxyz: list[float] | None = Field(None, max_length=4, description="unit quaternion, or null")


class HandPublic(BaseModel):
    """The arm and robot the hand guide reached."""

    q_human: list[float]
    q_robot: list[float]
    position_error_m: float
    reached: bool
    warning: str | None


class PlaybackAction(_Body):
    """Control a recording source."""

    action: Literal["play", "pause", "seek"]
    t: float | None = Field(None, ge=0)
    speed: float | None = Field(None, gt=0, le=100)


class ReachAction(_Body):
    """Tell the simulated operator to reach a robot goal (or to go back to random reaching)."""

    action: Literal["reach", "wander"] = "reach"
    goal_deg: list[float] | None = None
    """Joints 1-3 of the goal in degrees; None: the default goal of the robot taught."""


class RetargetUpdate(_Body):
    """Change the human-to-robot mapping."""

    mode: Literal["joint", "cartesian"]
    mirror: StrictBool | None = None


# ----------------------------------------------------------------------------- capture


class CaptureStart(_Body):
    """Start recording every raw frame of the live source."""

    name: str | None = None
    operator: str | None = Field(None, max_length=200)
    notes: str | None = Field(None, max_length=10_000)


class CapturePublic(BaseModel):
    """The capture in progress, if any, and why the last one stopped by itself (until dismissed)."""

    active: bool
    name: str | None
    seconds: float
    frames: int
    rejected: int = Field(
        0, description="frames of another tape width left out of the current or last capture"
    )
    error: str | None = Field(
        None,
        description="why the last capture stopped by itself (a full disk: what is kept); "
        "shown until DELETE /api/capture/error",
    )


class RecordingPublic(BaseModel):
    """A recording file in the list."""

    name: str
    frames: int
    duration: float
    rate_hz: float | None
    created: str
    operator: str
    notes: str
    source: str
    recovered: bool
    size_bytes: int
    sample: bool
    error: str | None = None
    capturing: bool = False
    """Another studio (or ``studio record``) on the same data folder is writing it now: its
    frames so far are not counted, and it is neither recovered nor deletable."""
    kind: Literal["tape", "pose", "hand"] = Field(
        "tape", description="what it records: tape frames, camera landmarks or hand-guide poses"
    )
    warnings: list[str] = Field(
        default_factory=list, description="what loads but looks wrong (times going backwards)"
    )


class RecordingCopy(_Body):
    """Copy a recording (a shipped sample, typically) into the user's recordings."""

    name: str | None = None


class RecordingUpdate(_Body):
    """Rename or annotate a recording."""

    name: str | None = None
    notes: str | None = Field(None, max_length=10_000)
    operator: str | None = Field(None, max_length=200)


class TimelineSignal(BaseModel):
    """One group of a recording's own values on its timeline (``studio.capture``'s ``Signal``)."""

    name: str = Field(
        description='"tape bend", "tape twist", "landmark visibility", "hand position"'
    )
    unit: str = Field(description='"deg", "0-1" or "cm"')
    labels: list[str] = Field(description="one per column: a tape region, a landmark, an axis")
    values: list[list[float | None]] = Field(description="per time, one per label; null: none")


class TimelinePublic(BaseModel):
    """A recording's joints over time, downsampled for the timeline (degrees), and its own values."""

    name: str
    kind: str
    duration: float = Field(description="the whole recording's length, s")
    times: list[float] = Field(description="s after the first frame")
    human: list[list[float]] = Field(description="the human arm's 7 joints per time, degrees")
    robot: list[list[float]] = Field(
        description="the taught robot's joints per time, degrees (one per `robot_joints`)"
    )
    robot_name: str = Field("puma560", description="the robot taught, whose joints `robot` holds")
    robot_title: str = Field("", description="its name as people read it")
    robot_joints: list[str] = Field(
        default_factory=list, description="its own joint names (its URDF's), in order"
    )
    robot_notes: list[str] = Field(
        default_factory=list,
        description="what retargeting onto it met, one sentence each: the first frame out of "
        "its reach, the frames where the hand went beyond its reach, and the frames where its "
        "tool is off the hand's target though within reach",
    )
    residual_mm: list[float] = Field(description="how far the fitted arm misses, mm")
    signals: list[TimelineSignal] = Field(
        default_factory=list,
        description="the recording's own values at the same times: a tape's bend and twist per region, a camera's landmark visibility, a hand guide's hand position",
    )


class RecordingReview(_Body):
    """Show a recording on the robot: hold the pose at ``t``, or draw and play ``[t0, t1]``."""

    t: float | None = Field(None, ge=0)
    t0: float | None = Field(None, ge=0)
    t1: float | None = Field(None, ge=0)


class TakeStart(_Body):
    """Start the next take."""

    operator: str | None = Field(None, max_length=200)


class TakesFinish(_Body):
    """Make the session's kept takes into demonstrations."""

    goal_from_end: StrictBool = False


class TakePublic(BaseModel):
    """One take of the session."""

    recording: str
    state: Literal["recording", "review", "kept"]
    demonstration: str | None = None
    error: str | None = None


class TakesPublic(BaseModel):
    """The take session (``started`` None when no session is open)."""

    started: str | None = None
    finished: str | None = None
    takes: list[TakePublic] = Field(default_factory=list)


# ----------------------------------------------------------------------------- demonstrations


class DemonstrationCreate(_Body):
    """Cut a demonstration out of a recording."""

    recording: str
    t0: float = Field(ge=0)
    t1: float = Field(ge=0)
    goal_from_end: StrictBool = False
    name: str | None = None


class DemonstrationMark(_Body):
    """Mark the start or the end of a demonstration in the live stream."""

    action: Literal["start", "stop"]
    name: str | None = None
    goal_from_end: StrictBool = False


class DemonstrationPublic(BaseModel):
    """A demonstration in the list."""

    name: str
    recording: str
    t0: float
    t1: float
    steps: int
    goal: list[float]
    reaches_goal: bool
    created: str
    sample: bool = False
    error: str | None = None


class DemonstrationDetail(DemonstrationPublic):
    """A demonstration with its robot path (radians, one row per sample)."""

    times: list[float]
    q_robot: list[list[float]]
    grid_path: list[int]


class MarkPublic(BaseModel):
    """The state of live demonstration marking."""

    marking: bool
    t0: float | None
    demonstration: DemonstrationPublic | None = None


# ----------------------------------------------------------------------------- runs


class ObstacleBody(_Body):
    """A box in the robot's base frame (m): its centre and full sizes, as runs store it."""

    centre: list[float] = Field(..., min_length=3, max_length=3)
    size: list[float] = Field(..., min_length=3, max_length=3)


class ObstaclesPublic(_Body):
    """The boxes placed in the scene for the next run, where their handles stand."""

    obstacles: list[ObstacleBody] = Field(default_factory=list, max_length=16)


class _RunCreateBase(_Body):
    """What every training run sets. Every default is the learning package's (``DynaQConfig``,
    ``ArmGrid``, the run defaults), which also checks every value and reports all bad fields at
    once."""

    name: str | None = None
    robot: str | None = None
    """The robot trained on, by the name ``studio robots`` lists (its first three joints on the
    grid, its first ``joints`` on the continuous task); left out: the robot chosen in the page
    (``PUT /api/robot``), the Puma560 by default. An unknown name is refused (422)."""
    planning: PlanningName = _DYNAQ.planning  # type: ignore[assignment]
    planning_steps: int = _DYNAQ.planning_steps
    epsilon: float = _DYNAQ.epsilon
    alpha: float = _DYNAQ.alpha
    gamma: float = _DYNAQ.gamma
    episodes: int = DEFAULT_EPISODES
    experiments: int = DEFAULT_EXPERIMENTS
    goal_deg: list[float] = Field(default_factory=lambda: list(DEFAULT_GOAL_DEG))
    """The goal as joint 1-3 angles, degrees (the continuous task's when it replays no
    demonstration: then the first demonstration's end is its goal)."""
    demonstrations: list[str] = Field(default_factory=list)
    seed: int = DEFAULT_SEED
    learner: str | None = None
    """What trains the run: left out (or ``"dyna-q"``), the task's own Dyna-Q; ``"teacher"`` (the
    demonstrations followed at every step) or ``"cloning"`` (behaviour cloning), baselines of the
    continuous task that learn nothing from reward (``studio train --learner``)."""
    obstacles: list[ObstacleBody] = Field(default_factory=list, max_length=16)
    """Boxes in the robot's base frame no move of the task may touch."""

    def request(self, robot: str, demonstrations: Sequence[DemonstrationPath] = ()) -> RunRequest:
        """The learning package's request of this run on ``robot`` (the one named here, or the
        one the page teaches when it names none), replaying ``demonstrations`` (the named ones'
        joint paths on that robot); :func:`studio.learning.resolve_run` checks it."""
        return RunRequest(
            task=self.task,
            robot=robot,
            config={
                "planning": self.planning,
                "planning_steps": self.planning_steps,
                "epsilon": self.epsilon,
                "alpha": self.alpha,
                "gamma": self.gamma,
            },
            goal_deg=self.goal_deg,
            experiments=self.experiments,
            episodes=self.episodes,
            seed=self.seed,
            demonstrations=demonstrations,
            name=self.name or "",
            origin="page",
            learner=self.learner or "",
            obstacles=[box.model_dump() for box in self.obstacles],
            **self._task_settings(),
        )

    def _task_settings(self) -> dict[str, Mapping[str, object]]:
        """The task's own settings, as :class:`~studio.learning.RunRequest` takes them."""
        raise NotImplementedError


class GridRunCreate(_RunCreateBase):
    """A run on the paper's arm grid, tabular (``task`` may be left out)."""

    task: Literal["arm-grid"] = "arm-grid"
    bins: int = ArmGrid.bins
    """Bins per joint."""

    @field_validator("task", mode="before")
    @classmethod
    def _known_task(cls, task: object) -> object:
        if task not in TASK_KINDS:
            raise ValueError(f"Input should be {' or '.join(map(repr, TASK_KINDS))}")
        return task

    def _task_settings(self) -> dict[str, Mapping[str, object]]:
        return {"grid": {"bins": self.bins}}


class ReachRunCreate(_RunCreateBase):
    """A run on the arm's continuous joints, learnt with tile coding."""

    task: Literal["arm-reach"]
    joints: int = REACH_DEFAULTS["joints"]
    """Joints 1..J learnt (3 to 6)."""
    step_deg: float = REACH_DEFAULTS["step_deg"]
    """Joint increment per action, degrees."""
    actions: str = REACH_DEFAULTS["actions"]
    """What one action moves: "single" (one joint), "pairs" (also two together), "all",
    "follow" (one joint, or all of them along the picked demonstrations), or "all-follow" (any
    joints, or all of them along the picked demonstrations)."""
    tilings: int = REACH_DEFAULTS["tilings"]
    """Offset tilings of each joint."""
    tiles: int | None = REACH_DEFAULTS["tiles"]
    """Tiles per joint in each tiling; left out (null): the robot's default (32 for the Puma560,
    more for an arm whose joints 1-3 turn further, so none of their tiles is wider than 10
    degrees)."""
    bins: int | None = None
    """Not used by this task: the page's form sends its grid field along with every run."""

    def _task_settings(self) -> dict[str, Mapping[str, object]]:
        return {
            "reach": {
                "joints": self.joints,
                "step_deg": self.step_deg,
                "actions": self.actions,
                "tilings": self.tilings,
                "tiles": self.tiles,
            }
        }


def _task_of(body: object) -> str:
    """The union member of a run body: its ``task``, the arm grid when it names none."""
    task = body.get("task") if isinstance(body, dict) else getattr(body, "task", None)
    return task if task in TASK_KINDS else TASK_KINDS[0]  # an unknown one is refused there


RunCreate = Annotated[
    Annotated[GridRunCreate, Tag(TASK_KINDS[0])] | Annotated[ReachRunCreate, Tag(TASK_KINDS[1])],
    Discriminator(_task_of),
]
"""A training run, by what it learns (``task``): ``arm-grid``, the paper's grid, tabular (the
default); ``arm-reach``, the arm's continuous joints with tile coding."""
RUN_TASK_TAGS = TASK_KINDS
"""The tags of :data:`RunCreate`'s members, which validation errors put in front of the field."""


class RunDefaults(GridRunCreate):
    """The train form's defaults (every task's fields, the learning package's defaults; the
    continuous task's actions the form's own, :data:`studio.learning.FORM_ACTIONS`)."""

    joints: int = REACH_DEFAULTS["joints"]
    step_deg: float = REACH_DEFAULTS["step_deg"]
    actions: str = FORM_ACTIONS
    tilings: int = REACH_DEFAULTS["tilings"]
    tiles: int | None = REACH_DEFAULTS["tiles"]


class RunPublic(BaseModel):
    """A training run and how far it got."""

    id: str
    name: str
    status: RunStatus
    config: RunCreate
    created: str
    started: str | None
    finished: str | None
    episodes_done: int
    episodes_total: int
    cpu_seconds: float
    """CPU time of the run's learning so far, counted live while it trains."""
    error: str | None
    note: str | None = None
    """While a running run prepares its learner before its first episode: what it does, e.g.
    "preparing the learner (first run on this machine, about 25 s)"; None otherwise."""
    has_policy: bool
    origin: Literal["cli", "page", "reproduce", "sweep"] = "page"
    group: str | None = None
    elsewhere: bool = Field(
        False,
        description="queued or running in another process (another studio, studio train): "
        "stop it there; POST .../mark-stopped only if no live process owns it",
    )
    damaged: bool = Field(
        False,
        description="the folder cannot be read (status 'damaged', the reason in error): it can "
        "only be deleted",
    )


class CurvePublic(BaseModel):
    """Steps per episode over the ``count`` experiments that finished each episode (the
    learning package's ``curve_statistics``)."""

    episodes: list[int]
    mean: list[float]
    std: list[float]
    median: list[float]
    p10: list[float]
    p90: list[float]
    min: list[float]
    max: list[float]
    count: list[int]
    wall_seconds: list[float | None] | None = None
    """Per episode, the mean over the experiments that finished it of each one's own wall seconds
    from its start to that episode's end; absent for a run saved without times (older runs)."""
    cpu_seconds: list[float | None] | None = None
    """The same in CPU seconds."""


class SweepPublic(BaseModel):
    """A parameter sweep (``studio sweep``, ``docs/sweeps.md``): its trials are ordinary runs whose
    ``group`` is the sweep's id, and its summary is one row per trial."""

    id: str
    status: Literal["running", "done", "interrupted"]
    created: str
    task: str
    metric: str
    swept: list[str]
    trials: int
    finished: int
    runs: list[str]
    """The trials' run ids in ``/api/runs``."""
    columns: list[str]
    rows: list[dict[str, str]]
    """``sweep.csv``'s rows: settings, status, metrics, CPU and wall time per trial."""


# ----------------------------------------------------------------------------- policies, watch


class PolicyPublic(BaseModel):
    """A policy that can be watched or downloaded: the learning package's listing facts
    (``policy_summary``), tabular or tile-coded. A damaged file has only its name, size and
    ``error``; the other fields keep their empty defaults."""

    name: str
    source: Literal["upload", "run"]
    run: str | None
    size_bytes: int
    error: str | None = None
    task: dict = Field(default_factory=dict)
    """What it acts on, as a run's ``config.json`` writes it; ``task["kind"]`` is ``arm-grid`` or
    ``arm-reach`` (or a Gymnasium id)."""
    grid: dict = Field(default_factory=dict)
    """The arm grid of a tabular policy; empty for a tile-coded one."""
    joints: int = 0
    goal_deg: list[float] = Field(default_factory=list)
    planning: str = ""
    episodes: int = 0
    experiments: int = 0
    created: str = ""
    notes: str = ""


class WatchCreate(_Body):
    """Play a policy on the robot in the scene."""

    run: str | None = None
    policy: str | None = None
    start: Literal["random", "current"] = "random"
    seed: int | None = Field(None, ge=0)
    demonstration: str | None = Field(None, max_length=200)
    """The demonstration the likeness card compares with (a name from the list); default the
    run's own first demonstration, or a movement primitive's."""


class MotionFiguresPublic(BaseModel):
    """One motion's own figures (``studio.learning.MotionFigures``; null where undefined)."""

    ldlj: float | None
    sparc: float | None
    joint_shares: list[float | None]
    together: float | None
    duration_s: float | None
    joint_travel_rad: float | None
    tool_path_m: float | None


class LikenessPublic(BaseModel):
    """A likeness card (``studio.learning.LikenessCard.to_dict()``) and what it compared."""

    name: str
    """The demonstration compared with, rolled out from its own start."""
    dtw_rad: float | None
    frechet_m: float | None
    shares_js: float | None
    policy: MotionFiguresPublic
    demonstration: MotionFiguresPublic


class WatchPublic(BaseModel):
    """The greedy rollout being played."""

    steps: int
    """Steps the greedy policy took: grid steps, or joint steps of a continuous policy."""
    seed: int | None
    """The seed of a random start (give it again to watch the same start); None from the current pose."""
    states: list[int]
    """Grid states visited (tabular policies; empty for continuous ones)."""
    times: list[float]
    q_robot: list[list[float]]
    reached_goal: bool
    likeness: LikenessPublic | None = None
    """The policy's likeness card against a demonstration, or None when there is none to
    compare with (``likeness_note`` says why)."""
    likeness_note: str = ""
