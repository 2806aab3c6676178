"""Policies: the uploaded policy files and every run's policy, found by name, loaded through one
reader, and deleted only when nothing plays them."""

from __future__ import annotations

from pathlib import Path
from typing import Literal, NamedTuple

import numpy as np

from studio.kinematics import DEFAULT_ROBOT, Obstacle
from studio.learning import POLICY_SUFFIX, AnyPolicy, policy_obstacles

from .._errors import ConflictError, InvalidError, NotFoundError
from ._changes import OnChange
from ._rollouts import Rollouts
from ._runs import RunQueue
from ._store import FolderStore, StoredFile, policy_store

PolicySource = Literal["upload", "run"]
"""Where a listed policy comes from: an uploaded file, or a run's folder."""


class WatchedRollout(NamedTuple):
    """The rollout last watched of a policy, with what an export of it needs.

    Attributes:
        path: the policy's file.
        name: the run's id or the uploaded policy's name.
        robot: the robot it was learnt on.
        times: sample times ``(N,)`` (s).
        q: the robot's joints ``(N, nq)`` (rad).
        obstacles: the boxes of the policy's task, which an export of it is checked against.
    """

    path: Path
    name: str
    robot: str
    times: np.ndarray
    q: np.ndarray
    obstacles: tuple[Obstacle, ...] = ()


class Policies:
    """The policies a studio offers: its uploaded ones (a folder store) and its runs'.

    Args:
        folder: the uploaded policies' folder.
        on_change: announces that the policy list changed.
        runs: the run queue, whose runs' policies are offered too.
        rollouts: what the scene plays (a policy playing cannot be deleted).
    """

    def __init__(
        self, folder: Path, on_change: OnChange, runs: RunQueue, rollouts: Rollouts
    ) -> None:
        self.runs = runs
        self.rollouts = rollouts
        self.store: FolderStore[AnyPolicy] = policy_store(folder, on_change, self._playing)

    def _playing(self, name: str) -> str | None:
        """Why uploaded policy ``name`` cannot be deleted now: it plays in the scene."""
        if self.rollouts.playing(f"policy:{name}"):
            return f"Policy {name!r} is playing in the scene; stop watching it first."
        return None

    def listed(self) -> list[tuple[StoredFile[AnyPolicy], PolicySource]]:
        """Uploaded policies, then the policy of every run that has one and is not training
        (newest run first); a damaged file is listed with the reason."""
        out: list[tuple[StoredFile[AnyPolicy], PolicySource]] = [
            (entry, "upload") for entry in self.store.entries()
        ]
        for run in self.runs.list():
            if run.has_policy and run.status != "running":
                try:
                    out.append((self.store.entry_at(run.id, run.policy_path), "run"))
                except FileNotFoundError:  # the run was deleted meanwhile
                    continue
        return out

    def names_taken(self) -> set[str]:
        """Names taken by uploaded policies and runs (a new policy must not shadow them)."""
        return set(self.store.names()) | {run.id for run in self.runs.list()}

    def adopt(self, tmp: Path, filename: str | None) -> str:
        """Check an uploaded policy file and give it a name no policy or run has; returns it."""
        taken = self.names_taken()
        return self.store.adopt(tmp, filename, lambda n: n in taken)

    def claim(self, tmp: Path, base: str) -> str:
        """Keep a policy file written by the studio (``tmp``) as a new uploaded policy named
        after ``base`` (``-2``, ... when a policy or a run has that name); returns its name."""
        taken = self.names_taken()
        name = self.store.new_name(base)  # a user's, not a sample's, name
        return self.store.claim(tmp, name, lambda n: n in taken, suffix=POLICY_SUFFIX)

    def delete(self, name: str) -> None:
        """Delete an uploaded policy (409 while it plays in the scene; a run's policy goes with
        its run) and forget its rollout."""
        if not self.store.exists(name) and name in {r.id for r in self.runs.list()}:
            raise ConflictError(
                f"Policy {name!r} belongs to a run; delete the run to delete its policy."
            )
        self.store.delete(name)
        self.rollouts.forget(f"policy:{name}")

    def file(self, run: str | None, policy: str | None) -> tuple[Path, str]:
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
        if not self.store.exists(policy):
            try:
                r = self.runs.get(policy)
            except (NotFoundError, InvalidError):
                r = None
            if r is not None and r.has_policy:
                return r.policy_path, f"run:{policy}"
        return self.store.path(policy), f"policy:{policy}"

    def load(self, run: str | None, policy: str | None) -> tuple[AnyPolicy, str]:
        """Load the policy of a run or an uploaded policy, of either kind, through the policy
        store's one reader; returns it and its key (see :meth:`file`)."""
        path, key = self.file(run, policy)
        return self.store.load_file(path), key

    def watched(self, run: str | None, policy: str | None) -> WatchedRollout:
        """The rollout last watched of a run's policy or an uploaded one.

        Raises:
            ConflictError: that policy has not been watched yet.
        """
        path, key = self.file(run, policy)
        last = self.rollouts.last(key)
        kind, name = key.split(":", 1)
        if last is None:
            raise ConflictError(
                f"{'Run' if kind == 'run' else 'Policy'} {name} has not been watched yet; watch it "
                "first, then export its rollout."
            )
        _, times, q = last
        watched = self.store.load_file(path)
        robot = watched.robot or DEFAULT_ROBOT  # (None: not an arm's policy; never watched)
        return WatchedRollout(path, name, robot, times, q, policy_obstacles(watched))
