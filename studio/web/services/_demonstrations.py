"""Demonstrations: cut out of recordings, shown and played on the robot taught, turned into the
joint paths a training run replays, fitted with a movement primitive, and deleted only when no
run replays them."""

from __future__ import annotations

import uuid
from pathlib import Path

import numpy as np

from studio import StudioError
from studio.capture import DEMO_ROBOT, Demonstration
from studio.kinematics import DEFAULT_ROBOT, KinematicsError, robot_spec
from studio.learning import DemonstrationPath, LearningError, fit_dmp_policy, save_dmp_policy
from studio.motion import MotionError, training_demonstration

from .._errors import InvalidError, NotFoundError
from ..live import Pipeline
from ..scene import RobotPlayer, Scene
from ._changes import OnChange
from ._policies import Policies
from ._runs import RunQueue
from ._store import FolderStore, RecordingStore, StoredFile, demonstration_store


class Demonstrations:
    """The demonstrations of a studio (a folder store beside the recordings) and what is done
    with them.

    Args:
        recordings: the recordings they are cut from (their folder holds the demonstrations).
        on_change: announces that the demonstration list changed.
        pipeline: the live pipeline (the robot taught, the retargeting mode).
        scene: the scene they are shown in, or None (headless).
        player: what plays them on a robot other than the Puma560 (None without a scene).
        runs: the run queue (a demonstration a queued or running run replays stays).
        policies: where a movement primitive fitted to one is kept.
    """

    def __init__(
        self,
        recordings: RecordingStore,
        on_change: OnChange,
        pipeline: Pipeline,
        scene: Scene | None,
        player: RobotPlayer | None,
        runs: RunQueue,
        policies: Policies,
    ) -> None:
        self.recordings = recordings
        self.pipeline = pipeline
        self.scene = scene
        self.player = player
        self.runs = runs
        self.policies = policies
        self.store: FolderStore[Demonstration] = demonstration_store(
            recordings.folder, on_change, self._replayed
        )

    def _replayed(self, name: str) -> str | None:
        """Why demonstration ``name`` cannot be deleted now: a queued or running run replays it."""
        run = self.runs.uses_demonstration(name)
        if run is None:
            return None
        return f"Demonstration {name!r} is used by run {run.id}, which is {run.status}; stop that run first."

    def listed(self) -> list[StoredFile[Demonstration]]:
        """Every demonstration: the shipped samples, then the user's newest first (by when each
        was cut, then by name); a damaged file is listed too, with the reason."""
        entries = self.store.entries()
        samples = [e for e in entries if e.sample]
        mine = sorted(
            (e for e in entries if not e.sample),
            key=lambda e: ((e.value.created or "") if e.value is not None else "", e.name),
        )
        return samples + mine[::-1]

    def path_on(self, name: str, robot: str = DEFAULT_ROBOT) -> DemonstrationPath:
        """A demonstration's joint path on ``robot`` (rad) and times, for training runs: its
        stored Puma560 path, or its recording's segment retargeted onto another robot
        (:func:`studio.motion.training_demonstration`).

        Raises:
            InvalidError: no such demonstration, or it cannot be retargeted (a bad run parameter,
                so 422 rather than 404).
        """
        try:
            self.store.load(name)
            return training_demonstration(
                self.store.path(name), robot, f"Demonstration {name!r}", name
            )
        except NotFoundError:
            raise InvalidError(
                f"demonstrations names {name!r}, which does not exist; pick demonstrations from the list."
            ) from None
        except (MotionError, KinematicsError) as err:
            raise InvalidError(str(err)) from None

    def cut(
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
            self.store.check_new_name(name)
        path = self.recordings.path(recording)
        final = name or self.store.new_name(f"{recording}.{t0:.2f}-{t1:.2f}")
        demo = extract_demonstration(
            path,
            t0,
            t1,
            mode=self.pipeline.retarget_mode,
            goal_from_end=goal_from_end,
            name=final,
        )
        tmp = self.recordings.folder / f".cut-{uuid.uuid4().hex}.tmp"
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
        final = self.store.claim(tmp, final, exact=name is not None)
        self.show(final, play=False)
        return final

    def show(self, name: str, play: bool) -> None:
        """Draw demonstration ``name``'s tool path on the robot taught and play it (``play``).

        The Puma560 plays the joint path stored in the file at once; any other robot plays the
        demonstration's recording segment retargeted onto it (in the background: the page is
        told meanwhile), its end pose shown as that robot's goal.

        Raises:
            NotFoundError: no such demonstration (or a damaged one: the reader's sentence).
        """
        from studio.learning import ROLLOUT_RATE_HZ
        from studio.motion import demonstration_motion

        demo = self.store.load(name)
        scene, player = self.scene, self.player
        if scene is None or player is None:
            return
        robot = self.pipeline.robot_name
        if robot == DEMO_ROBOT:  # the path the file stores is this robot's
            q = np.asarray(demo.q_robot, dtype=float)
            scene.show_path(f"demo-{name}", q)
            if play:
                scene.play_trajectory(np.asarray(demo.times, dtype=float), q)
            player.clear_note()
            return
        path = self.store.path(name)
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

    def fit_primitive(self, name: str) -> str:
        """Fit the movement-primitive baseline (a DMP) to demonstration ``name`` on the robot
        taught, in that robot's joint space, and keep it among the policies as
        ``<name>-dmp-<robot>``; returns the policy's name.

        Raises:
            NotFoundError: no such demonstration.
            InvalidError: it cannot be retargeted (its recording gone) or fitted.
        """
        self.store.load(name)  # 404 with the store's sentence
        robot = self.pipeline.robot_name
        demo = self.path_on(name, robot)
        try:
            policy = fit_dmp_policy(
                demo.times if demo.times is not None else np.zeros(0),
                demo.q_robot,
                robot=robot,
                notes=f"fitted to the demonstration {name} on the {robot_spec(robot).title}",
            )
        except LearningError as err:
            raise InvalidError(str(err)) from None
        tmp: Path = self.policies.store.folder / f".dmp-{uuid.uuid4().hex}.tmp"
        try:
            save_dmp_policy(tmp, policy)
            return self.policies.claim(tmp, f"{name}-dmp-{robot}")
        finally:
            tmp.unlink(missing_ok=True)

    def delete(self, name: str) -> None:
        """Delete a demonstration (409 for a sample, or while a queued or running run replays
        it) and its path from the scene."""
        self.store.delete(name)
        if self.scene is not None:
            self.scene.clear_path(f"demo-{name}")
