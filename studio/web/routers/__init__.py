"""One router per resource; :func:`studio.web.create_app` includes them all."""

from __future__ import annotations

from typing import Any


def file_responses(*media_types: str) -> dict[int | str, dict[str, Any]]:
    """The OpenAPI ``responses`` of a download: its 200 is a file of these media types, not JSON."""
    binary = {"schema": {"type": "string", "format": "binary"}}
    return {200: {"description": "the file", "content": dict.fromkeys(media_types, binary)}}
