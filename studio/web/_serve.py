"""Run the studio: the viser scene server and uvicorn serving the app, in one process.

Start-up order matters: the API's port is bound first (a taken port is one sentence, before
anything else starts), then the scene, whose really bound port and instance id go into the
settings the page reads. The scene server is guarded like the API (:class:`SceneGuard`): it
answers only the studio's own ``Host`` and ``Origin`` (any web page can open a websocket to
127.0.0.1), and it never opens viser's public share tunnel, whatever a client asks.
"""

from __future__ import annotations

import asyncio
import errno
import json
import logging
import secrets
import socket
import sys
import threading
import time
import webbrowser
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import urlsplit

from studio import StudioError, is_loopback
from studio.kinematics import isolate_robot_loading, prepare_arm_ik_in_background
from studio.learning import prepare_in_background

from ._guard import SiteRule
from ._settings import Settings

if TYPE_CHECKING:
    import uvicorn
    import viser
    from websockets.asyncio.server import Server, ServerConnection
    from websockets.http11 import Request, Response

    from .scene import StudioScene

    ProcessRequest = Callable[[ServerConnection, Request], Response | None]
    """websockets' hook that may answer a handshake request itself."""

log = logging.getLogger(__name__)

SHUTDOWN_GRACE_S = 3
"""On Ctrl+C, open event streams (which never end by themselves) are closed after this long."""
UP_POLL_S = 0.1
"""How often the start checks whether the API is up, to compile the learner after it."""
GIL_SWITCH_INTERVAL_S = 0.001
"""How long a Python thread may keep the GIL while another waits (CPython's default: 5 ms)."""
INSTANCE_PATH = "/studio-instance"
"""Where the scene server answers its instance id (the page checks it before embedding)."""
TOKEN_COOKIE = "teach-studio-scene-{port}"
"""Cookie that carries the token to the scene's files and websocket after the first page load."""
FIND_SERVER_TIMEOUT_S = 5.0


class ServeError(StudioError):
    """The studio cannot start: a port taken, a data folder that cannot be written."""


class SceneGuard(SiteRule):
    """Who the scene server answers: the studio's own Host and Origin, and the token if any.

    The same rule as the API's guard (one :class:`~studio.web._guard.SiteRule`): a request
    whose ``Host`` names another site (DNS rebinding) is refused, and so is a request, websocket
    included, sent by a page of another origin. Clients that send no ``Origin`` (command-line
    tools, tests) are local programs and pass, as on the API.

    Args:
        hosts: host names accepted in ``Host`` and ``Origin``.
        ports: ports an ``Origin`` may carry: the scene's own (its page opens the websocket)
            and the API's (the studio page reads the instance id).
        instance: the id answered at :data:`INSTANCE_PATH`.
        token: when set, every request must carry it, as ``?token=`` (the page's iframe URL)
            or in the cookie set on the first such request.

    Attributes:
        refused: requests refused so far.
        share_requests_refused: share-tunnel requests refused so far.
    """

    cookie_name = TOKEN_COOKIE

    def __init__(
        self,
        hosts: Iterable[str],
        ports: Iterable[int],
        instance: str,
        token: str | None = None,
    ) -> None:
        super().__init__(hosts, ports, token)
        self.instance = instance
        self.refused = 0
        self.share_requests_refused = 0

    # ------------------------------------------------------------------ websockets hook

    def wrap(self, process_request: ProcessRequest | None) -> ProcessRequest:
        """A websockets ``process_request`` that applies the rule, then calls the original."""
        from websockets.datastructures import Headers
        from websockets.http11 import Response

        def reply(status: int, reason: str, body: bytes, headers: dict[str, str]) -> Response:
            h = Headers(headers)
            h["Content-Length"] = str(len(body))
            h.setdefault("Content-Type", "text/plain; charset=utf-8")
            h["Cache-Control"] = "no-store"
            return Response(status, reason, h, body)

        def guarded(connection: ServerConnection, request: Request) -> Response | None:
            headers = request.headers
            origin = headers.get("Origin")
            if not self.host_ok(headers.get("Host")):
                self.refused += 1
                return reply(400, "Bad Request", b"Invalid host header", {})
            if not self.origin_ok(origin):
                self.refused += 1
                log.warning("Refused a scene request from another site (Origin %s).", origin)
                return reply(403, "Forbidden", b"This scene belongs to another page.", {})
            allowed, from_query = self.token_ok(request.path, headers.get("Cookie"))
            if not allowed:
                self.refused += 1
                return reply(403, "Forbidden", b"Open the studio with its token.", {})
            if urlsplit(request.path).path == INSTANCE_PATH:
                cors = {"Access-Control-Allow-Origin": origin} if origin else {}
                body = json.dumps({"instance": self.instance}).encode()
                return reply(200, "OK", body, {"Content-Type": "application/json", **cors})
            response = process_request(connection, request) if process_request else None
            if response is not None and from_query and self.token is not None:
                response.headers["Set-Cookie"] = self.set_cookie_header()
            return response

        return guarded

    def install(self, server: viser.ViserServer) -> None:
        """Guard a running viser server and make its share tunnel impossible.

        Raises:
            ServeError: viser's internals changed so that the guard cannot be installed (the
                scene is then not served unguarded).
        """
        ws_server = _websockets_server(server)
        ws_server.process_request = self.wrap(ws_server.process_request)
        # Anything that connected in the instant before the guard has to connect again.
        server._websock_server.disconnect_all_clients()
        self._refuse_share(server)

    def _refuse_share(self, server: viser.ViserServer) -> None:
        from viser import _messages

        ws = server._websock_server
        for cls in (_messages.ShareUrlRequest, _messages.ShareUrlDisconnect):
            ws._incoming_handlers.pop(cls, None)

        def refuse_message(client_id: int, message: object) -> None:
            self.share_requests_refused += 1
            log.warning("Refused a request to publish the scene (client %s).", client_id)

        def refuse_call(*args: object, **kwargs: object) -> None:
            self.share_requests_refused += 1
            log.warning("Refused a request to publish the scene: the share tunnel is disabled.")

        ws.register_handler(_messages.ShareUrlRequest, refuse_message)
        # Belt and braces: viser's own entry point refuses too, whoever calls it.
        server.request_share_url = refuse_call  # type: ignore[method-assign]


