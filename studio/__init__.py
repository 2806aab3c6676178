"""Teach Studio: teach a robot arm by showing it a motion.

Subpackages, each usable alone:

- :mod:`studio.kinematics`: Puma560 and human-arm models, ShapeTape reconstruction, fitting, retargeting.
- :mod:`studio.capture`: tape frames, sources, recordings, demonstrations.
- :mod:`studio.learning`: tabular MDPs, Dyna-Q, the arm grid task, policy files, the paper's experiments.
- :mod:`studio.web`: the FastAPI app, the viser scene and the page.
"""

from __future__ import annotations

from ._errors import StudioError as StudioError

__version__ = "0.1.0"
