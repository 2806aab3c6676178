"""The live pipeline: observations from the current source through their fitter into the scene,
every raw one into the capture writer while recording, and a recording played as the source
along the path planned over all of it."""

from __future__ import annotations

from ._pipeline import Pipeline as Pipeline
from ._recorder import CaptureWriter as CaptureWriter
