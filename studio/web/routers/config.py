"""``/api/config``: what the page needs to know at start (scene URL, upload limit)."""

from __future__ import annotations

from fastapi import APIRouter

from ... import __version__
from .._deps import SettingsDep
from .._schemas import ConfigPublic

router = APIRouter(prefix="/api/config", tags=["config"])


@router.get("", response_model=ConfigPublic)
def read_config(settings: SettingsDep) -> ConfigPublic:
    """The viser scene's URL, the studio version and the upload limit."""
    return ConfigPublic(
        viser_url=settings.scene_url(),
        version=__version__,
        upload_limit_bytes=settings.upload_limit_bytes,
        data_dir=str(settings.data_dir.resolve()),
        scene_instance=settings.scene_instance,
    )
