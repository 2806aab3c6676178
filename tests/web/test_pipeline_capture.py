"""The capture keeps going through frames of another tape width (issue 13 item 8, any source).

The network source already refuses such datagrams; a source that yields them anyway (or a switch
of source mid-capture) must not end the capture silently either: the pipeline leaves them out of
the recording, counts them, and keeps capturing.
"""

from __future__ import annotations

from studio.capture import RecordingWriter, read_recording
from studio.web._schemas import CapturePublic
from studio.web.live._pipeline import Pipeline
from tests.capture.conftest import synthetic_frames


def test_frames_of_another_width_are_left_out_and_counted(tmp_path):
    pipeline = Pipeline()
    good = synthetic_frames(40)
    odd = synthetic_frames(3, regions=3)
    path = tmp_path / "mixed.tape.csv"
    pipeline.start_capture(RecordingWriter(path, regions=good[0].bend.shape[0]), "mixed", path)
    pipeline._record(good[:20])
    pipeline._record([odd[0]])  # a batch of odd frames only
    pipeline._record([*good[20:30], odd[1], *good[30:], odd[2]])  # mixed in a batch
    capture = pipeline.capture_status()
    assert capture["active"] and capture["error"] is None
    assert capture["frames"] == 40 and capture["rejected"] == 3
    assert CapturePublic.model_validate(capture).rejected == 3  # what GET /api/capture answers
    source = pipeline.status()
    assert source["rejected"] == 3 and "3 frames of another tape width" in source["warning"]
    name, written = pipeline.stop_capture()
    recording = read_recording(written)
    assert name == "mixed" and len(recording) == 40
    assert [int(f) for f in recording.frame] == [f.frame for f in good]


def test_a_failed_write_ends_the_capture_with_its_reason(tmp_path):
    """A writer that fails (here: closed under the pipeline) ends the capture with a reason that
    stays until dismissed, apart from the fit warnings."""
    pipeline = Pipeline()
    frames = synthetic_frames(10)
    path = tmp_path / "cut.tape.csv"
    writer = RecordingWriter(path, regions=frames[0].bend.shape[0])
    pipeline.start_capture(writer, "cut", path)
    pipeline._record(frames[:5])
    writer.close()
    pipeline._record(frames[5:])
    capture = pipeline.capture_status()
    assert not capture["active"] and capture["error"] and "cut" in capture["error"]
    pipeline.dismiss_capture_error()
    assert pipeline.capture_status()["error"] is None


def test_frames_of_the_source_before_a_switch_change_nothing_after_it():
    """The pipeline's thread may hold a batch of the old source's frames when the source is
    switched; fitted afterwards, they set the residual and the fitter of the source before (a
    camera read the simulator's fit residual). They are dropped instead."""
    from studio.capture import CameraSource

    pipeline = Pipeline()
    tape = CameraSource()  # any source object: the one switched away from
    pipeline.set_source(tape, "camera")
    frames = synthetic_frames(3)
    assert pipeline._fit(tape, frames) is not None
    assert pipeline.status()["fit_residual_mm"] is not None and pipeline._fitter is not None
    camera = CameraSource()
    pipeline.set_source(camera, "camera")
    assert pipeline._fit(tape, frames) is None  # the old source's batch, after the switch
    assert pipeline.status()["fit_residual_mm"] is None
    assert pipeline._fitter is None
    pipeline.close()