def _websockets_server(server: viser.ViserServer) -> Server:
    """The ``websockets`` server object behind a running viser server.

    viser 1.1 keeps it only as a local of the coroutine that serves it (``serve_future`` in
    ``WebsockServer._background_worker.start_server``); read it from that suspended frame.
    """
    import websockets.asyncio.server

    loop = server._websock_server._background_event_loop
    if loop is None:
        raise ServeError("The scene server is not running; restart the studio.")

    async def find() -> Server | None:
        for task in asyncio.all_tasks(loop):
            frame = getattr(task.get_coro(), "cr_frame", None)
            found = frame.f_locals.get("serve_future") if frame is not None else None
            if isinstance(found, websockets.asyncio.server.Server):
                return found
        return None

    found = asyncio.run_coroutine_threadsafe(find(), loop).result(FIND_SERVER_TIMEOUT_S)
    if found is None:
        raise ServeError(
            "This viser version cannot be guarded (its websocket server was not found); "
            "install the viser version Teach Studio pins."
        )
    return found


def start_scene(
    settings: Settings, api_port: int | None = None
) -> tuple[viser.ViserServer, StudioScene, SceneGuard]:
    """Start the guarded viser server and the studio's scene in it.

    Args:
        settings: host, scene port (viser moves on to the next free port when it is taken:
            read the bound one from ``server.get_port()``), trusted hosts, token.
        api_port: the page's port, whose origin may read the instance id (default
            ``settings.port``).
    """
    import viser

    from .scene import StudioScene

    server = viser.ViserServer(host=settings.host, port=settings.viser_port, verbose=False)
    try:
        guard = SceneGuard(
            settings.trusted_hosts(),
            {server.get_port(), api_port if api_port is not None else settings.port},
            instance=secrets.token_hex(8),
            token=settings.token,
        )
        guard.install(server)
        server.gui.configure_theme(show_share_button=False)
        scene = StudioScene(server, mesh_cache=settings.mesh_cache_dir)
    except BaseException:
        server.stop()
        raise
    if server.get_port() != settings.viser_port:
        log.warning(
            "Scene port %d was taken; the scene listens on %d.",
            settings.viser_port,
            server.get_port(),
        )
    return server, scene, guard


def bind_port(host: str, port: int) -> socket.socket:
    """Bind the API's listening socket now, so that a taken port is one clear sentence.

    Raises:
        ServeError: the port is taken, privileged, or the address is not this machine's.
    """
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except socket.gaierror:
        raise ServeError(
            f"--host {host} is not an address of this machine; give an address such as 127.0.0.1."
        ) from None
    family, kind, proto, _, address = infos[0]
    sock = socket.socket(family, kind, proto)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind(address)
    except OSError as err:
        sock.close()
        if err.errno == errno.EADDRINUSE:
            raise ServeError(
                f"Port {port} is already in use (another studio or program); stop it or start this studio with --port and a free port."
            ) from None
        if err.errno == errno.EACCES:
            raise ServeError(
                f"Port {port} needs administrator rights; start the studio with --port 1024 or above."
            ) from None
        raise ServeError(
            f"Cannot listen on {host}:{port} ({err.strerror}); check --host and --port."
        ) from None
    sock.listen(socket.SOMAXCONN)
    return sock


