"""The FastAPI app: the API routers, the page and its vendored libraries, and the host guard.

:func:`create_app` builds the app for given :class:`Settings`; the studio state (stores, live
pipeline, run queue) is created when the app starts and closed when it stops, so tests get a
fresh studio per ``with TestClient(create_app(settings))`` block.
"""

from __future__ import annotations

import logging
import re
from collections.abc import AsyncIterator, Mapping, Sequence
from contextlib import asynccontextmanager
from pathlib import Path

from fastapi import Depends, FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse
from fastapi.staticfiles import StaticFiles
from fastapi_offline import FastAPIOffline
from starlette.exceptions import HTTPException
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from studio import StudioError, __version__, human_size
from studio.export import SafetyError

from ._deps import refuse_broken_text
from ._errors import (
    NotFoundError,
    StorageError,
    WebError,
    document_errors,
    findings_public,
    os_error_answer,
)
from ._guard import GuardMiddleware, SiteRule
from ._schemas import RUN_TASK_TAGS
from ._settings import Settings, get_settings
from ._state import Studio
from .routers import (
    capture,
    config,
    demonstrations,
    events,
    policies,
    recordings,
    robots,
    run_notes,
    runs,
    scene_controls,
    sources,
    sweeps,
    takes,
    watch,
)
from .scene import Scene

log = logging.getLogger(__name__)

STATIC_DIR = Path(__file__).parent / "static"
HTTP_METHODS = frozenset({"GET", "HEAD", "POST", "PUT", "PATCH", "DELETE", "OPTIONS"})
MULTIPART_OVERHEAD_BYTES = 64 * 1024
"""Room for the multipart framing around an upload at the size limit."""


def create_app(settings: Settings | None = None, scene: Scene | None = None) -> FastAPI:
    """The studio's web app.

    Args:
        settings: data directory, ports, limits (default: ``Settings()``).
        scene: the :class:`~studio.web.scene._scene.StudioScene` the studio drives, or None.
    """
    settings = settings if settings is not None else get_settings()

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        studio = Studio(settings, scene)
        app.state.studio = studio
        studio.start()
        try:
            yield
        finally:
            studio.close()

    # FastAPI's own /docs and /redoc load Swagger UI and ReDoc from a CDN, which leaves the API
    # page blank without internet; FastAPIOffline serves the same pages from its package.
    app = FastAPIOffline(
        title="Teach Studio",
        version=__version__,
        description="Teach a robot arm by showing it a motion: capture, demonstrations, "
        "Dyna-Q training with live curves, policies. The contract is docs/api.md.",
        lifespan=lifespan,
        dependencies=[Depends(refuse_broken_text)],
    )
    app.dependency_overrides[get_settings] = lambda: settings
    app.add_middleware(UploadLimitMiddleware, limit=settings.upload_limit_bytes)
    # Inside the Host check: the token (beyond loopback) and no change from another site's page.
    app.add_middleware(
        GuardMiddleware,
        rule=SiteRule(settings.trusted_hosts(), {settings.port}, settings.token, settings.port),
    )
    app.add_middleware(TrustedHostMiddleware, allowed_hosts=settings.trusted_hosts())

    answer_errors(app, settings)
    for module in (
        config,
        sources,
        robots,
        capture,
        recordings,
        takes,
        demonstrations,
        runs,
        run_notes,
        sweeps,
        policies,
        watch,
        scene_controls,
        events,
    ):
        app.include_router(module.router)

    @app.get("/", include_in_schema=False)
    def index() -> FileResponse:
        page = STATIC_DIR / "index.html"
        if not page.is_file():
            raise NotFoundError(
                f"The page is missing from {STATIC_DIR}; reinstall Teach Studio (the API still works at /docs)."
            )
        return FileResponse(page, headers={"Cache-Control": "no-cache"})

    app.mount("/static", StaticFiles(directory=STATIC_DIR, check_dir=False), name="static")

    def openapi() -> dict[str, object]:
        if app.openapi_schema is None:  # built once, with the studio's real error shape
            app.openapi_schema = document_errors(FastAPI.openapi(app))
        return app.openapi_schema

    app.openapi = openapi  # type: ignore[method-assign]
    return app


def answer_errors(app: FastAPI, settings: Settings) -> None:
    """Answer every refusal as ``{"detail": sentence}``: a :class:`studio.StudioError` with its
    status (422 for the algorithm packages'), a wrong method, a disk that refuses a write, a
    malformed request."""

    @app.exception_handler(StudioError)
    async def studio_error(request: Request, err: StudioError) -> JSONResponse:
        status = err.status_code if isinstance(err, WebError) else 422
        body: dict[str, object] = {"detail": str(err)}
        if isinstance(err, SafetyError):  # the refusal in words (no command-line flags)
            body["detail"] = err.in_words
            body["findings"] = findings_public(err.found)
        reason = getattr(err, "reason", None)
        if isinstance(reason, str):
            body["reason"] = reason  # e.g. a refused demonstration: "never_reaches_goal"
        problems = getattr(err, "problems", None)
        if isinstance(problems, list) and problems:  # every bad field of a form, by field
            body["problems"] = problems
            body["by_field"] = getattr(err, "by_field", {})
        return JSONResponse(body, status_code=status)

    @app.exception_handler(405)
    async def method_not_allowed(request: Request, err: Exception) -> JSONResponse:
        allow = ", ".join(allowed_methods(app, request.url.path))
        return JSONResponse(
            {"detail": f"{request.method} is not allowed here; use {allow}."},
            status_code=405,
            headers={"Allow": allow},
        )

    @app.exception_handler(OSError)
    async def os_error(request: Request, err: OSError) -> JSONResponse:
        status, sentence = os_error_answer(err, settings.data_dir.resolve())
        if status >= 500 and status != StorageError.status_code:
            log.error("%s %s failed", request.method, request.url.path, exc_info=err)
        return JSONResponse({"detail": sentence}, status_code=status)

    @app.exception_handler(RequestValidationError)
    async def validation_error(request: Request, err: RequestValidationError) -> JSONResponse:
        return JSONResponse({"detail": validation_sentence(err.errors())}, status_code=422)


