"""The page's default continuous run shows its curve falling, with or without a sample ticked
(issue 40): the form's defaults, as ``GET /api/config`` serves them, trained in this process.

With the follow action in the defaults a run taught by a sample pressed the teacher's button from
its first own episode, and its curve stayed at the teacher's level: nothing visibly learnt. The
budget here is the curve's start (two experiments, 20 episodes), judged by its steps, never by a
clock; the same episodes of the default run (20 experiments, 100 episodes) are its first minute.
"""

from __future__ import annotations

import pytest

from studio.learning import LiveProgress, RunRequest, resolve_run
from studio.learning.runs._train import train_learner
from studio.motion import training_demonstration
from studio.samples import SAMPLES_DIR
from studio.web._schemas import RunDefaults

EPISODES = 20
EARLY, LATE = slice(0, 5), slice(15, 20)
FALL = 0.6
"""The last five of the first 20 own episodes take at most this share of the first five's steps."""


@pytest.mark.parametrize("ticked", [False, True], ids=["no sample", "sample-reach-1"])
def test_the_default_continuous_runs_curve_falls_in_its_first_episodes(ticked):
    form = {**RunDefaults().model_dump(), "task": "arm-reach", "experiments": 2}
    form["episodes"] = EPISODES + ticked
    demos = []
    if ticked:
        path = SAMPLES_DIR / "sample-reach-1.demo.json"
        demos = [training_demonstration(path, "puma560", "sample-reach-1", "sample-reach-1")]
    record = resolve_run(RunRequest.from_form(form, demonstrations=demos))
    assert record.arm_reach().joints == 6  # the form's six joints, its planning and reward
    live = LiveProgress(record.experiments, record.episodes)
    result = train_learner(record, live, workers=1)
    own = result.steps[:, len(demos) :].mean(axis=0)  # the curve after the replayed sample
    assert own[LATE].mean() <= FALL * own[EARLY].mean(), own.round().tolist()
