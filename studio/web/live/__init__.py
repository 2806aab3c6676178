"""The live pipeline: observations from the current source through their fitter into the scene,
every raw one into the capture writer while recording, and a recording played as the source
along the path planned over all of it.

Importing the package loads none of its modules (``studio/_lazy.py``), so the planning's child
process (``python -m studio.web.live._plan_child``) loads only what planning needs.
"""

import typing

from ... import _lazy

if typing.TYPE_CHECKING:  # the public names, each loaded when first used (see studio/_lazy.py)
    from ._pipeline import Pipeline as Pipeline
    from ._recorder import CaptureWriter as CaptureWriter

__getattr__, __dir__, __all__ = _lazy.lazy_exports(__name__, __file__)
