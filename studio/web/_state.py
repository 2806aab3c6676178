"""The studio's state: the stores, the live pipeline, the run queue, the scene and the watched rollouts.

One :class:`Studio` per app, built when the app starts and closed when it stops. Routes reach it
through the ``StudioDep`` dependency. Every list's owner announces its own changes through one
``on_change`` callback (the stores, the pipeline's capture, the run queue), which bumps a version
per list; the SSE stream compares versions, so a slow or vanished client never holds anything up.
"""

from __future__ import annotations

import logging
import threading
import uuid
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import TypeVar

import numpy as np

from studio import StudioError, is_loopback
from studio.capture import (
    DEFAULT_PORT,
    CameraSource,
    Fitted,
    FloodError,
    HandPose,
    HandSource,
    LandmarkFrame,
    PlaybackSource,
    SecondSenderError,
    SimulatorSource,
    source_from_spec,
)
from studio.kinematics import (
    DEFAULT_ROBOT,
    KinematicsError,
    load_robot,
    robot_names,
    robot_spec,
)
from studio.learning import (
    AnyPolicy,
    DemonstrationPath,
    default_goal_deg,
    goal_pose,
)
from studio.motion import MotionError, training_demonstration

from ._errors import ConflictError, InvalidError, NotFoundError, TooManyRequestsError
from ._schemas import LandmarksFrame, LandmarksPublic, RunCreate
from ._settings import Settings
from .live import Pipeline
from .scene import RobotPlayer, RobotViews, Scene
from .services import (
    RunQueue,
    demonstration_store,
    policy_store,
    recording_store,
)

log = logging.getLogger(__name__)

Fed = TypeVar("Fed", LandmarkFrame, HandPose)
"""An observation a fed source (the camera, the hand guide) takes in."""
LIST_NAMES = ("recordings", "demonstrations", "runs", "policies")
ROLLOUTS_KEPT = 16
"""Policies whose last watched rollout stays downloadable (each at most a megabyte or two)."""