def prepare_data_dir(data_dir: Path) -> None:
    """Create the data folder and its subfolders, or say in one sentence why that fails.

    Raises:
        ServeError: the folder cannot be created or written.
    """
    probe = Settings(data_dir=data_dir)
    try:
        # The data folder itself, not its parents: a mistyped path makes no tree of folders.
        for folder in (data_dir, probe.recordings_dir, probe.runs_dir, probe.policies_dir):
            folder.mkdir(exist_ok=True)
    except FileNotFoundError:
        raise ServeError(
            f"The data folder {data_dir} cannot be created: {data_dir.parent} does not exist; create it first, or give --data-dir a folder that exists."
        ) from None
    except OSError as err:
        reason = err.strerror or type(err).__name__
        raise ServeError(
            f"The data folder {data_dir} cannot be created ({reason}); give --data-dir a folder you can write to."
        ) from None


def _prepare_when_up(http: uvicorn.Server) -> None:
    """Once the API answers, compile the learner's kernels and the arms' IK in the background if
    they are not cached (a first run, or a first robot chosen, then loads them instead of
    compiling them); after, so that the compile never slows the start."""
    while not http.started and not http.should_exit:
        time.sleep(UP_POLL_S)
    if http.started:
        prepare_in_background()
        prepare_arm_ik_in_background()


def serve(settings: Settings, open_browser: bool = True) -> None:
    """Serve the studio until interrupted (Ctrl+C).

    Args:
        settings: where to listen and where the data lives.
        open_browser: open the page in the default browser once the server is up.

    Raises:
        ServeError: the API port is taken, the data folder cannot be written, or the host is
            not loopback and there is no token.
    """
    import uvicorn

    from ._app import create_app

    if not settings.is_loopback and not settings.token:
        raise ServeError(
            f"--host {settings.host} opens the studio to other machines, which needs a token; give --token (or set STUDIO_TOKEN), or keep --host 127.0.0.1 and use an SSH tunnel."
        )
    if not is_loopback(settings.bridge_host) and not settings.token:
        raise ServeError(
            f"--bridge-host {settings.bridge_host} opens the network bridge to other machines, which needs a token to sign the frames; give --token (or set STUDIO_TOKEN), or keep the bridge on 127.0.0.1."
        )
    prepare_data_dir(settings.data_dir)
    # A live pose hops across four Python threads (source, pipeline, scene, viser's loop) before
    # it reaches the browser; at each hop the next thread may wait for the GIL for a whole
    # switch interval (5 ms by default) while a request or the run list holds it. 1 ms keeps
    # the hops short (issue 10's motion-to-scene latency) at a negligible cost in throughput.
    sys.setswitchinterval(GIL_SWITCH_INTERVAL_S)
    # A robot's first load reads its meshes for seconds holding the GIL: in a child process,
    # so that a robot switch does not freeze the API and the scene meanwhile; and once per
    # machine, kept in the data folder's cache.
    isolate_robot_loading(settings.robot_cache_dir)
    sock = bind_port(settings.host, settings.port)
    try:
        server, scene, guard = start_scene(settings)
    except BaseException:
        sock.close()
        raise
    try:
        settings = settings.model_copy(
            update={"viser_port": server.get_port(), "scene_instance": guard.instance}
        )
        app = create_app(settings, scene)
        host = "127.0.0.1" if settings.host in ("0.0.0.0", "::") else settings.host
        url = f"http://{host}:{settings.port}/"
        if settings.token:
            url += f"?token={settings.token}"
        config = uvicorn.Config(
            app,
            log_level="warning",
            access_log=False,
            timeout_graceful_shutdown=SHUTDOWN_GRACE_S,
        )
        http = uvicorn.Server(config)
        print(
            f"Teach Studio: open {url}  (scene at {settings.scene_url()}, data in {settings.data_dir.resolve()})",
            flush=True,
        )
        if not is_loopback(settings.bridge_host):
            print(
                f"The network bridge listens on {settings.bridge_host} and takes only frames signed with the token: studio bridge --to HOST:PORT --token TOKEN",
                flush=True,
            )
        if open_browser:
            threading.Timer(1.0, lambda: webbrowser.open(url)).start()
        threading.Thread(target=_prepare_when_up, args=(http,), daemon=True).start()
        http.run(sockets=[sock])
    finally:
        sock.close()
        scene.close()
        server.stop()
