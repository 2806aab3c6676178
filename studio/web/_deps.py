"""Dependencies the routers share, as ``Annotated`` aliases (FastAPI's "bigger applications")."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from ._settings import Settings, get_settings
from ._state import Studio


def get_studio(request: Request) -> Studio:
    """The studio state of the app serving this request."""
    return request.app.state.studio


StudioDep = Annotated[Studio, Depends(get_studio)]
SettingsDep = Annotated[Settings, Depends(get_settings)]
