"""A policy judged from held-out random starts, beside its teacher on the same starts.

``studio evaluate`` asks this: each start is drawn as the task draws its episodes' starts (from
a seed of its own, drawn from ``--seed``), the policy is rolled out greedily through its learner
(:mod:`._registry`), and every sample of every rollout is checked for contact by the caller's
``collides`` (the robot's collision geometry: kinematics' to know, not learning's). For a
continuous task taught from demonstrations, the teacher (the demonstrations followed with no
learning, :mod:`.linear._teacher`) is rolled out from the very same starts.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ._interface import Evaluation, Start
from ._registry import learner_of
from .linear._policy import DEFAULT_MAX_STEPS, TilePolicyFile
from .linear._teacher import follows_demonstrations, teacher_walk
from .tabular._policy import ROLLOUT_RATE_HZ

Collides = Callable[[str, np.ndarray], bool]
"""Whether the named robot touches itself or the table anywhere along the joints ``(N, nq)``."""


@dataclass(frozen=True)
class Evaluated:
    """A policy and, when it has one, its teacher, from the same starts.

    Attributes:
        starts: how many starts.
        seed: the seed the starts were drawn from.
        policy: the policy's figures.
        teacher: the teacher's (None: the policy was not taught by following demonstrations).
    """

    starts: int
    seed: int
    policy: Evaluation
    teacher: Evaluation | None


def evaluate_policy(
    policy: object, starts: int, seed: int, collides: Collides, rate_hz: float = ROLLOUT_RATE_HZ
) -> Evaluated:
    """``policy`` rolled out greedily from ``starts`` random starts drawn from ``seed``, beside
    its teacher from the same starts."""
    learner = learner_of(policy)
    seeds = np.random.default_rng(seed).integers(0, 2**31 - 1, size=starts)
    reached, collided, steps, seconds = [], [], [], []
    for s in seeds:
        rollout = learner.roll_out(policy, Start(seed=int(s)), rate_hz)
        reached.append(rollout.reached)
        collided.append(collides(rollout.robot, rollout.q))
        steps.append(rollout.steps)
        seconds.append(float(rollout.times[-1]) if len(rollout.times) else 0.0)
    judged = Evaluation.of(reached, steps, seconds=seconds, collided=collided)
    return Evaluated(starts, seed, judged, _teacher(policy, seeds, collides))


def _teacher(policy: object, seeds: np.ndarray, collides: Collides) -> Evaluation | None:
    """The demonstrations followed from each start (a tile-coded policy that follows them)."""
    if not isinstance(policy, TilePolicyFile) or policy.task is None:
        return None
    task = policy.task
    if not follows_demonstrations(task):
        return None
    reached, collided, steps, seconds = [], [], [], []
    for s in seeds:
        start = task.random_start(np.random.default_rng(int(s)))  # as the policy's rollout
        path, done = teacher_walk(task, start, DEFAULT_MAX_STEPS)
        reached.append(done)
        collided.append(collides(task.robot, np.array([task.full_q(q) for q in path])))
        steps.append(len(path) - 1)
        seconds.append((len(path) - 1) * policy.seconds_per_step)
    return Evaluation.of(reached, steps, seconds=seconds, collided=collided)
