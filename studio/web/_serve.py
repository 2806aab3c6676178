"""Run the studio: the viser scene server and uvicorn serving the app, in one process."""

from __future__ import annotations

import logging
import threading
import webbrowser
from typing import TYPE_CHECKING

from ._settings import Settings

if TYPE_CHECKING:
    import viser

    from ._scene import StudioScene

log = logging.getLogger(__name__)

SHUTDOWN_GRACE_S = 3
"""On Ctrl+C, open event streams (which never end by themselves) are closed after this long."""


def start_scene(settings: Settings) -> tuple[viser.ViserServer, StudioScene]:
    """Start the viser server (share button hidden) and the studio's scene in it."""
    import viser

    from ._scene import StudioScene

    server = viser.ViserServer(host=settings.host, port=settings.viser_port, verbose=False)
    server.gui.configure_theme(show_share_button=False)
    return server, StudioScene(server)


def serve(settings: Settings, open_browser: bool = True) -> None:
    """Serve the studio until interrupted (Ctrl+C).

    Args:
        settings: where to listen and where the data lives.
        open_browser: open the page in the default browser once the server is up.
    """
    import uvicorn

    from ._app import create_app

    server, scene = start_scene(settings)
    try:
        app = create_app(settings, scene)
        url = f"http://{'127.0.0.1' if settings.host in ('0.0.0.0', '::') else settings.host}:{settings.port}/"
        config = uvicorn.Config(
            app,
            host=settings.host,
            port=settings.port,
            log_level="warning",
            access_log=False,
            timeout_graceful_shutdown=SHUTDOWN_GRACE_S,
        )
        http = uvicorn.Server(config)
        print(
            f"Teach Studio: open {url}  (scene at {settings.scene_url()}, data in {settings.data_dir.resolve()})"
        )
        if open_browser:
            threading.Timer(1.0, lambda: webbrowser.open(url)).start()
        http.run()
    finally:
        scene.close()
        server.stop()