class ListChanges:
    """A version number per list (recordings, demonstrations, runs, policies)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._versions = dict.fromkeys(LIST_NAMES, 0)

    def bump(self, name: str) -> None:
        """Record that list ``name`` changed."""
        with self._lock:
            self._versions[name] += 1

    def versions(self) -> dict[str, int]:
        """The current versions."""
        with self._lock:
            return dict(self._versions)


class Studio:
    """Everything the API acts on.

    Args:
        settings: data directory, ports, limits.
        scene: the viser scene to drive, or None (tests, headless).
    """

    def __init__(self, settings: Settings, scene: Scene | None = None) -> None:
        self.settings = settings
        for folder in (settings.recordings_dir, settings.runs_dir, settings.policies_dir):
            folder.mkdir(parents=True, exist_ok=True)
        self.changes = ListChanges()
        changed = self.changes.bump
        self.scene = scene
        self.pipeline = Pipeline(scene, on_change=changed)
        self.player = None if scene is None else RobotPlayer(scene)
        self.runs = RunQueue(settings.runs_dir, changed, settings.run_workers)
        self.recordings = recording_store(settings.recordings_dir, self.pipeline, changed)
        self.policies = policy_store(settings.policies_dir, changed, self._policy_playing)
        self.demonstrations = demonstration_store(
            settings.recordings_dir, changed, self._demonstration_replayed
        )
        self.watch_lock = threading.Lock()
        self.watching: str | None = None  # "policy:<name>" or "run:<id>" being played
        # the last rollout watched of each policy key: (times, q), the oldest watched first
        self.rollouts: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.mark_t0: float | None = None  # live demonstration start, recording time (s)
        self._robot_lock = threading.Lock()  # one robot switch at a time
        # one fed update at a time, numbered, timed, fitted and written in the order it came
        self._fed_lock = threading.Lock()
        self._robot_switching: str | None = None  # the robot whose model loads (set_robot)

    def start(self) -> None:
        """Start the run worker and the pipeline (with the configured source, if any)."""
        self.runs.start()
        self.pipeline.start()
        if self.scene is not None:
            from studio.learning import ArmGrid

            grid = ArmGrid()  # the default task's goal, until a watch shows another
            goal = np.zeros(6)
            goal[: grid.joints] = grid.angles_of(grid.goal_state)
            self.scene.set_goal(goal)
        if self.settings.source is not None:
            try:
                self.start_source(self.settings.source)
            except Exception as err:  # the studio still starts: the page shows why
                log.warning("could not start the source %s: %s", self.settings.source, err)
                message = (
                    str(err)
                    if isinstance(err, StudioError)
                    else f"The {self.settings.source} source could not start ({type(err).__name__}: {err}); choose another source."
                )
                self.pipeline.report_error(
                    "simulator" if self.settings.source == "simulator" else "recording", message
                )

    def close(self) -> None:
        """Stop training (keeping partial curves), close a capture cleanly, stop the source."""
        self.runs.close()
        self.pipeline.close()

    # ------------------------------------------------------------------ source

    def start_source(self, source: str) -> None:
        """Start ``"simulator"``, a recording by name, or a recording file by path."""
        if source == "simulator":
            self.set_source(kind="simulator")
            return
        path = Path(source)
        if path.is_file() and path.resolve().parent != self.settings.recordings_dir.resolve():
            name = self.recordings.stem_of(path.name)
            playback = source_from_spec(str(path.resolve()), loop=True)
            self.pipeline.set_source(playback, "recording", name)
            return
        name = self.recordings.stem_of(path.name) if path.is_file() else source
        self.set_source(kind="recording", recording=name, loop=True)

    def set_source(
        self,
        kind: str,
        recording: str | None = None,
        port: int | None = None,
        device: str | None = None,
        calibration: str | None = None,
        speed: float | None = None,
        loop: bool | None = None,
        seed: int | None = None,
        side: str | None = None,
    ) -> None:
        """Build a source of ``kind`` (with the capture package's one factory of sources) and
        make it the live one."""
        if self.scene is not None and kind not in ("camera", "hand"):
            self.scene.show_hand_handle(None, None)
        if kind in ("camera", "hand"):
            self.pipeline.set_source(source_from_spec(f"{kind}:{side or 'right'}", fed=True), kind)
            if kind == "hand" and self.scene is not None:
                self.scene.show_hand_handle(self.pipeline.side(), self.hand_moved)
        elif kind == "simulator":
            self.pipeline.set_source(source_from_spec("simulator", seed=seed or 0), kind)
        elif kind == "recording":
            if recording is None:
                raise InvalidError(
                    "recording is missing; give the name of a recording to play back."
                )
            if not self._replay_in_place(recording, speed, loop):
                path = self.recordings.path(recording).resolve()
                playback = source_from_spec(
                    str(path), speed=1.0 if speed is None else speed, loop=loop is not False
                )
                self.pipeline.set_source(playback, kind, recording)
        elif kind == "network":
            # Loopback unless the user asked for another address (serve --bridge-host); beyond
            # loopback only frames signed with the studio's token are taken.
            host = self.settings.bridge_host
            token = None if is_loopback(host) else self.settings.token
            spec = f"udp:{host}:{DEFAULT_PORT if port is None else port}"
            self.pipeline.set_source(source_from_spec(spec, token=token), kind)
        elif kind == "serial":
            if not device:
                raise InvalidError(
                    "device is missing; give the serial device of the tape, for example /dev/ttyUSB0."
                )
            try:
                serial = source_from_spec(
                    f"serial:{device}", calibration=(calibration or "").strip() or None
                )
            except StudioError as err:
                # pyserial missing, a missing or malformed calibration file: the switch happens
                # as for a device that cannot open, with the serial source showing why.
                self.pipeline.report_error(kind, str(err))
                return
            self.pipeline.set_source(serial, kind)
        else:  # the schema allows only the kinds above
            raise InvalidError(
                f"kind is {kind!r}; give simulator, recording, network, serial, camera or hand."
            )

    def _replay_in_place(self, recording: str, speed: float | None, loop: bool | None) -> bool:
        """Change the speed and loop of ``recording`` if it is the one playing (so that ticking
        "loop" never restarts it from 0); whether it was."""
        current = self.pipeline.source
        if not (
            isinstance(current, PlaybackSource)
            and self.pipeline.recording == recording
            and current.running
        ):
            return False
        if speed is not None:
            current.speed = speed
        if loop is not None:
            current.loop = loop
        return True

    def simulator_reach(self, action: str, goal_deg: list[float] | None = None) -> None:
        """Make the simulator reach a goal of the robot taught (``goal_deg``, joints 1-3) or
        wander again; no goal: the robot's default goal. The Puma560's goal is mirrored joint by
        joint; another robot's is the arm that puts the hand where that robot's tool goes at it.

        Raises:
            ConflictError: the live source is not the simulator.
            ConfigError: the goal is not 3 angles within the robot's limits.
        """
        source = self.pipeline.source
        if self.pipeline.kind != "simulator" or not isinstance(source, SimulatorSource):
            raise ConflictError(
                "The live source is not the simulator; switch the source to the simulator first."
            )
        if action == "wander":
            source.wander()
            return
        robot = self.pipeline.robot_name
        q = goal_pose(default_goal_deg(robot) if goal_deg is None else goal_deg, robot)
        if robot == DEFAULT_ROBOT:  # the Puma560: its joints mirror the arm's one by one
            source.reach(q)
        else:
            source.reach_human(self.pipeline.human_reaching(q))
        if self.scene is not None:
            self.scene.set_goal(q, robot)

    def _fed_source(self, kind: str) -> CameraSource | HandSource:
        """The live fed source ``kind`` (camera or hand).

        Raises:
            ConflictError: the live source is not ``kind``.
        """
        source = self.pipeline.source
        fed = CameraSource if kind == "camera" else HandSource
        if self.pipeline.kind != kind or not isinstance(source, fed):
            label = "camera" if kind == "camera" else "hand guide"
            raise ConflictError(
                f"The live source is not the {label}; switch the source to {kind} first."
            )
        return source

    def _observe_fed(self, submit: Callable[[], Fed]) -> tuple[Fed, Fitted | None]:
        """Hand one update to a fed source (``submit``) and fit it; returns the observation and
        the fit (None when it failed: the pipeline's status says why).

        Raises:
            TooManyRequestsError: a flood (the update is dropped).
            ConflictError: another page sends frames already (the update is dropped).
        """
        with self._fed_lock:
            try:
                observation = submit()
            except FloodError as err:
                raise TooManyRequestsError(str(err)) from None
            except SecondSenderError as err:
                raise ConflictError(str(err)) from None
            return observation, self.pipeline.observe(observation)

    def post_landmarks(self, frame: LandmarksFrame) -> LandmarksPublic:
        """Fit and record one frame of landmarks from the page, as the API parsed it; the camera
        source checks its values (the one check: NaN, sizes, time) and the answer is built
        typed, not read back from a dict.

        Raises:
            ConflictError: the live source is not the camera.
            TooManyRequestsError: a flood (the frame is dropped).
            CaptureError: NaN or wrong sizes (422).
        """
        camera = self._fed_source("camera")
        observation, fitted = self._observe_fed(
            lambda: camera.submit(
                frame.t, frame.world, frame.image, frame.width, frame.height, frame.fps, frame.model
            )
        )
        observable = None if fitted is None else fitted.observable
        return LandmarksPublic(
            person_detected=observation.person,
            observable=None if observable is None else [bool(b) for b in observable],
            warning=fitted.warning if fitted is not None else self.pipeline.status()["error"],
            q_human=None if fitted is None else [float(x) for x in fitted.q_human],
            q_robot=None if fitted is None else [float(x) for x in fitted.q_robot],
        )

    def hand_moved(self, position: object, wxyz: object = None) -> dict[str, object]:
        """Move the operator's hand to a pose (``HandTarget``): what dragging the scene's handle
        does. Returns the arm and robot reached (``HandPublic``).

        Raises:
            ConflictError: the live source is not the hand guide.
            TooManyRequestsError: a flood (the update is dropped).
            CaptureError: NaN or wrong sizes (422).
        """
        hand = self._fed_source("hand")
        _, fitted = self._observe_fed(lambda: hand.submit(position, wxyz))
        if fitted is None:
            raise InvalidError(
                self.pipeline.status()["error"]
                or "The hand guide could not solve this pose; drag the handle elsewhere."
            )
        return {
            "q_human": [float(x) for x in fitted.q_human],
            "q_robot": [float(x) for x in fitted.q_robot],
            "position_error_m": float(fitted.residual),
            "reached": bool(fitted.success),
            "warning": fitted.warning,
        }

    def source_public(self) -> dict[str, object]:
        """``SourcePublic``: the pipeline status plus the playback state."""
        status = self.pipeline.status()
        status.update(self.robot_state())
        plan = self.pipeline.plan_note()
        notes = status["robot_notes"]
        if plan and isinstance(notes, list):
            status["robot_notes"] = [*notes, plan]
        status["playback"] = None
        source = self.pipeline.source
        if self.pipeline.kind == "recording" and isinstance(source, PlaybackSource):
            status["playback"] = _playback_state(source)
        return status

    # ------------------------------------------------------------------ robot

    def set_robot(self, name: str) -> None:
        """Teach robot ``name``: the scene draws it from its meshes, and the live chain
        retargets the operator onto it from the next frame.

        Raises:
            KinematicsError: an unknown name, or a model or mesh that cannot be read (the
                robot taught before stays).
        """
        with self._robot_lock:
            self._robot_switching = robot_spec(name).name
            try:
                arm = load_robot(self._robot_switching)  # seconds the first time
            finally:
                self._robot_switching = None
            if self.scene is not None:
                self.scene.set_robot(arm)  # its meshes are read in the background
            self.pipeline.set_robot(arm.scratch_copy())  # the live thread's own scratch data

    def robot_state(self) -> dict[str, object]:
        """The robot the scene draws, the one whose meshes it reads, and one sentence for each
        thing the page should know about them (loading, retargeting, what cannot be shown)."""
        scene, player = self.scene, self.player
        if scene is None or player is None:
            return {"robot_drawn": None, "robot_loading": None, "robot_notes": []}
        busy, note = player.status()
        notes = [*scene.robot_notes(), *(s for s in (busy, note) if s)]
        switching = self._robot_switching
        if switching is not None:
            title = RobotViews.title(switching)
            notes.insert(
                0, f"Loading the {title}'s model and meshes; the robot drawn stays meanwhile."
            )
        return {
            "robot_drawn": scene.robot_name,
            "robot_loading": switching or scene.robot_loading,
            "robot_notes": notes,
        }

    def robots_public(self) -> dict[str, object]:
        """``RobotsPublic``: every offered robot with its joints and default goal, and the one
        taught now."""
        robots = [
            {
                "name": name,
                "title": robot_spec(name).title,
                "joints": list(load_robot(name, geometry=False).joint_names),
                "goal_deg": list(default_goal_deg(name)),
            }
            for name in robot_names()
        ]
        scene = self.scene
        return {
            "robots": robots,
            "robot": self.pipeline.robot_name,
            "drawn": None if scene is None else scene.robot_name,
            "drawn_meshes": 0 if scene is None else scene.robot_mesh_count,
        }

    def playback(self, action: str, t: float | None, speed: float | None) -> None:
        """Play, pause or seek the recording source.

        Raises:
            ConflictError: the live source is not a recording.
        """
        source = self.pipeline.source
        if self.pipeline.kind != "recording" or not isinstance(source, PlaybackSource):
            raise ConflictError(
                "The live source is not a recording; switch the source to a recording first."
            )
        if speed is not None:
            source.speed = speed
        if action == "play":
            source.resume()
        elif action == "pause":
            source.pause()
        elif action == "seek":
            if t is None:
                raise InvalidError("t is missing; give the time to seek to, in seconds.")
            source.seek(t)

    # ------------------------------------------------------------------ capture

    def start_capture(self, name: str | None, operator: str | None, notes: str | None) -> str:
        """Start recording every raw frame of the live source into a new file.

        Raises:
            ConflictError: a capture is already running, or there is no running source.
        """
        from studio.capture import recording_suffix, recording_writer

        if self.pipeline.capture_name is not None:
            raise ConflictError(
                f"Recording {self.pipeline.capture_name!r} is already running; stop it before starting another."
            )
        source = self.pipeline.source
        if source is None:
            raise ConflictError("There is no live source to record; choose a source first.")
        base = name or f"capture-{datetime.now(UTC):%Y%m%d-%H%M%S}"
        if name is not None:
            self.recordings.check_new_name(name)
        final = self.recordings.new_name(base)
        kind = getattr(source, "observation_kind", "tape")
        path = self.settings.recordings_dir / f"{final}{recording_suffix(kind)}"
        writer = recording_writer(
            kind,
            path,
            config=self.pipeline.tape_config(),
            side=self.pipeline.side(),
            operator=operator or "",
            notes=notes or "",
            source=self.pipeline.source_label(),
        )
        self.pipeline.start_capture(writer, final, path)  # which announces the new recording
        self.mark_t0 = None
        return final

    def stop_capture(self) -> str:
        """Close the capture cleanly; returns the new recording's name."""
        name, _ = self.pipeline.stop_capture()
        self.mark_t0 = None
        return name

    # ------------------------------------------------------------------ demonstrations

    def with_robot(self, create: RunCreate) -> RunCreate:
        """``create`` with its robot filled in: the one chosen in the page when it names none."""
        if create.robot is not None:
            return create
        return create.model_copy(update={"robot": self.pipeline.robot_name})

    def demonstration_path(self, name: str, robot: str = DEFAULT_ROBOT) -> DemonstrationPath:
        """A demonstration's joint path on ``robot`` (rad) and times, for training runs: its
        stored Puma560 path, or its recording's segment retargeted onto another robot
        (:func:`studio.export.training_demonstration`).

        Raises:
            InvalidError: no such demonstration, or it cannot be retargeted (a bad run parameter,
                so 422 rather than 404).
        """
        try:
            self.demonstrations.load(name)
            return training_demonstration(
                self.demonstrations.path(name), robot, f"Demonstration {name!r}", name
            )
        except NotFoundError:
            raise InvalidError(
                f"demonstrations names {name!r}, which does not exist; pick demonstrations from the list."
            ) from None
        except (MotionError, KinematicsError) as err:
            raise InvalidError(str(err)) from None

    def cut_demonstration(
        self,
        recording: str,
        t0: float,
        t1: float,
        goal_from_end: bool = False,
        name: str | None = None,
    ) -> str:
        """Cut ``[t0, t1]`` (s) of a recording into a saved demonstration; returns its name.

        Raises:
            InvalidError: the segment is refused (the capture package's reason) or the name is bad.
        """
        from studio.motion import checked_demonstration, extract_demonstration

        if not (np.isfinite(t0) and np.isfinite(t1)):
            raise InvalidError(
                f"The segment [{t0:g}, {t1:g}] s is not two finite times; give t0 and t1 in "
                "seconds within the recording."
            )
        if t1 <= t0:
            raise InvalidError(
                f"The segment ends at {t1:g} s, not after its start at {t0:g} s; give t1 > t0."
            )
        if name is not None:
            self.demonstrations.check_new_name(name)
        path = self.recordings.path(recording)
        final = name or self.demonstrations.new_name(f"{recording}.{t0:.2f}-{t1:.2f}")
        demo = extract_demonstration(
            path,
            t0,
            t1,
            mode=self.pipeline.retarget_mode,
            goal_from_end=goal_from_end,
            name=final,
        )
        tmp = self.settings.recordings_dir / f".cut-{uuid.uuid4().hex}.tmp"
        try:
            demo.save(tmp)
            checked_demonstration(tmp)  # what the list would refuse is never stored
        except StudioError as err:
            tmp.unlink(missing_ok=True)
            said = str(err).replace(str(tmp), f"{recording} [{t0:.2f}, {t1:.2f}] s")
            raise InvalidError(said) from None
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
        # named without replacing a file that took the name meanwhile
        final = self.demonstrations.claim(tmp, final, exact=name is not None)
        self.show_demonstration(final, play=False)
        return final

    def mark_start(self) -> float:
        """Mark the start of a live demonstration (needs a running capture)."""
        t = self.pipeline.capture_time()
        if t is None:
            raise ConflictError(
                "Marking a demonstration needs a running recording; press Record first."
            )
        self.mark_t0 = t
        return t

    def mark_stop(self, goal_from_end: bool, name: str | None) -> str:
        """Cut the marked segment out of the recording being captured."""
        t1 = self.pipeline.capture_time()
        recording = self.pipeline.capture_name
        if t1 is None or recording is None:
            raise ConflictError(
                "Marking a demonstration needs a running recording; press Record first."
            )
        if self.mark_t0 is None:
            raise ConflictError("No demonstration start is marked; mark the start first.")
        t0, self.mark_t0 = self.mark_t0, None
        self.pipeline.flush_capture()
        return self.cut_demonstration(recording, t0, t1, goal_from_end, name)

    def preview_demonstration(self, name: str) -> None:
        """Draw a demonstration's path and play it on the robot taught."""
        self.show_demonstration(name, play=True)

    def show_demonstration(self, name: str, play: bool) -> None:
        """Draw demonstration ``name``'s tool path on the robot taught and play it (``play``).

        The Puma560 plays the joint path stored in the file at once; any other robot plays the
        demonstration's recording segment retargeted onto it (in the background: the page is
        told meanwhile), its end pose shown as that robot's goal.

        Raises:
            NotFoundError: no such demonstration (or a damaged one: the reader's sentence).
        """
        from studio.learning import ROLLOUT_RATE_HZ
        from studio.motion import demonstration_motion

        demo = self.demonstrations.load(name)
        scene, player = self.scene, self.player
        if scene is None or player is None:
            return
        robot = self.pipeline.robot_name
        if robot == "puma560":
            q = np.asarray(demo.q_robot, dtype=float)
            scene.show_path(f"demo-{name}", q)
            if play:
                scene.play_trajectory(np.asarray(demo.times, dtype=float), q)
            player.clear_note()
            return
        path = self.demonstrations.path(name)
        stat = path.stat()
        player.play(
            robot,
            f"the demonstration {name}",
            ("demonstration", str(path), stat.st_mtime_ns, stat.st_size, robot),
            lambda: demonstration_motion(path, robot, ROLLOUT_RATE_HZ),
            f"demo-{name}",
            goal=True,
            play=play,
        )

    def delete_demonstration(self, name: str) -> None:
        """Delete a demonstration (409 for a sample, or while a queued or running run replays
        it) and its path from the scene."""
        self.demonstrations.delete(name)
        if self.scene is not None:
            self.scene.clear_path(f"demo-{name}")

    # ------------------------------------------------------------------ in-use checks

    def _demonstration_replayed(self, name: str) -> str | None:
        """Why demonstration ``name`` cannot be deleted now: a queued or running run replays it."""
        run = self.runs.uses_demonstration(name)
        if run is None:
            return None
        return f"Demonstration {name!r} is used by run {run.id}, which is {run.status}; stop that run first."

    def _policy_playing(self, name: str) -> str | None:
        """Why uploaded policy ``name`` cannot be deleted now: it plays in the scene."""
        if self.policy_in_use(f"policy:{name}"):
            return f"Policy {name!r} is playing in the scene; stop watching it first."
        return None

    def policy_in_use(self, key: str) -> bool:
        """Whether the scene is playing this policy (``policy:<name>`` or ``run:<id>``)."""
        return self.watching == key and self.scene is not None and self.scene.playing

    def delete_policy(self, name: str) -> None:
        """Delete an uploaded policy (409 while it plays in the scene; a run's policy goes with
        its run) and forget its rollout."""
        if not self.policies.exists(name) and name in {r.id for r in self.runs.list()}:
            raise ConflictError(
                f"Policy {name!r} belongs to a run; delete the run to delete its policy."
            )
        self.policies.delete(name)
        self.forget_rollout(f"policy:{name}")

    def policy_names(self) -> set[str]:
        """Names taken by uploaded policies and runs (a policy upload must not shadow them)."""
        return set(self.policies.names()) | {run.id for run in self.runs.list()}

    def policy_file(self, run: str | None, policy: str | None) -> tuple[Path, str]:
        """The file of a run's or an uploaded policy and its key (``run:<id>`` or
        ``policy:<name>``); ``policy`` may also name a run, as the policy list does."""
        if (run is None) == (policy is None):
            raise InvalidError("Give either run or policy (exactly one) to choose what to watch.")
        if run is not None:
            r = self.runs.get(run)
            if not r.has_policy:
                raise ConflictError(
                    f"Run {run} has no policy yet; wait until it has finished episodes, then try again."
                )
            return r.policy_path, f"run:{run}"
        assert policy is not None
        if not self.policies.exists(policy):
            try:
                r = self.runs.get(policy)
            except (NotFoundError, InvalidError):
                r = None
            if r is not None and r.has_policy:
                return r.policy_path, f"run:{policy}"
        return self.policies.path(policy), f"policy:{policy}"

    def load_policy(self, run: str | None, policy: str | None) -> tuple[AnyPolicy, str]:
        """Load the policy of a run or an uploaded policy, of either kind, through the policy
        store's one reader; returns it and its key (see :meth:`policy_file`)."""
        path, key = self.policy_file(run, policy)
        return self.policies.load_file(path), key

    def keep_rollout(self, key: str, times: np.ndarray, q: np.ndarray) -> None:
        """Remember the rollout just watched of policy ``key`` (the last :data:`ROLLOUTS_KEPT`
        policies' are kept) and mark it as playing."""
        with self.watch_lock:
            self.rollouts.pop(key, None)
            self.rollouts[key] = (times, q)
            while len(self.rollouts) > ROLLOUTS_KEPT:
                self.rollouts.pop(next(iter(self.rollouts)))
            self.watching = key

    def forget_rollout(self, key: str) -> None:
        """Drop the rollout of policy ``key`` (its file is gone)."""
        with self.watch_lock:
            self.rollouts.pop(key, None)

    def watched_rollout(self, key: str | None) -> tuple[str, np.ndarray, np.ndarray] | None:
        """The last rollout watched of policy ``key`` (None: of any policy) as ``(key, times,
        q)``, or None."""
        with self.watch_lock:
            if key is None:
                key = next(reversed(self.rollouts), None)
            if key is None or key not in self.rollouts:
                return None
            return (key, *self.rollouts[key])


def _playback_state(source: PlaybackSource) -> dict[str, object]:
    return {
        "playing": bool(source.running and not source.paused),
        "speed": None if source.speed is None else float(source.speed),
        "t": float(source.position),
        "duration": float(source.duration),
        "loop": bool(source.loop),
    }