def allowed_methods(app: FastAPI, path: str) -> list[str]:
    """Every method the API documents at ``path`` (for a 405's ``Allow``).

    Starlette names only the methods of the first route matching the path, but a resource is
    often served by several routes (``GET``, ``PATCH`` and ``DELETE /api/recordings/{name}``).
    """
    paths = app.openapi().get("paths", {})
    if path in paths:  # a fixed path (``/api/demonstrations/mark``) wins over a template
        return sorted(m.upper() for m in paths[path] if m.upper() in HTTP_METHODS)
    methods: set[str] = set()
    for template, item in paths.items():
        parts = re.split(r"\{[^}]+\}", template)
        if re.fullmatch("[^/]+".join(re.escape(part) for part in parts), path):
            methods |= {m.upper() for m in item if m.upper() in HTTP_METHODS}
    return sorted(methods)


def validation_sentence(errors: Sequence[Mapping[str, object]]) -> str:
    """One sentence for FastAPI's validation errors, naming the first bad field and the fix."""
    if not errors:
        return "The request is malformed; check its fields and try again."
    first = errors[0]
    where = first.get("loc", ())
    parts = where if isinstance(where, (list, tuple)) else ()
    loc = [str(p) for p in parts if p not in ("body", "query", "path", *RUN_TASK_TAGS)]
    field = ".".join(loc) or "the request body"
    message = str(first.get("msg", "is invalid")).rstrip(".")
    given = first.get("input")
    kind = first.get("type", "")
    if kind == "missing":
        return f"{field} is missing; add it to the request."
    if kind == "extra_forbidden":
        return f"{field} is not a known field; remove it or check its spelling."
    if kind in ("json_invalid", "model_attributes_type", "dict_type", "model_type"):
        return f"The request body is not a JSON object ({message}); send a JSON object."
    shown = repr(given) if given is not None and len(repr(given)) <= 60 else "the value given"
    return f"{field} is {shown}: {message[0].lower()}{message[1:]}; fix {field} and try again."


FRAME_BODY_LIMIT_BYTES = 64_000
"""Largest body of one landmark frame or hand pose (a frame is about 2 KB of JSON)."""
ROUTE_BODY_LIMITS = {
    "/api/source/landmarks": FRAME_BODY_LIMIT_BYTES,
    "/api/source/hand": FRAME_BODY_LIMIT_BYTES,
}
"""Routes whose bodies are far smaller than an upload: their own limit (413 above it)."""


class UploadLimitMiddleware:
    """Refuse request bodies larger than the upload limit (413), without storing them.

    A body announced larger (``Content-Length``) is refused before it is read; a body sent
    without one (chunked) is counted while it streams in and refused at the limit, so at most
    the limit (plus the multipart framing) is ever received.
    """

    def __init__(
        self, app: ASGIApp, limit: int, route_limits: dict[str, int] | None = None
    ) -> None:
        self.app = app
        self.limit = limit
        self.route_limits = dict(ROUTE_BODY_LIMITS if route_limits is None else route_limits)

    def _sentence(self, size: str, path: str = "") -> str:
        if path in self.route_limits:
            return f"The request body is {size}, over the limit of {human_size(self.route_limits[path])} for {path}; send one frame or pose per request."
        return f"The upload is {size}, over the limit of {human_size(self.limit)}; upload a smaller file or start the studio with a larger limit."

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        path = scope.get("path", "")
        allowed = self.route_limits.get(path, self.limit + MULTIPART_OVERHEAD_BYTES)
        for key, value in scope.get("headers", ()):
            if key == b"content-length":
                try:
                    size = int(value)
                except ValueError:
                    size = 0
                if size > allowed:
                    response = JSONResponse(
                        {"detail": self._sentence(human_size(size), path)}, status_code=413
                    )
                    await response(scope, receive, send)
                    return
        received = 0
        started = False

        async def counted_receive() -> Message:
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > allowed:
                    # An HTTPException passes FastAPI's body parsing unchanged, and whatever
                    # was read so far (Starlette's spooled parts, an upload's temporary file)
                    # is dropped on the way out.
                    raise BodyTooLarge(
                        413, self._sentence(f"more than {human_size(allowed)}", path)
                    )
            return message

        async def tracked_send(message: Message) -> None:
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, counted_receive, tracked_send)
        except BodyTooLarge as err:  # raised where no exception handler answered it
            if started:
                raise
            await JSONResponse({"detail": err.detail}, status_code=413)(scope, receive, send)


class BodyTooLarge(HTTPException):
    """A request body that grew past the upload limit while it streamed in."""
