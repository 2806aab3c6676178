"""A run keeps its demonstrations' motions for the likeness card; learning refuses bad motions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from studio.capture import load_demonstration
from studio.learning import (
    DemonstrationMotion,
    DemonstrationPath,
    LearningError,
    RunRecord,
    RunRequest,
    motion_problem,
    resolve_run,
)
from studio.samples import SAMPLES_DIR


def sample_path(times: bool = True) -> DemonstrationPath:
    demo = load_demonstration(SAMPLES_DIR / "sample-reach-1.demo.json")
    return DemonstrationPath("Demonstration 'r'", demo.q_robot, "r", demo.times if times else None)


def test_a_record_keeps_the_motions_and_reads_older_files_without_them():
    record = resolve_run(RunRequest(episodes=4, experiments=1, demonstrations=[sample_path()]))
    [motion] = record.demonstration_motions
    assert motion.name == "r" and motion.q_robot.shape[1] == 6
    again = RunRecord.from_dict(record.to_dict())
    np.testing.assert_allclose(again.demonstration_motions[0].times, motion.times)
    older = record.to_dict()
    del older["demonstration_motions"]  # config.json as today's studio wrote it
    assert RunRecord.from_dict(older).demonstration_motions == ()
    plain = resolve_run(RunRequest(episodes=4, experiments=1, demonstrations=[sample_path(False)]))
    assert plain.demonstration_motions == () and "demonstration_motions" not in plain.to_dict()


@pytest.mark.parametrize(
    ("times", "q", "words"),
    [
        (np.arange(3.0), np.zeros((3, 8)), "8 joint angles"),
        (np.arange(1.0), np.zeros((1, 6)), "zero length"),
        (np.zeros(3), np.zeros((3, 6)), "zero length"),
        (np.arange(3.0), np.array([[0.0] * 6, [math.nan] * 6, [0.0] * 6]), "NaN"),
    ],
)
def test_bad_motions_are_one_sentence(times, q, words):
    said = motion_problem("Demonstration 'x'", times, q)
    assert said is not None and words in said and "Demonstration 'x'" in said
    with pytest.raises(LearningError, match=words):
        DemonstrationMotion.checked("x", times, q)
