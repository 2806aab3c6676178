"""A recording played as the source moves the robot taught along the path planned over the whole
recording (the path ``studio export`` writes), once that is planned, and never jumps onto it."""

from __future__ import annotations

import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from studio.capture import PlaybackSource, human_angles, read_any_recording
from studio.export import recording_motion
from studio.kinematics import RetargetConfig, keep_robot_geometry, load_robot, retarget_path
from studio.samples import SAMPLES_DIR
from studio.web.live import _planned_playback
from studio.web.live._pipeline import Pipeline
from tests.export.conftest import smooth_arm, write_arm_recording

SAMPLE = SAMPLES_DIR / "sample-reach-2.tape.csv"
STEP = RetargetConfig().max_joint_step
WAIT_S = 60.0


@pytest.fixture(scope="module")
def robots_kept(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The module's robot cache folder (a studio keeps one in its data folder)."""
    return tmp_path_factory.mktemp("robots")


@pytest.fixture(autouse=True)
def _robots_kept_there(robots_kept: Path) -> None:
    """This process and its plans' children read each robot's geometry from
    :func:`robots_kept`, as a studio and its children read its own: each robot built once for
    the module, not once a plan (``tests/conftest.py`` forgets the folder after each test)."""
    keep_robot_geometry(robots_kept)


@pytest.fixture(scope="module")
def ur3():
    return load_robot("ur3")


@pytest.fixture
def playing(ur3):
    """A pipeline teaching the UR3, with sample 2 as its source (frames handed in by the test)."""
    pipeline = Pipeline()
    pipeline.set_robot(ur3)
    pipeline.set_source(PlaybackSource(SAMPLE, speed=None), "recording", "sample-reach-2")
    yield pipeline, read_any_recording(SAMPLE)
    pipeline.close()


@pytest.fixture
def children(monkeypatch) -> list[subprocess.Popen]:
    """Every child process started, as started (the planning's)."""
    started: list[subprocess.Popen] = []
    popen = subprocess.Popen

    def spy(*args, **kwargs):
        started.append(popen(*args, **kwargs))
        return started[-1]

    monkeypatch.setattr(subprocess, "Popen", spy)
    return started


def wait_for(pipeline: Pipeline, words: str) -> str:
    deadline = time.monotonic() + WAIT_S
    while words not in (pipeline.plan_note() or ""):
        assert time.monotonic() < deadline, pipeline.plan_note()
        time.sleep(0.02)
    return pipeline.plan_note() or ""


def play(pipeline: Pipeline, recording, rows) -> tuple[np.ndarray, list[str | None]]:
    """The robot's pose and note after each row is fitted, in order."""
    q, notes = [], []
    for row in rows:
        q.append(pipeline.observe(recording.frame_at(row)).q_robot)
        notes.append(pipeline.status()["robot_warning"])
    return np.array(q), notes


def test_played_from_its_start_the_robot_follows_the_planned_path():
    """On a recording whose live retargeting misses frames the plan reaches: the SO-101 on
    sample 3 (the UR3 reaches every frame of sample 2 live, since the workspace map)."""
    so101, path = load_robot("so101"), SAMPLES_DIR / "sample-reach-3.tape.csv"
    recording = read_any_recording(path)
    pipeline = Pipeline()
    pipeline.set_robot(so101)
    pipeline.set_source(PlaybackSource(path, speed=None), "recording", "sample-reach-3")
    try:
        pipeline.observe(recording.frame_at(0))  # the first frame asks for the plan
        assert f"Planning the {so101.spec.title}'s path" in pipeline.plan_note()
        wait_for(pipeline, "is planned")
        q, notes = play(pipeline, recording, range(len(recording)))
        assert "follows the path planned over the whole recording" in pipeline.plan_note()
    finally:
        pipeline.close()
    exported = recording_motion(path, "so101")
    np.testing.assert_array_equal(q, exported.q)  # from the first frame: the arm jumped there
    assert exported.path is not None
    # more frames on the hand's target than the live retargeting gives the same recording
    q_human = human_angles(recording, slice(0, len(recording)))
    live = retarget_path(so101, q_human, side=recording.side, as_live=True)
    assert exported.path.reached.sum() > live.reached.sum()
    # where the plan turns between IK branches, the page says so, frame by frame
    turning = ~exported.path.reached & ~exported.path.out_of_reach
    assert turning.any()
    said = np.array(["turns from one of its IK branches" in (n or "") for n in notes])
    np.testing.assert_array_equal(said, turning)


@pytest.mark.parametrize(
    ("sample", "robot"), [("sample-reach-3", "ur3"), ("sample-reach-2", "kinova")]
)
def test_the_robot_moves_onto_the_plan_where_it_meets_it_or_at_the_loop_never_jumping(
    monkeypatch, sample, robot
):
    """The UR3's live path on sample 3 meets its plan mid-way; the Kinova's on sample 2 never
    does (the UR3 reaches every frame of sample 2 live since the workspace map: its plan is the
    live path, met at once)."""
    path = SAMPLES_DIR / f"{sample}.tape.csv"
    recording = read_any_recording(path)
    pipeline = Pipeline()
    pipeline.set_robot(load_robot(robot))
    pipeline.set_source(PlaybackSource(path, speed=None, loop=True), "recording", sample)
    release = threading.Event()
    plan = _planned_playback.plan_recording

    def slow(path, robot, abandoned):
        release.wait(WAIT_S)
        return plan(path, robot, abandoned)

    monkeypatch.setattr(_planned_playback, "plan_recording", slow)
    try:
        q_live, _ = play(pipeline, recording, range(40))  # played live while it plans
        assert "Planning" in pipeline.plan_note()
        release.set()
        wait_for(pipeline, "is planned")
        q_rest, _ = play(pipeline, recording, range(40, len(recording)))
        q_again, _ = play(pipeline, recording, range(len(recording)))  # the loop's next pass
    finally:
        pipeline.close()
    q = np.vstack([q_live, q_rest])
    assert np.abs(np.diff(q, axis=0)).max() <= STEP + 1e-9  # it never jumped onto the plan
    planned = recording_motion(path, robot).q
    on_plan = np.flatnonzero(np.all(q == planned, axis=1))
    if sample == "sample-reach-3":  # the live pose meets the plan's mid-way: it joins there
        assert len(on_plan) and on_plan[0] > 40
        assert np.array_equal(q[on_plan[0] :], planned[on_plan[0] :])  # and stays on it
    else:  # they never meet in the first pass: it joins at the loop, where the arm jumps too
        assert not len(on_plan)
    np.testing.assert_array_equal(q_again, planned)


def test_a_seek_back_or_a_loop_moves_the_robot_onto_the_plan_with_the_arm(playing, robots_kept):
    pipeline, recording = playing
    pipeline.observe(recording.frame_at(200))
    wait_for(pipeline, "is planned")
    assert list(robots_kept.glob("ur3-*/sha256.json"))  # kept for the next plan
    q, _ = play(pipeline, recording, [201, 202, 10, 11])  # a seek back to row 10
    planned = recording_motion(SAMPLE, "ur3").q
    np.testing.assert_array_equal(q[2:], planned[10:12])


def test_unmirrored_the_robot_follows_the_hand_live(playing, ur3):
    pipeline, recording = playing
    pipeline.set_retarget("cartesian", False)
    q, _ = play(pipeline, recording, range(60))
    assert pipeline.plan_note() is None
    # the path a live session shows, unmirrored (the plan is made for the mirrored robot)
    assert not np.array_equal(q, recording_motion(SAMPLE, "ur3").q[:60])


def test_a_recording_that_cannot_be_planned_plays_live_and_says_why(ur3, tmp_path):
    path = write_arm_recording(tmp_path / "one.tape.csv", smooth_arm(1))
    pipeline = Pipeline()
    pipeline.set_robot(ur3)
    pipeline.set_source(PlaybackSource(path, speed=None), "recording", "one")
    try:
        fitted = pipeline.observe(read_any_recording(path).frame_at(0))
        note = wait_for(pipeline, "could not be planned")
        assert note.startswith("The robot follows the hand as it would live: ")
        assert "one.tape.csv holds 1 frame there" in note  # the export's own sentence
        assert np.isfinite(fitted.q_robot).all() and pipeline.status()["error"] is None
    finally:
        pipeline.close()


def test_a_plan_no_longer_wanted_stops_its_process(children, robots_kept):
    assert _planned_playback.plan_recording(SAMPLE, "ur3", lambda: True) is None
    assert len(children) == 1 and children[0].returncode is not None  # killed, and reaped
    assert children[0].args[-1] == str(robots_kept)  # told where the studio keeps its robots


def test_switching_the_source_or_the_robot_forgets_the_plan(playing):
    pipeline, recording = playing
    pipeline.observe(recording.frame_at(0))
    wait_for(pipeline, "is planned")
    pipeline.set_robot(load_robot("puma560"))
    assert pipeline.plan_note() is None
    pipeline.set_robot(load_robot("ur3"))
    pipeline.observe(recording.frame_at(0))
    assert "follows the path planned" in pipeline.plan_note()  # kept: not planned again
    pipeline.set_source(None, None)
    assert pipeline.plan_note() is None


def test_closing_the_studio_stops_the_planning_under_way(ur3, children):
    pipeline = Pipeline()
    pipeline.set_robot(ur3)
    pipeline.set_source(PlaybackSource(SAMPLE, speed=None), "recording", "sample-reach-2")
    pipeline.observe(read_any_recording(SAMPLE).frame_at(0))
    deadline = time.monotonic() + WAIT_S
    while not children:  # the worker has started the child
        assert time.monotonic() < deadline
        time.sleep(0.01)
    pipeline.close()
    assert children[0].returncode is not None  # killed and reaped, not left running
    assert children[0].returncode != 0  # stopped before it had planned


def test_a_killed_plan_is_tried_again_when_the_recording_is_played_again(playing, monkeypatch):
    """ "planning … failed (exit code -9)" was kept per recording, file time and robot, so
    playing the recording again planned nothing until a restart."""
    pipeline, recording = playing
    popen, started = subprocess.Popen, []

    def killed_once(*args, **kwargs):
        child = popen(*args, **kwargs)
        started.append(child)
        if len(started) == 1:
            child.kill()  # as the out-of-memory killer or a user's kill -9 would
        return child

    monkeypatch.setattr(subprocess, "Popen", killed_once)
    pipeline.observe(recording.frame_at(0))
    note = wait_for(pipeline, "failed (exit code -9")
    pipeline.set_source(PlaybackSource(SAMPLE, speed=None), "recording", "sample-reach-2")
    pipeline.observe(recording.frame_at(0))
    wait_for(pipeline, "is planned")  # planned again, not the failure kept
    assert len(started) == 2
    assert note.endswith("play the recording again to plan it again.")


def test_the_planning_child_quits_and_cleans_up_when_its_studio_is_killed(tmp_path):
    """After ``kill -9`` of the studio the child planned on, re-parented to init, and its
    ``studio-plan-*`` folder stayed in the temporary folder."""
    import os
    import sys

    studio = (
        "import subprocess, sys\n"
        "from pathlib import Path\n"
        "from studio.web.live import _planned_playback\n"
        "popen = subprocess.Popen\n"
        "def spy(*args, **kwargs):\n"
        "    child = popen(*args, **kwargs)\n"
        "    print(child.pid, flush=True)\n"
        "    return child\n"
        "subprocess.Popen = spy\n"
        f"_planned_playback.plan_recording(Path({str(SAMPLE)!r}), 'ur5', lambda: False)\n"
    )
    env = {**os.environ, "TMPDIR": str(tmp_path)}
    parent = subprocess.Popen([sys.executable, "-c", studio], stdout=subprocess.PIPE, env=env)
    child = int(parent.stdout.readline())
    assert list(tmp_path.glob("studio-plan-*"))  # the plan's folder, while it plans
    parent.kill()
    parent.wait()

    def gone(pid: int) -> bool:
        status = Path(f"/proc/{pid}/status")
        try:
            return "\nState:\tZ" in status.read_text()  # ended, not yet reaped by init
        except OSError:
            return True

    deadline = time.monotonic() + WAIT_S
    while not gone(child) or list(tmp_path.glob("studio-plan-*")):
        assert time.monotonic() < deadline, "the planning child outlived its studio"
        time.sleep(0.02)
