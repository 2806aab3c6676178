"""Capture: observations of the arm (tape frames, pose landmarks, hand poses), sources (simulator,
playback, network, serial, camera, hand guide), recordings, and the demonstrations cut from them
(stored here, cut by :func:`studio.motion.extract_demonstration`).

See ``docs/architecture.md`` for the public names and :mod:`._recording_format` for the file format::

    from studio.capture import SimulatorSource, RecordingWriter, read_recording

    with SimulatorSource(seed=0) as source, RecordingWriter("recordings/x.tape.csv", config=source.config) as out:
        for _ in range(100):
            out.write_many(source.read(timeout=0.1))
    recording = read_recording("recordings/x.tape.csv")
"""

from __future__ import annotations

import typing

from .. import _lazy

if typing.TYPE_CHECKING:  # the public names, each loaded when first used (see studio/_lazy.py)
    from ._calibration import Calibration as Calibration
    from ._calibration import import_raw as import_raw
    from ._capture_loop import capture as capture
    from ._capture_loop import cli_speed as cli_speed
    from ._capture_loop import describe as describe
    from ._capture_loop import parse_host_port as parse_host_port
    from ._capture_loop import source_from_spec as source_from_spec
    from ._demonstration import DEMO_FORMAT as DEMO_FORMAT
    from ._demonstration import DEMO_ROBOT as DEMO_ROBOT
    from ._demonstration import Demonstration as Demonstration
    from ._demonstration import load_demonstration as load_demonstration
    from ._demonstration import track_segment as track_segment
    from ._errors import CaptureError as CaptureError
    from ._errors import DemonstrationError as DemonstrationError
    from ._errors import RecordingError as RecordingError
    from ._fitters import Fitted as Fitted
    from ._fitters import ObservationFitter as ObservationFitter
    from ._fitters import fitter_for as fitter_for
    from ._network import NetworkSource as NetworkSource
    from ._network import encode_frame as encode_frame
    from ._network import stream_source as stream_source
    from ._observation_recording import ObservationRecording as ObservationRecording
    from ._observation_recording import read_any_recording as read_any_recording
    from ._observation_recording import recording_writer as recording_writer
    from ._observation_recording import summarize_any_recording as summarize_any_recording
    from ._observations import HandPose as HandPose
    from ._observations import LandmarkFrame as LandmarkFrame
    from ._observations import Observation as Observation
    from ._observations import TapeFrame as TapeFrame
    from ._observations import frames_to_arrays as frames_to_arrays
    from ._playback import PlaybackSource as PlaybackSource
    from ._push_sources import CameraSource as CameraSource
    from ._push_sources import FloodError as FloodError
    from ._push_sources import HandSource as HandSource
    from ._push_sources import SecondSenderError as SecondSenderError
    from ._recording_edit import DEMO_SUFFIX as DEMO_SUFFIX
    from ._recording_edit import being_recorded as being_recorded
    from ._recording_edit import delete_recording as delete_recording
    from ._recording_edit import rename_recording as rename_recording
    from ._recording_edit import update_recording_meta as update_recording_meta
    from ._recording_edit import write_recording as write_recording
    from ._recording_format import DEFAULT_RATE_HZ as DEFAULT_RATE_HZ
    from ._recording_format import RECORDING_SUFFIX as RECORDING_SUFFIX
    from ._recording_format import RECORDING_SUFFIXES as RECORDING_SUFFIXES
    from ._recording_format import recording_path as recording_path
    from ._recording_format import recording_suffix as recording_suffix
    from ._recording_reader import Recording as Recording
    from ._recording_reader import read_recording as read_recording
    from ._recording_reader import recording_bytes as recording_bytes
    from ._recording_writer import RecordingWriter as RecordingWriter
    from ._recording_writer import recording_meta as recording_meta
    from ._review import DEFAULT_SERIES_POINTS as DEFAULT_SERIES_POINTS
    from ._review import MAX_SERIES_POINTS as MAX_SERIES_POINTS
    from ._review import TAKES_FILE as TAKES_FILE
    from ._review import RecordingSeries as RecordingSeries
    from ._review import Take as Take
    from ._review import TakeSession as TakeSession
    from ._review import human_angles as human_angles
    from ._review import read_takes as read_takes
    from ._review import recording_series as recording_series
    from ._review import write_takes as write_takes
    from ._serial import SerialSource as SerialSource
    from ._serial import ShapeTapeEmulator as ShapeTapeEmulator
    from ._simulator import OperatorConfig as OperatorConfig
    from ._simulator import SimulatorSource as SimulatorSource
    from ._simulator import goal_configuration as goal_configuration
    from ._simulator import simulate as simulate
    from ._source import FrameSource as FrameSource
    from ._source import SourceStatus as SourceStatus
    from ._source import check_seconds as check_seconds
    from ._source_specs import DEFAULT_PORT as DEFAULT_PORT
    from ._source_specs import SOURCE_SPECS as SOURCE_SPECS

__getattr__, __dir__, __all__ = _lazy.lazy_exports(__name__, __file__)
