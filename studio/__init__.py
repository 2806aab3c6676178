"""Teach Studio: teach a robot arm by showing it a motion.

Subpackages, each usable alone:

- :mod:`studio.kinematics`: Puma560 and human-arm models, ShapeTape reconstruction, fitting, retargeting.
- :mod:`studio.capture`: tape frames, sources, recordings, demonstrations.
- :mod:`studio.learning`: tabular MDPs, Dyna-Q, the arm grid task, policy files, the paper's experiments.
- :mod:`studio.web`: the FastAPI app, the viser scene and the page.
"""

from __future__ import annotations

from ._errors import StudioError as StudioError
from ._files import FileLimitError as FileLimitError
from ._files import human_size as human_size
from ._files import open_regular as open_regular
from ._files import read_bytes_bounded as read_bytes_bounded
from ._json import MAX_JSON_BYTES as MAX_JSON_BYTES
from ._json import MAX_JSON_DEPTH as MAX_JSON_DEPTH
from ._json import JSONFileError as JSONFileError
from ._json import TOMLFileError as TOMLFileError
from ._json import loads_json as loads_json
from ._json import read_json as read_json
from ._json import read_toml as read_toml
from ._json import unpaired_surrogate as unpaired_surrogate
from ._net import is_loopback as is_loopback

__version__ = "0.1.0"
