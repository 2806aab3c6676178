"""The studio in the browser: the FastAPI app, its settings, and the server that runs both.

``studio serve`` (the default verb) runs :func:`serve`; tests and scripts build the app with
:func:`create_app` and a :class:`Settings`. The HTTP contract with the page is ``docs/api.md``.

Importing the package loads none of its modules (``studio/_lazy.py``): a child process the studio
starts for one part of its work (planning a recording's path, simplifying a robot's meshes) runs a
module of the package without loading the whole app.
"""

import typing

from .. import _lazy

if typing.TYPE_CHECKING:  # the public names, each loaded when first used (see studio/_lazy.py)
    from ._app import create_app as create_app
    from ._serve import serve as serve
    from ._settings import DEFAULT_UPLOAD_LIMIT_BYTES as DEFAULT_UPLOAD_LIMIT_BYTES
    from ._settings import Settings as Settings
    from ._settings import get_settings as get_settings
    from ._settings import is_loopback as is_loopback

__getattr__, __dir__, __all__ = _lazy.lazy_exports(__name__, __file__)
