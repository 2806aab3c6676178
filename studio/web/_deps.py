"""Dependencies the routers share, as ``Annotated`` aliases (FastAPI's "bigger applications")."""

from __future__ import annotations

import json
import re
from typing import Annotated

from fastapi import Depends, Request

from studio import unpaired_surrogate

from ._errors import InvalidError
from ._settings import Settings, get_settings
from ._state import Studio


def get_studio(request: Request) -> Studio:
    """The studio state of the app serving this request."""
    return request.app.state.studio


StudioDep = Annotated[Studio, Depends(get_studio)]
SettingsDep = Annotated[Settings, Depends(get_settings)]


_SURROGATE_ESCAPE = re.compile(rb"\\u[dD][89a-fA-F]")
"""A JSON escape of a UTF-16 surrogate: a body without one holds only real text."""


async def refuse_broken_text(request: Request) -> None:
    """Refuse a JSON body holding a string that is not text (an unpaired ``\\ud800`` escape).

    Such a string cannot be written as UTF-8: stored in a run's or a recording's file, it would
    make every list that shows it fail. Applied to every route, before the route does anything.
    """
    kind = request.headers.get("content-type", "")
    if kind and "json" not in kind:
        return  # an upload: its own reader checks it
    body = await request.body()  # Starlette keeps it: the route reads the same bytes
    if not _SURROGATE_ESCAPE.search(body):
        return
    try:
        value = json.loads(body)
    except ValueError:
        return  # not JSON: the route answers it
    found = unpaired_surrogate(value)
    if found is not None:
        field = found[0] or "The request body"
        raise InvalidError(
            f"{field} holds an unpaired UTF-16 surrogate, which is not text; send it as valid "
            "Unicode text."
        )
