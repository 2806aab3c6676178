"""Capture: tape frames, sources (simulator, playback, network, serial), recordings, demonstrations.

See ``docs/interfaces.md`` for the contract and :mod:`._recording_format` for the file format::

    from studio.capture import SimulatorSource, RecordingWriter, read_recording

    with SimulatorSource(seed=0) as source, RecordingWriter("recordings/x.tape.csv", 16) as out:
        for _ in range(100):
            out.write_many(source.read(timeout=0.1))
    recording = read_recording("recordings/x.tape.csv")
"""

from __future__ import annotations

from ._errors import CaptureError as CaptureError
from ._errors import DemonstrationError as DemonstrationError
from ._errors import RecordingError as RecordingError
from ._frames import SWITCH0_BIT as SWITCH0_BIT
from ._frames import SWITCH1_BIT as SWITCH1_BIT
from ._frames import TRIGGER_BIT as TRIGGER_BIT
from ._frames import TapeFrame as TapeFrame
from ._frames import frames_to_arrays as frames_to_arrays
from ._playback import PlaybackSource as PlaybackSource
from ._recording_edit import copy_recording as copy_recording
from ._recording_edit import rename_recording as rename_recording
from ._recording_edit import update_recording_meta as update_recording_meta
from ._recording_edit import write_recording as write_recording
from ._recording_format import FORMAT_VERSION as FORMAT_VERSION
from ._recording_format import RECORDING_SUFFIX as RECORDING_SUFFIX
from ._recording_reader import Recording as Recording
from ._recording_reader import read_header as read_header
from ._recording_reader import read_recording as read_recording
from ._recording_writer import RecordingWriter as RecordingWriter
from ._recording_writer import recording_meta as recording_meta
from ._source import FrameSource as FrameSource
from ._source import SourceStatus as SourceStatus
from ._source import ThreadedSource as ThreadedSource
