"""``/api/config``: what the page needs to know at start (scene URL, upload limit, and the train
form's defaults, which the learning package owns)."""

from __future__ import annotations

from fastapi import APIRouter

from studio.learning import PLANNERS

from ... import __version__
from .._deps import SettingsDep
from .._schemas import ConfigPublic, RunDefaults
from ..scene import SceneLayout

router = APIRouter(prefix="/api/config", tags=["config"])


@router.get("", response_model=ConfigPublic)
def read_config(settings: SettingsDep) -> ConfigPublic:
    """The viser scene's URL and colours, the studio version, the upload limit and the training
    defaults."""
    return ConfigPublic(
        viser_url=settings.scene_url(),
        version=__version__,
        upload_limit_bytes=settings.upload_limit_bytes,
        data_dir=str(settings.data_dir.resolve()),
        scene_instance=settings.scene_instance,
        training=RunDefaults(),
        planners=list(PLANNERS),
        scene_colors=SceneLayout().colors,
    )
